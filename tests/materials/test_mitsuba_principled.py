"""Mitsuba 3's `principled` BSDF and spectrace's import of the same XML render alike: a sphere of the material on a
grey floor, filling most of the view, under a small area light and a dim uniform sky, rendered by Mitsuba's
scalar_spectral variant and by spectrace, independent replicas of each compared block by block and over the whole
image within 5 standard errors (replica_agreement), over a sweep of the parameters (metallic 0/1, roughness
0.2/0.6, spec_trans 0/1, sheen, clearcoat). The base colour is a spectrum, not RGB, so both renderers reflect the
same one.

The two models differ where docs/materials.md says: Mitsuba's separable masking G1 G1 against spectrace's
height-correlated G2 on the main lobes (spectrace's rough lobes slightly brighter). The clearcoat is Mitsuba's,
without the microfacet lobe's 1/(4 cos θo cos θi) Burley's reference code has: with that factor the clearcoat
cases failed (gloss 0.9: blocks 5.9 σ, the image 0.67 % darker; gloss 0 on the metal: blocks 6.7 σ; gloss 0.5:
4.7 σ, which is why the sweep takes 0.9).

Measured (12 replicas of 64 spp each, Intel's CPU runtime), largest block difference and whole image:
dielectric r 0.6: 2.0 σ, +0.15 %; metal r 0.2: 2.3 σ, +0.43 %; metal r 0.6: 2.5 σ, +0.46 %; glass r 0.2: 2.9 σ,
+0.33 %; glass r 0.6: 3.5 σ, +0.56 % (4.4 σ); sheen: 1.9 σ, +0.15 %; clearcoat gloss 0.9: 1.7 σ, +0.15 %;
clearcoat gloss 0 on the metal: 2.3 σ, +0.39 %. The scene tells wrong models apart: spectrace
rendering metal r 0.2 as r 0.25 fails at 10.4 σ, glass η 1.5 as 1.4 at 13.8 σ, the sheen left out at 5.7 σ, the
clearcoat left out at 8.5 σ, the dielectric r 0.6 as r 0.3 at 8.6 σ.
"""

import numpy as np
import pytest

from materials.test_mitsuba_materials import _scene
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict

pytestmark = pytest.mark.peer

BLOCK = 6
BASE = '<spectrum name="base_color" value="400:0.15, 480:0.7, 560:0.45, 640:0.25, 700:0.6"/>'


def _principled_scene(parameters: dict[str, float], plugin: str = "principled") -> str:
    """The sphere of `plugin` (principled, in `twosided` unless it transmits, or principledthin, the same from both
    faces by itself) and its surroundings."""
    floats = "".join(f'<float name="{k}" value="{v}"/>' for k, v in parameters.items())
    bsdf = f'<bsdf type="{plugin}">{BASE}{floats}</bsdf>'
    if plugin == "principled" and not parameters.get("spec_trans"):
        bsdf = f'<bsdf type="twosided">{bsdf}</bsdf>'
    body = f"""
    <shape type="sphere"><float name="radius" value="1"/>{bsdf}</shape>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/><translate value="0, 0, -1"/></transform>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.8"/><rotate x="1" angle="180"/><translate value="1.2, -1.6, 2"/>
        </transform>
        <bsdf type="diffuse"><spectrum name="reflectance" value="0"/></bsdf>
        <emitter type="area"><spectrum name="radiance" value="5"/></emitter>
    </shape>
    <emitter type="constant"><spectrum name="radiance" value="0.3"/></emitter>"""
    return _scene(body, origin="0, -3.4, 0.8", max_depth=8)


SWEEP = [
    ("dielectric-r0.6", {"roughness": 0.6}),
    ("metal-r0.2", {"metallic": 1.0, "roughness": 0.2}),
    ("metal-r0.6", {"metallic": 1.0, "roughness": 0.6}),
    ("glass-r0.2", {"spec_trans": 1.0, "roughness": 0.2, "eta": 1.5}),
    ("glass-r0.6", {"spec_trans": 1.0, "roughness": 0.6, "eta": 1.5}),
    ("sheen-r0.6", {"roughness": 0.6, "sheen": 1.0, "sheen_tint": 0.0}),
    ("clearcoat-g0.9", {"roughness": 0.6, "clearcoat": 1.0, "clearcoat_gloss": 0.9}),
    ("clearcoat-g0-metal", {"metallic": 1.0, "roughness": 0.6, "clearcoat": 1.0, "clearcoat_gloss": 0.0}),
]


def _replicas(tmp_path, device, mi, parameters, plugin="principled", replicas=12, spp=64):
    xml = tmp_path / "scene.xml"
    xml.write_text(_principled_scene(parameters, plugin))
    scene = load_mitsuba_scene(xml)
    mitsuba_scene = mi.load_file(str(xml))
    theirs = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=spp, seed=seed), mi) for seed in range(replicas)])
    ours = spectrace_replicas(Renderer(scene, device), replicas, spp)
    assert theirs[..., 1].mean() > 0.02  # a lit image
    return ours, theirs


@pytest.mark.slow
@pytest.mark.parametrize("name, parameters", SWEEP, ids=[c[0] for c in SWEEP])
def test_principled_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, name, parameters):
    ours, theirs = _replicas(tmp_path, device, mitsuba_scalar_spectral, parameters)
    assert_replicas_agree(ours, theirs, BLOCK, what=name)


# Mitsuba's principledthin: a sphere of the sheet shows its reflection, its specular transmission and diffuse
# transmission through both walls. Measured as above: diffuse r 0.5 with diff_trans 1: 2.2 σ, -0.00 %; specular
# r 0.3: 2.7 σ, +0.01 %; specular r 0.8: 2.1 σ, +0.33 %; every lobe at η 1.33: 2.7 σ, -0.00 %. The transmission's
# test of the light's side matters: left out, specular r 0.8 fails at 14.8 σ (+3.9 %).
THIN_SWEEP = [
    ("thin-diffuse-r0.5", {"roughness": 0.5, "diff_trans": 1.0}),
    ("thin-specular-r0.3", {"spec_trans": 1.0, "roughness": 0.3, "eta": 1.5}),
    ("thin-specular-r0.8", {"spec_trans": 1.0, "roughness": 0.8}),
    ("thin-mixed-r0.6", {"spec_trans": 0.5, "roughness": 0.6, "diff_trans": 0.6, "sheen": 0.5, "eta": 1.33}),
]


@pytest.mark.slow
@pytest.mark.parametrize("name, parameters", THIN_SWEEP, ids=[c[0] for c in THIN_SWEEP])
def test_principledthin_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, name, parameters):
    ours, theirs = _replicas(tmp_path, device, mitsuba_scalar_spectral, parameters, plugin="principledthin")
    assert_replicas_agree(ours, theirs, BLOCK, what=name)


@pytest.mark.slow
@pytest.mark.parametrize("name, parameters", [SWEEP[2], SWEEP[4]], ids=[SWEEP[2][0], SWEEP[4][0]])
def test_exported_principled_is_mitsubas(tmp_path, device, mitsuba_scalar_spectral, name, parameters):
    """The scene imported and exported back (scene_to_mitsuba_dict: the material as Mitsuba's principled, in
    `twosided` unless it transmits) renders in Mitsuba as the original XML does, block by block within 5 σ."""
    mi = mitsuba_scalar_spectral
    xml = tmp_path / "scene.xml"
    xml.write_text(_principled_scene(parameters))
    exported = scene_to_mitsuba_dict(load_mitsuba_scene(xml), tmp_path / "export", spp=16)

    def principled(entry):
        if isinstance(entry, dict) and entry.get("type") == "twosided":
            entry = entry["bsdf"]
        return entry if isinstance(entry, dict) and entry.get("type") == "principled" else None

    found = [b for b in map(principled, exported.values()) if b is not None]
    assert len(found) == 1 and all(found[0][k] == pytest.approx(v, rel=1e-6) for k, v in parameters.items())
    original, back = mi.load_file(str(xml)), mi.load_dict(exported)
    replicas = 12
    theirs = np.stack([mitsuba_film_xyz(mi.render(original, spp=64, seed=seed), mi) for seed in range(replicas)])
    ours = np.stack([mitsuba_film_xyz(mi.render(back, spp=64, seed=100 + seed), mi) for seed in range(replicas)])
    assert_replicas_agree(ours, theirs, BLOCK, what=name)
