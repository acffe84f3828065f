"""pbrt-v4 conductors given by `rgb eta` and `rgb k`, uplifted as the Mitsuba import uplifts <rgb> η and k
(docs/mitsuba.md, "Conductors given in RGB"): with both triples, the imported η(λ), k(λ) reflect at normal incidence,
under D65, the colour R_c = ((η_c − 1)² + k_c²) / ((η_c + 1)² + k_c²) an RGB renderer reflects per channel; one
triple beside a measured spectrum is uplifted alone."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data
from spectrace.spectral import reflectance_to_xyz, xyz_to_linear_srgb
from spectrace.spectral.illuminants import cie_illuminant
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import normal_incidence_reflectance

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
"""
GOLD_ETA, GOLD_K = (0.143119, 0.374957, 1.44248), (3.98316, 2.38572, 1.60322)


def _write(folder: Path, material: str) -> Path:
    path = folder / "scene.pbrt"
    path.write_text(HEADER + material + '\nShape "sphere"\n')
    return path


def _triple(values) -> str:
    return " ".join(f"{v:g}" for v in values)


def _normal_incidence_colour(material) -> np.ndarray:
    reflectance = normal_incidence_reflectance(material.eta.values, material.k.values)
    return xyz_to_linear_srgb(reflectance_to_xyz(Spectrum(reflectance), cie_illuminant("D65")))


@pytest.mark.parametrize(
    "eta, k",
    [(GOLD_ETA, GOLD_K), ((0.2, 0.92, 1.1), (3.9, 2.45, 2.14)), ((1.5, 1.5, 1.5), (0.0, 0.0, 0.0))],
    ids=["gold", "copper", "grey_dielectric_like"],
)
def test_rgb_eta_and_k_give_the_rgb_renderers_colour(tmp_path, eta, k):
    path = _write(tmp_path, f'Material "conductor" "rgb eta" [{_triple(eta)}] "rgb k" [{_triple(k)}]')
    material = load_pbrt_scene(path).shapes[0].material
    expected = normal_incidence_reflectance(np.array(eta), np.array(k))
    np.testing.assert_allclose(_normal_incidence_colour(material), expected, atol=1e-3)
    assert material.eta.min() > 0 and material.k.min() >= 0
    notes = pbrt_scene_data(path)[1].notes
    assert any("eta and k given as rgb are uplifted" in note for note in notes), notes


def test_a_number_beside_an_rgb_counts_as_a_grey_triple(tmp_path):
    path = _write(tmp_path, 'Material "conductor" "float eta" 0.2 "rgb k" [3.9 2.4 2.1]')
    material = load_pbrt_scene(path).shapes[0].material
    expected = normal_incidence_reflectance(np.full(3, 0.2), np.array((3.9, 2.4, 2.1)))
    np.testing.assert_allclose(_normal_incidence_colour(material), expected, atol=1e-3)


def test_one_triple_beside_pbrts_default_copper_is_uplifted_alone(tmp_path):
    """`rgb eta` alone: k stays pbrt's default (copper's measured k); η is the reflectance uplift of the triple over
    its largest value, times that value, so η / max seen as a reflectance under D65 has the colour triple / max."""
    triple = np.array((0.2, 0.4, 1.1))
    data, _ = pbrt_scene_data(_write(tmp_path, f'Material "conductor" "rgb eta" [{_triple(triple)}]'))
    (table,) = data["materials"].values()
    assert table["k"] == {"spectrum": "metals/Cu:k"}
    wavelengths, eta = np.array(table["eta"]["values"]).T  # every 5 nm, a smooth curve
    scaled = Spectrum(np.interp(np.arange(360.0, 831.0), wavelengths, eta) / triple.max())
    colour = xyz_to_linear_srgb(reflectance_to_xyz(scaled, cie_illuminant("D65")))
    np.testing.assert_allclose(colour, triple / triple.max(), atol=1e-3)


def test_a_negative_triple_is_refused_at_its_line(tmp_path):
    path = _write(tmp_path, 'Material "conductor" "rgb eta" [0.2 -0.4 1.1] "rgb k" [3 2 1]')
    with pytest.raises(SpectraceError, match="components must lie in >= 0") as error:
        pbrt_scene_data(path)
    assert error.value.where == f"{path}:5"
