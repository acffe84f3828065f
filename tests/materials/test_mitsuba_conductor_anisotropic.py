"""An anisotropic rough conductor (Mitsuba's `roughconductor` with alpha_u ≠ alpha_v) renders as Mitsuba 3 renders
it: its lobe is stretched along dp/du (alpha_u) and the bitangent (alpha_v) of the surface, both renderers framing
the BSDF along dp/du made orthogonal to the shading normal (kernels/material.cl, material_frame). The scenes are
test_mitsuba_principled_anisotropic's: a metal sphere (dp/du along its azimuth) over a grey floor under a small
area light and a dim sky, the sphere turned so that its poles face sideways, and a floor of the metal whose
rectangle is turned about its normal (dp/du from its texture coordinates); GGX and Beckmann (Mitsuba's default);
alpha_u given by a grey image of two values in squares (a bitmap: Mitsuba 3.9's checkerboard gives a number where
its colour lookup gives the other square's).
Replicas of both renderers are compared block by block and over the whole image within 5 standard errors
(replica_agreement).

Measured (12 replicas of 64 spp each, Intel's CPU runtime), largest block difference, whole image, image Y:
sphere 3.3 σ, 0.4 σ, +0.07 %; turned sphere 2.8 σ, 1.5 σ, +0.30 %; Beckmann sphere 3.2 σ, 2.0 σ, +0.55 %; turned
floor 2.5 σ, 1.6 σ, +0.26 %; textured alpha_u 2.4 σ, 1.6 σ, +0.40 % (with alpha_u either of its two values
instead: 58.4 σ and 64.7 σ); BDPT on the turned sphere 2.8 σ, 1.0 σ, +0.21 %. With the isotropic α = √(αu αv)
that the import used before, the sphere fails at 49.7 σ, the turned sphere at 53.3 σ (BDPT 52.7 σ).
"""

import dataclasses

import numpy as np
import pytest
from PIL import Image

from materials.test_mitsuba_materials import _scene
from materials.test_mitsuba_principled import BLOCK
from materials.test_mitsuba_principled_anisotropic import GREY, _body
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz

pytestmark = pytest.mark.peer


def _metal(alpha_u: str, alpha_v: str, distribution: str | None = "ggx") -> str:
    chosen = "" if distribution is None else f'<string name="distribution" value="{distribution}"/>'
    return (
        f'<bsdf type="twosided"><bsdf type="roughconductor"><string name="material" value="Al"/>{chosen}'
        f"{alpha_u}{alpha_v}</bsdf></bsdf>"
    )


def _alpha(name: str, value: float) -> str:
    return f'<float name="{name}" value="{value}"/>'


STRETCHED = _metal(_alpha("alpha_u", 0.05), _alpha("alpha_v", 0.4))
BECKMANN = _metal(_alpha("alpha_u", 0.35), _alpha("alpha_v", 0.06), None)
# alpha_u in a grey image of 0.04 and 0.3 in 4 x 4 squares, raw, nearest texels (the test writes it).
TEXTURED = _metal(
    '<texture type="bitmap" name="alpha_u"><string name="filename" value="alpha_u.png"/>'
    '<boolean name="raw" value="true"/><string name="filter_type" value="nearest"/></texture>',
    _alpha("alpha_v", 0.5),
)
TURNED = '<rotate x="1" angle="90"/><rotate z="1" angle="30"/>'
CASES = [
    ("sphere-ggx", _body("", STRETCHED, "", GREY)),
    ("turned-sphere-ggx", _body(TURNED, STRETCHED, "", GREY)),
    ("sphere-beckmann", _body("", BECKMANN, "", GREY)),
    ("turned-floor-ggx", _body("", GREY, '<rotate z="1" angle="60"/>', STRETCHED)),
    ("sphere-textured-alpha-u", _body("", TEXTURED, "", GREY)),
]
# BDPT's light subpaths sample and evaluate the adjoint BSDF in the same frame.
RUNS = [(name, body, "path") for name, body in CASES] + [(CASES[1][0], CASES[1][1], "bdpt")]


@pytest.mark.slow
@pytest.mark.parametrize("name, body, integrator", RUNS, ids=[f"{r[0]}-{r[2]}" for r in RUNS])
def test_anisotropic_rough_conductor_as_mitsuba(tmp_path, device, mitsuba_scalar_spectral, name, body, integrator):
    mi = mitsuba_scalar_spectral
    squares = (np.indices((16, 16)) // 4).sum(axis=0) % 2
    Image.fromarray(np.where(squares == 0, 10, 77).astype(np.uint8)).save(tmp_path / "alpha_u.png")  # 0.04, 0.3
    xml = tmp_path / "scene.xml"
    xml.write_text(_scene(body, origin="0, -3.4, 0.8", max_depth=8))
    mitsuba_scene = mi.load_file(str(xml))
    replicas, spp = 12, 64
    theirs = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=spp, seed=seed), mi) for seed in range(replicas)])
    scene = dataclasses.replace(load_mitsuba_scene(xml), integrator=integrator)
    ours = spectrace_replicas(Renderer(scene, device), replicas, spp)
    assert theirs[..., 1].mean() > 0.02  # a lit image
    assert_replicas_agree(ours, theirs, BLOCK, what=f"{name} under {integrator}")
