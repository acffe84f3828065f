"""The path, direct and bidirectional integrators through delta lobes, against the enclosure law.

Inside a closed box whose walls all emit radiance Le, the radiance after d path segments follows from the walls'
directional albedo A: if A is the same for every direction, the field stays uniform and L_d = Le (1 + A + ... +
A^(d−1)). A mirror of reflectance R has A = R; a smooth plastic with a white base has A = F + (1 − F) = 1 at every
angle, so L_d = d·Le. The mirror exercises pure delta paths (no next-event estimation); the plastic mixes a delta
coat with a diffuse base (next-event estimation, MIS against the mixture pdf, lobe selection); under BDPT, subpaths
that go on from a vertex by the coat's delta lobe are still joined there, and the MIS weights must treat the joined
vertex by the join, not by that lobe."""

import numpy as np
import pytest

from replica_agreement import spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.geometry import primitives
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene.model import AreaEmitter, Camera, MirrorMaterial, PlasticMaterial, Scene, Shape
from spectrace.spectral.spectrum import Spectrum
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

EMITTED = 0.5


def _box(material, integrator: str, max_depth: int, spp: int = 4) -> Scene:
    box = apply_transform(primitives.cube(), transform_matrix([{"scale": [1.0, 0.7, 1.3]}], where="test"))
    shape = Shape(mesh=box, material=material, emitter=AreaEmitter(Spectrum.constant(EMITTED), two_sided=True))
    camera = Camera(origin=(0.1, -0.2, 0.3), target=(0.5, 0.1, -1.0), fov_degrees=100.0)
    return Scene(
        camera=camera,
        width=24,
        height=24,
        shapes=[shape],
        integrator=integrator,
        max_depth=max_depth,
        rr_depth=16,
        spp=spp,
        seed=7,
    )


def _measured_y(scene: Scene, device) -> tuple[float, float]:
    y = Renderer(scene, device).render().xyz[..., 1].ravel().astype(np.float64)
    return y.mean(), y.std(ddof=1) / np.sqrt(y.size)


@pytest.mark.parametrize("integrator", ["path", "direct"])
@pytest.mark.parametrize("max_depth", [1, 2, 4])
def test_mirror_enclosure(device, integrator, max_depth):
    reflectance = 0.6
    expected = EMITTED * (1 - reflectance**max_depth) / (1 - reflectance)
    mean, standard_error = _measured_y(
        _box(MirrorMaterial(Spectrum.constant(reflectance)), integrator, max_depth), device
    )
    # Delta paths from a constant spectrum carry no noise: only float rounding remains.
    assert abs(mean - expected) <= 1e-4 * expected + 4 * standard_error, (mean, expected, standard_error)


@pytest.mark.parametrize("integrator, max_depth", [("path", 2), ("path", 3), ("direct", 2)])
def test_white_smooth_plastic_enclosure(device, integrator, max_depth):
    material = PlasticMaterial(Spectrum.constant(1.0), ior=1.5)
    # The direct integrator's next-event estimation has no MIS, so light from wall points near a corner (1/r²)
    # makes it far noisier than the path tracer: it gets more samples.
    spp = 256 if integrator == "direct" else 64
    mean, standard_error = _measured_y(_box(material, integrator, max_depth, spp=spp), device)
    expected = EMITTED * max_depth
    assert_within_standard_errors(mean, expected, standard_error, power=0.05)


@pytest.mark.parametrize("max_depth", [3, 4])
def test_white_smooth_plastic_enclosure_bdpt(device, max_depth):
    """Paths of three segments and more, where both subpaths go on past the vertices they are joined at. A light
    path splats into any pixel, so the standard error comes from independent replicas, not from the pixels."""
    material = PlasticMaterial(Spectrum.constant(1.0), ior=1.5)
    images = spectrace_replicas(Renderer(_box(material, "bdpt", max_depth), device), replicas=16, replica_spp=8)
    mean, standard_error = mean_and_standard_error(images[..., 1].mean(axis=(1, 2)))
    expected = EMITTED * max_depth
    assert_within_standard_errors(mean, expected, standard_error, what=f"max_depth {max_depth}", power=0.01)
