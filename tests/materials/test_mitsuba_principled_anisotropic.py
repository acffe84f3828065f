"""The direction of an anisotropic principled highlight: Mitsuba 3 frames its BSDFs along dp/du made orthogonal to
the shading normal, so `anisotropic` stretches the highlight along the texture coordinates' u. spectrace's
material_frame (kernels/material.cl) does the same for materials whose row asks for it. The scene is
test_mitsuba_principled's: a sphere (dp/du along its azimuth) of anisotropic metal over a grey floor under a small
area light and a dim sky; then the same sphere turned so that its poles face sideways (the tangent field turns
with it, a frame built from the normal alone would not), and a floor of the material whose rectangle is turned
about its normal (triangles with texture coordinates: dp/du from the corners). Replicas of both renderers are
compared block by block and over the whole image within 5 standard errors (replica_agreement).

Measured (12 replicas of 64 spp each, Intel's CPU runtime), largest block difference, whole image, image Y:
sphere 3.1 σ, 2.1 σ, +0.26 %; turned sphere 2.3 σ, 1.9 σ, +0.18 %; turned floor 3.7 σ, 1.2 σ, +0.15 %. With the
frame taken from the normal alone (the rows' tangent_frame flag cleared) the blocks fail at 23.1 σ, 60.8 σ and
8.6 σ. BDPT on the turned sphere: 2.6 σ, 0.3 σ, -0.12 % (40.6 σ without the frame).
"""

import dataclasses

import numpy as np
import pytest

from materials.test_mitsuba_materials import _scene
from materials.test_mitsuba_principled import BASE, BLOCK
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz

pytestmark = pytest.mark.peer

ANISOTROPIC_METAL = (
    f'<bsdf type="twosided"><bsdf type="principled">{BASE}<float name="metallic" value="1"/>'
    '<float name="roughness" value="0.4"/><float name="anisotropic" value="0.9"/></bsdf></bsdf>'
)
GREY = '<bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf>'
LIGHT = """
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.8"/><rotate x="1" angle="180"/><translate value="1.2, -1.6, 2"/>
        </transform>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0"/></bsdf>
        <emitter type="area"><spectrum name="radiance" value="5"/></emitter>
    </shape>
    <emitter type="constant"><spectrum name="radiance" value="0.3"/></emitter>"""


def _body(sphere_turn: str, sphere_bsdf: str, floor_turn: str, floor_bsdf: str) -> str:
    return f"""
    <shape type="sphere"><transform name="to_world">{sphere_turn}</transform>{sphere_bsdf}</shape>
    <shape type="rectangle">
        <transform name="to_world">{floor_turn}<scale value="4"/><translate value="0, 0, -1"/></transform>
        {floor_bsdf}</shape>{LIGHT}"""


CASES = [
    ("sphere", _body("", ANISOTROPIC_METAL, "", GREY)),
    ("turned-sphere", _body('<rotate x="1" angle="90"/><rotate z="1" angle="30"/>', ANISOTROPIC_METAL, "", GREY)),
    ("turned-floor", _body("", GREY, '<rotate z="1" angle="60"/>', ANISOTROPIC_METAL)),
]
# BDPT's light subpaths sample and evaluate the adjoint BSDF in the same frame (its own vertices carry dp/du).
RUNS = [(name, body, "path") for name, body in CASES] + [(CASES[1][0], CASES[1][1], "bdpt")]


@pytest.mark.slow
@pytest.mark.parametrize("name, body, integrator", RUNS, ids=[f"{r[0]}-{r[2]}" for r in RUNS])
def test_anisotropic_principled_follows_dpdu_as_mitsuba(
    tmp_path, device, mitsuba_scalar_spectral, name, body, integrator
):
    mi = mitsuba_scalar_spectral
    xml = tmp_path / "scene.xml"
    xml.write_text(_scene(body, origin="0, -3.4, 0.8", max_depth=8))
    mitsuba_scene = mi.load_file(str(xml))
    replicas, spp = 12, 64
    theirs = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=spp, seed=seed), mi) for seed in range(replicas)])
    scene = dataclasses.replace(load_mitsuba_scene(xml), integrator=integrator)
    ours = spectrace_replicas(Renderer(scene, device), replicas, spp)
    assert theirs[..., 1].mean() > 0.02  # a lit image
    assert_replicas_agree(ours, theirs, BLOCK, what=f"{name} under {integrator}")
