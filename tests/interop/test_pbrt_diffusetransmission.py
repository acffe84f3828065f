"""pbrt-v4's `diffusetransmission` material (Lambertian reflection R/π on the lit side, Lambertian transmission
T/π through to the other) against its analytic values:

- under a distant light of irradiance E, a sheet seen from the lit side shows R·E/π and from the other side T·E/π,
  so against a `diffuse` plate of reflectance ρ in the same light (ρ·E/π) the ratios are R/ρ and T/ρ exactly (one
  deterministic next-event estimate per pixel: nothing to average);
- in a furnace (a constant sky of radiance L all round, direct light only) the sheet shows (R + T)·L: both lobes
  sampled and weighted against the sky's own sampling, within the estimator's standard error."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" {spp}
Integrator "path" "integer maxdepth" 1
WorldBegin
"""
SHEET = """{material}
Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "integer indices" [0 1 2  0 2 3]
"""
SHEET_MATERIAL = 'Material "diffusetransmission" "rgb reflectance" [0.2 0.2 0.2] "rgb transmittance" [0.6 0.6 0.6]'


def _mean_xyz(tmp_path: Path, world: str, device, spp: int = 4) -> tuple[np.ndarray, np.ndarray]:
    path = tmp_path / "sheet.pbrt"
    path.write_text(HEADER.format(spp=spp) + world)
    xyz = Renderer(load_pbrt_scene(path), device).render().xyz.reshape(-1, 3).astype(np.float64)
    return xyz.mean(axis=0), xyz.std(axis=0, ddof=1) / np.sqrt(len(xyz))


@pytest.mark.parametrize(("light_z", "expected_ratio"), [(1, 0.2 / 0.5), (-1, 0.6 / 0.5)])
def test_a_sheet_reflects_R_over_pi_on_the_lit_side_and_transmits_T_over_pi_through(
    tmp_path, device, light_z, expected_ratio
):
    """Light from the camera's side (+z): the camera sees the reflection; from behind (−z): the transmission."""
    light = f'LightSource "distant" "rgb L" [1 1 1] "point3 from" [0 0 {light_z}] "point3 to" [0 0 0]\n'
    sheet, _ = _mean_xyz(tmp_path, light + SHEET.format(material=SHEET_MATERIAL), device)
    plate, _ = _mean_xyz(
        tmp_path,
        'LightSource "distant" "rgb L" [1 1 1] "point3 from" [0 0 1] "point3 to" [0 0 0]\n'
        + SHEET.format(material='Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]'),
        device,
    )
    assert plate[1] > 0.01
    np.testing.assert_allclose(sheet / plate, expected_ratio, rtol=2e-3)


def test_a_sheet_in_a_furnace_shows_R_plus_T_times_the_sky(tmp_path, device):
    sky = 'LightSource "infinite" "rgb L" [1 1 1]\n'
    sheet, sheet_error = _mean_xyz(tmp_path, sky + SHEET.format(material=SHEET_MATERIAL), device, spp=64)
    bare, _ = _mean_xyz(tmp_path, sky, device)
    assert bare[1] > 0.01
    expected = (0.2 + 0.6) * bare
    assert np.all(np.abs(sheet - expected) <= 5 * sheet_error + 1e-6 * expected), (sheet, expected, sheet_error)
    # Leaving out either lobe would miss by far more than the noise.
    assert np.all(np.abs(0.2 * bare - sheet) > 20 * sheet_error)


def test_pbrt_defaults_and_scale(tmp_path):
    path = tmp_path / "d.pbrt"
    path.write_text(
        HEADER.format(spp=1)
        + SHEET.format(material='Material "diffusetransmission" "float scale" 2 "rgb transmittance" [0.1 0.2 0.3]')
    )
    data, _ = pbrt_scene_data(path)
    (material,) = data["materials"].values()
    # pbrt-v4's defaults: reflectance and transmittance 0.25, each multiplied by scale.
    assert material == {
        "type": "diffusetransmission",
        "reflectance": {"value": 0.5},
        "transmittance": {"rgb": [0.2, 0.4, 0.6]},
    }
