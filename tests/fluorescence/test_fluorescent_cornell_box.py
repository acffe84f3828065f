"""The path tracer and the light tracer agree on a fluorescent Cornell box: the bundled box with its white surfaces
(floor, ceiling, back wall and both blocks) dyed with a blue-absorbing, green-emitting dye over their own white,
compared block by block from independent replicas (tests/replica_agreement.py). Reciprocity does not hold for the
dye, so the two walk light in opposite directions through a real change of wavelength: the camera path switches
from the emitted to an absorbed wavelength, the light path from the absorbed to an emitted one."""

import dataclasses

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.resources import resolve_scene_path
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum

SIZE = 32
EXCITATION = np.where((GRID_NM >= 400) & (GRID_NM <= 500), 0.7, 0.0)
EMISSION = np.exp(-0.5 * ((GRID_NM - 540.0) / 20.0) ** 2)


def _dyed_box():
    scene = spectrace.load_scene(resolve_scene_path("cornell_box")).with_overrides(width=SIZE, height=SIZE, seed=5)
    shapes = []
    for shape in scene.shapes:
        if shape.name == "white surfaces":
            dye = spectrace.fluorescent(shape.material, Spectrum(EXCITATION), Spectrum(EMISSION), quantum_yield=0.9)
            shape = dataclasses.replace(shape, material=dye)
        shapes.append(shape)
    assert any(isinstance(s.material, spectrace.materials.fluorescent.FluorescentMaterial) for s in shapes)
    return scene.with_overrides(shapes=shapes)


@pytest.mark.slow
def test_path_and_light_tracers_agree_on_a_fluorescent_cornell_box(device):
    scene = _dyed_box()
    path = spectrace_replicas(Renderer(scene, device), 8, 16)
    light = spectrace_replicas(Renderer(scene.with_overrides(integrator="light"), device), 8, 16)
    assert_replicas_agree(light, path, block=8, what="a fluorescent Cornell box")
    # The dye shows: the white surfaces turn greener than without it (Y over Z up by more than noise).
    plain = spectrace_replicas(Renderer(scene.with_overrides(shapes=_undyed(scene)), device), 8, 16)
    assert path[..., 1].mean() / path[..., 2].mean() > 1.05 * plain[..., 1].mean() / plain[..., 2].mean()


def _undyed(scene):
    return [
        dataclasses.replace(s, material=s.material.base)
        if isinstance(s.material, spectrace.materials.fluorescent.FluorescentMaterial)
        else s
        for s in scene.shapes
    ]
