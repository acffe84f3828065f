"""pbrt-v4's and Mitsuba 3's `hair` imported as spectrace's hair (docs/materials.md#hair): the parameters under
their names and defaults, bad values refused in one line naming the file, and a white fibre sheet from a pbrt file
in a furnace returns the sky's radiance (∫ S dω = 1 whatever ωo and h: the closed form of a white fibre lit
evenly from everywhere, through the import, the v coordinate as h and dp/du as the fibre)."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import mitsuba_scene_data
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from stats_toolkit import assert_within_standard_errors

PBRT_HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" {spp}
Integrator "path" "integer maxdepth" 8
WorldBegin
"""
# A sheet whose u runs along x (the fibre) and v across it (h = 2v − 1), filling the view.
PBRT_SHEET = """{material}
Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "integer indices" [0 1 2  0 2 3]
    "point2 uv" [0 0  1 0  1 1  0 1]
"""


def _pbrt_material(tmp_path: Path, material: str) -> dict:
    path = tmp_path / "scene.pbrt"
    path.write_text(PBRT_HEADER.format(spp=1) + PBRT_SHEET.format(material=material))
    data, _ = pbrt_scene_data(path)
    (table,) = data["materials"].values()
    return table


def test_pbrt_hair_parameters_and_defaults(tmp_path):
    assert _pbrt_material(tmp_path, 'Material "hair"') == {
        "type": "hair",
        "eumelanin": 1.3,
        "eta": 1.55,
        "beta_m": 0.3,
        "beta_n": 0.3,
        "alpha": 2.0,
    }
    table = _pbrt_material(
        tmp_path,
        'Material "hair" "float eumelanin" 8 "float pheomelanin" 0.5 "float eta" 1.6 "float beta_m" 0.25 '
        '"float beta_n" 0.4 "float alpha" -3',
    )
    assert table == {
        "type": "hair",
        "eumelanin": 8.0,
        "pheomelanin": 0.5,
        "eta": 1.6,
        "beta_m": 0.25,
        "beta_n": 0.4,
        "alpha": -3.0,
    }
    assert _pbrt_material(tmp_path, 'Material "hair" "rgb sigma_a" [0.2 0.5 1.5]')["sigma_a"] == {
        "rgb": [0.2, 0.5, 1.5]
    }
    assert _pbrt_material(tmp_path, 'Material "hair" "rgb reflectance" [0.4 0.3 0.2]')["reflectance"] == {
        "rgb": [0.4, 0.3, 0.2]
    }


def test_pbrt_hair_out_of_range_is_one_line_naming_the_file(tmp_path):
    with pytest.raises(SpectraceError) as caught:
        _pbrt_material(tmp_path, 'Material "hair" "float beta_m" 0')
    message = str(caught.value)
    assert "scene.pbrt:7" in message and "beta_m" in message and "\n" not in message


@pytest.mark.slow
def test_a_white_hair_sheet_in_a_furnace_shows_the_sky(tmp_path, device):
    """σa = 0: every fibre scatters all it receives, so a sheet of them under a sky of radiance L shows L (paths
    that return to the sheet included: max depth 8, each bounce losing nothing)."""
    path = tmp_path / "scene.pbrt"
    world = 'LightSource "infinite" "rgb L" [1 1 1]\n' + PBRT_SHEET.format(
        material='Material "hair" "rgb sigma_a" [0 0 0] "float beta_m" 0.2 "float beta_n" 0.5'
    )
    path.write_text(PBRT_HEADER.format(spp=64) + world)
    xyz = Renderer(load_pbrt_scene(path), device).render().xyz.reshape(-1, 3).astype(np.float64)
    bare_path = tmp_path / "bare.pbrt"
    bare_path.write_text(PBRT_HEADER.format(spp=4) + 'LightSource "infinite" "rgb L" [1 1 1]\n')
    bare = Renderer(load_pbrt_scene(bare_path), device).render().xyz.reshape(-1, 3).astype(np.float64).mean(axis=0)
    assert bare[1] > 0.1
    mean = xyz.mean(axis=0)
    se = xyz.std(axis=0, ddof=1) / np.sqrt(len(xyz))
    assert_within_standard_errors(mean[1], bare[1], se[1], 4.0, slack=1e-3 * bare[1], what="Y")


MITSUBA_SCENE = """<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>
<bsdf type="hair" id="fibre">{properties}</bsdf>
<shape type="sphere"><ref id="fibre"/></shape>
</scene>
"""


def _mitsuba_material(tmp_path: Path, properties: str) -> dict:
    path = tmp_path / "scene.xml"
    path.write_text(MITSUBA_SCENE.format(properties=properties))
    data, _ = mitsuba_scene_data(path)
    (table,) = data["materials"].values()
    return table


def test_mitsuba_hair_parameters_and_defaults(tmp_path):
    """Mitsuba's defaults: eumelanin 1.3 and pheomelanin 0.2, amber (1.55) in air (1.000277)."""
    table = _mitsuba_material(tmp_path, "")
    assert table["type"] == "hair" and table["eumelanin"] == 1.3 and table["pheomelanin"] == 0.2
    assert table["eta"] == pytest.approx(1.55 / 1.000277)
    table = _mitsuba_material(
        tmp_path,
        '<rgb name="sigma_a" value="0.2, 0.25, 0.7"/><float name="scale" value="2"/>'
        '<float name="int_ior" value="1.6"/><float name="ext_ior" value="1.0"/>'
        '<float name="longitudinal_roughness" value="0.2"/><float name="azimuthal_roughness" value="0.6"/>'
        '<float name="scale_tilt" value="-1.5"/>',
    )
    assert table == {
        "type": "hair",
        "eta": 1.6,
        "sigma_a": {"rgb": pytest.approx([0.4, 0.5, 1.4])},
        "beta_m": 0.2,
        "beta_n": 0.6,
        "alpha": -1.5,
    }


def test_mitsuba_hair_with_both_absorptions_is_refused(tmp_path):
    with pytest.raises(SpectraceError) as caught:
        _mitsuba_material(tmp_path, '<rgb name="sigma_a" value="0.2, 0.25, 0.7"/><float name="eumelanin" value="1"/>')
    assert "scene.xml" in str(caught.value) and "sigma_a" in str(caught.value) and "\n" not in str(caught.value)
