"""Mitsuba 3's `blendbsdf` imported as spectrace's `mix` material and spectrace's mix exported as a blendbsdf:
Mitsuba evaluates (1 − weight) f₀ + weight f₁ exactly, spectrace picks one of the two per shading point with
probability weight (as pbrt-v4 does); both converge to the same image. Checked against Mitsuba 3 (scalar_spectral)
rendering the same XML, and the same exported scene, block by block within 5 standard errors."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba, assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict
from spectrace.scene.model import MixMaterial

DIFFUSE = '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.15, 0.1"/></bsdf>'
GOLD = (
    '<bsdf type="roughconductor"><string name="material" value="Au"/><string name="distribution" value="ggx"/>'
    '<float name="alpha" value="0.3"/></bsdf>'
)
WEIGHT = '<float name="weight" value="0.3"/>'


def _xml(folder: Path, weight: str = WEIGHT) -> Path:
    path = folder / "blend.xml"
    # A sphere filling most of the frame in a uniform sky, lit by a small area light: the conductor's highlight
    # and the diffuse's shading both show.
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="4"/></integrator>
<sensor type="perspective"><float name="fov" value="18"/>
  <transform name="to_world"><lookat origin="0, -4, 1" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
<shape type="rectangle">
  <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="60"/><translate x="0.3" y="1" z="2"/></transform>
  <emitter type="area"><spectrum name="radiance" value="6"/></emitter></shape>
<shape type="sphere"><float name="radius" value="1"/>
  <bsdf type="blendbsdf">{weight}{DIFFUSE}{GOLD}</bsdf></shape>
</scene>
"""
    )
    return path


def test_blendbsdf_imports_as_a_mix_of_its_two_bsdfs_in_order(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path))
    (mixed,) = [m for m in data["materials"].values() if m["type"] == "mix"]
    assert mixed["amount"] == 0.3
    assert [data["materials"][name]["type"] for name in mixed["materials"]] == ["diffuse", "conductor"]
    # Mitsuba's default weight is 0.5; a texture weight is a texture amount.
    data, _ = mitsuba_scene_data(_xml(tmp_path, ""))
    assert [m for m in data["materials"].values() if m["type"] == "mix"][0]["amount"] == 0.5
    checker = (
        '<texture type="checkerboard" name="weight"><float name="color0" value="0"/>'
        '<float name="color1" value="1"/></texture>'
    )
    data, _ = mitsuba_scene_data(_xml(tmp_path, checker))
    (mixed,) = [m for m in data["materials"].values() if m["type"] == "mix"]
    assert data["textures"][mixed["amount"]["texture"]]["type"] == "checkerboard"
    assert isinstance(load_mitsuba_scene(_xml(tmp_path, checker)).shapes[-1].material, MixMaterial)


@pytest.mark.peer
def test_blendbsdf_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, 16 independent images of 8 spp each; 8 x 8-pixel block means and the image mean
    agree within 5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 16, 8, 8
    path = _xml(tmp_path)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
    assert by_mitsuba.mean() > 0.05  # the comparison saw a lit image


@pytest.mark.peer
def test_a_mix_exports_as_blendbsdf_and_renders_like_spectrace(tmp_path, device, mitsuba_scalar_spectral):
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 16, 8, 8
    scene = load_mitsuba_scene(_xml(tmp_path))
    exported = scene_to_mitsuba_dict(scene, tmp_path / "export", spp=replica_spp)
    blends = [entry for entry in exported.values() if isinstance(entry, dict) and entry.get("type") == "blendbsdf"]
    assert len(blends) == 1 and blends[0]["weight"] == pytest.approx(0.3)
    mitsuba_scene = mi.load_dict(exported)
    by_mitsuba = np.stack(
        [mitsuba_film_xyz(mi.render(mitsuba_scene, spp=replica_spp, seed=seed), mi) for seed in range(replicas)]
    )
    by_spectrace = spectrace_replicas(Renderer(scene, device), replicas, replica_spp)
    assert_replicas_agree(by_spectrace, by_mitsuba, block)


def test_a_blend_on_a_rectangle_flips_its_materials_textures_as_its_own(tmp_path):
    """Mitsuba's rectangle has v up, spectrace's down: the textures of a blend's materials on a rectangle are
    imported with v flipped, as a plain bsdf's are, and the blend becomes a material of its own too."""
    checker = '<texture type="checkerboard" name="reflectance"/>'
    path = tmp_path / "rect.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
<integer name="height" value="8"/></film></sensor>
<shape type="rectangle"><bsdf type="blendbsdf">{WEIGHT}<bsdf type="diffuse">{checker}</bsdf>{GOLD}</bsdf></shape>
</scene>
"""
    )
    data, _ = mitsuba_scene_data(path)
    (mixed,) = [m for m in data["materials"].values() if m["type"] == "mix"]
    diffuse = data["materials"][mixed["materials"][0]]
    texture = data["textures"][diffuse["reflectance"]["texture"]]
    assert texture["uv_scale"][1] < 0  # v flipped
