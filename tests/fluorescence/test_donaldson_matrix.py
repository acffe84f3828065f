"""A fluorescent material given by a measured re-radiation (Donaldson) matrix CSV (spectrace.spectral.donaldson):
a separable matrix written here as Q · a(λi) ⊗ e(λo) is the parametric dye it was made from, on the film's grid and
in a render against the closed form of test_fluorescent_path; a malformed or non-separable matrix is one error
naming the file and the scene key."""

import numpy as np
import pytest

import spectrace as S
from cli_runner import run_spectrace
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.scene.loader import load_scene
from spectrace.spectral.grid import GRID_NM

from .test_fluorescent_path import (
    EMISSION,
    EMISSION_NORMALISED,
    EXCITATION,
    SIGMAS,
    Q,
    _bands,
    _closed_form_bands,
    _dye,
    _fluorescent_radiance,
    _gaussian,
    _mean_and_error,
    _scene,
)

# The matrix's grid: 1 nm steps, so that the grid's resampling is exact; rows cover the excitation band, columns the
# emission (the Gaussian is below 1e-8 of its peak at their ends, which the resampling holds outside).
ROWS = (GRID_NM >= 400) & (GRID_NM <= 490)
COLUMNS = (GRID_NM >= 400) & (GRID_NM <= 720)


def _write_matrix(path, matrix: np.ndarray, rows=GRID_NM[ROWS], columns=GRID_NM[COLUMNS]) -> None:
    lines = [
        "# photons re-emitted per nm of λ_out per photon arriving at λ_in",
        "wavelength_nm," + ",".join(f"{c:g}" for c in columns),
    ]
    lines += [f"{r:g}," + ",".join(f"{v:.9g}" for v in row) for r, row in zip(rows, matrix)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _separable(quantum_yield: float = Q) -> np.ndarray:
    emission = EMISSION[COLUMNS] / np.trapezoid(EMISSION[COLUMNS], GRID_NM[COLUMNS])
    return quantum_yield * np.outer(EXCITATION[ROWS], emission)


def test_a_separable_matrix_is_the_parametric_dye_it_was_made_from(tmp_path):
    path = tmp_path / "dye.csv"
    _write_matrix(path, _separable())
    material = S.fluorescent(S.diffuse(0.0), matrix=path)
    # The matrix holds the yield: its excitation is Q a(λ), its yield factor 1.
    np.testing.assert_allclose(material.excitation.values, Q * EXCITATION, atol=1e-7)
    emission = material.emission.values / np.trapezoid(material.emission.values, GRID_NM)
    np.testing.assert_allclose(emission, EMISSION_NORMALISED, atol=1e-6 * EMISSION_NORMALISED.max())
    assert material.quantum_yield == 1.0


@pytest.mark.slow
def test_a_separable_matrix_renders_the_closed_form_and_the_parametric_dye(device, tmp_path):
    """Narrow-band blue light on the matrix's dye over a black base: the band radiance in 30 nm groups is the closed
    form's within 4 standard errors, and that of the parametric dye's render within both renders' noise."""
    path = tmp_path / "dye.csv"
    _write_matrix(path, _separable())
    light = _gaussian(445.0, 8.0)
    renders = []
    for material in (S.fluorescent(S.diffuse(0.0), matrix=path), _dye(S.diffuse(0.0))):
        centres, edges, pixels = _bands(device, _scene(material, light, spp=256))
        masks = [(centres > lo) & (centres < hi) for lo, hi in [(500, 530), (530, 560), (560, 590), (590, 620)]]
        renders.append(_mean_and_error(np.stack([pixels[:, m].mean(axis=1) for m in masks], axis=1)))
    expected = _closed_form_bands(edges, _fluorescent_radiance(light))
    grouped_expected = np.array([expected[m].mean() for m in masks])
    (matrix_mean, matrix_error), (parametric_mean, parametric_error) = renders
    assert np.all(np.abs(matrix_mean - grouped_expected) <= SIGMAS * matrix_error), (matrix_mean, grouped_expected)
    assert np.all(matrix_error < 0.2 * grouped_expected)  # precise enough to tell a yield applied twice
    assert np.all(np.abs(matrix_mean - parametric_mean) <= SIGMAS * np.hypot(matrix_error, parametric_error)), (
        matrix_mean,
        parametric_mean,
    )


SCENE = (
    camera_film(width="8", height="8")
    + """[materials.paper]
type = "diffuse"
reflectance = {{ value = 0.5 }}
[materials.dye]
type = "fluorescent"
base = "paper"
{keys}
[[shapes]]
type = "sphere"
material = "dye"
[[lights]]
type = "constant"
radiance = {{ value = 1.0 }}
"""
)


def _scene_file(tmp_path, keys: str = 'matrix = "dye.csv"'):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(keys=keys), encoding="utf-8")
    return path


def test_a_scene_file_reads_the_matrix_relative_to_itself(tmp_path):
    _write_matrix(tmp_path / "dye.csv", _separable())
    material = load_scene(_scene_file(tmp_path, 'matrix = "dye.csv"\nquantum_yield = 0.5')).shapes[0].material
    np.testing.assert_allclose(material.excitation.values, Q * EXCITATION, atol=1e-7)
    assert material.quantum_yield == 0.5  # a factor on the matrix


def _non_separable() -> np.ndarray:
    # Excitation at 420-445 nm re-emitted around 520 nm, at 445-470 nm around 620 nm: two dyes, rank two.
    shifted = np.where(GRID_NM[ROWS][:, None] < 445, _gaussian(520.0, 15.0)[COLUMNS], _gaussian(620.0, 15.0)[COLUMNS])
    return 0.02 * EXCITATION[ROWS][:, None] * shifted


@pytest.mark.parametrize(
    "matrix, edit, problem",
    [
        (_non_separable, None, "not separable (its rank-one remainder is"),
        (_separable, lambda text: text.replace("\n410,", "\n410,-1,", 1), "expected 322 comma-separated fields"),
        (_separable, lambda text: text.replace("\n410,0,", "\n410,-0.5,", 1), "is negative"),
        (_separable, lambda text: text.replace("\n410,0,", "\n410,x,", 1), "'x' is not a number"),
        (_separable, lambda text: text.replace("\n412,", "\n409,", 1), "ascending"),
        (lambda: 100 * _separable(), None, "re-emits 64 photons per photon arriving"),
        (lambda: 0 * _separable(), None, "zero everywhere"),
    ],
)
def test_a_bad_matrix_is_one_error_naming_the_file_and_the_key(tmp_path, matrix, edit, problem):
    path = tmp_path / "dye.csv"
    _write_matrix(path, matrix())
    if edit is not None:
        path.write_text(edit(path.read_text(encoding="utf-8")), encoding="utf-8")
    with pytest.raises(SpectraceError) as error:
        load_scene(_scene_file(tmp_path))
    message = str(error.value)
    assert "materials.dye.matrix" in message and str(path) in message and problem in message, message
    assert "\n" not in message


@pytest.mark.parametrize(
    "keys",
    [
        'matrix = "dye.csv"\nexcitation = { value = 0.5 }',
        "excitation = { value = 0.5 }",
    ],
)
def test_matrix_or_excitation_and_emission(tmp_path, keys):
    _write_matrix(tmp_path / "dye.csv", _separable())
    with pytest.raises(SpectraceError) as error:
        load_scene(_scene_file(tmp_path, keys))
    assert "materials.dye" in str(error.value) and "matrix" in str(error.value)


@pytest.mark.subprocess
def test_the_command_line_reports_a_non_separable_matrix_in_one_line_and_writes_nothing(tmp_path):
    _write_matrix(tmp_path / "dye.csv", _non_separable())
    out = tmp_path / "out.png"
    out.write_bytes(b"kept")
    result = run_spectrace("render", str(_scene_file(tmp_path)), "-o", str(out))
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1, result.stderr
    assert "materials.dye.matrix" in lines[0] and "dye.csv" in lines[0] and "not separable" in lines[0]
    assert out.read_bytes() == b"kept"
