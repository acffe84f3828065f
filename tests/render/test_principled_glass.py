"""A principled glass (spec_trans 1, metallic 0, white base) is the rough dielectric of α = roughness², through whole
paths: a dispersive SF11 sphere on a grey floor under a small light and a dim sky renders as the `dielectric` of the
same index does, with the path tracer and with BDPT, independent replicas of each compared block by block within
5 standard errors (replica_agreement). The path keeps only its hero wavelength at either surface (the flags'
BSDF_DISPERSIVE), so colour noise and all, the two images agree; one of η 1.5 does not (the check can fail)."""

import pytest

import spectrace as S
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.scene.model import Scene

pytestmark = pytest.mark.slow

SIDE, BLOCK = 24, 6


def _scene(material, integrator: str) -> Scene:
    light = S.shape(
        "sphere",
        S.diffuse(0.0),
        emitter=S.area_emitter(30.0),
        transform=[{"scale": 0.3}, {"translate": [1.0, 2.0, 1.5]}],
    )
    floor = S.shape(
        "rectangle",
        S.diffuse(0.5),
        transform=[
            {"scale": 4.0},
            {"rotate": {"axis": [1.0, 0.0, 0.0], "angle": -90.0}},
            {"translate": [0.0, -1.0, 0.0]},
        ],
    )
    return Scene(
        camera=S.Camera(origin=(0.0, 0.6, -3.4), target=(0.0, -0.2, 0.0), fov_degrees=40.0),
        width=SIDE,
        height=SIDE,
        shapes=[S.shape("sphere", material), floor, light],
        lights=[S.constant_environment(0.3)],
        max_depth=8,
        integrator=integrator,
        seed=5,
    )


def _replicas(device, material, integrator):
    return spectrace_replicas(Renderer(_scene(material, integrator), device), 10, 32)


@pytest.mark.parametrize("integrator", ["path", "bdpt"])
def test_principled_glass_renders_as_the_dielectric(device, integrator):
    ours = _replicas(device, S.principled(1.0, roughness=0.5, spec_trans=1.0, eta="SF11"), integrator)
    theirs = _replicas(device, S.dielectric("SF11", roughness=0.25), integrator)
    assert_replicas_agree(ours, theirs, BLOCK, what=integrator)


def test_a_different_index_is_told_apart(device):
    ours = _replicas(device, S.principled(1.0, roughness=0.5, spec_trans=1.0, eta=1.5), "path")
    theirs = _replicas(device, S.dielectric("SF11", roughness=0.25), "path")
    with pytest.raises(AssertionError):
        assert_replicas_agree(ours, theirs, BLOCK)
