"""A fluorescent material given by a measured re-radiation (Donaldson) matrix CSV (spectrace.spectral.donaldson):
a separable matrix written here as Q · a(λi) ⊗ e(λo) is the parametric dye it was made from, on the film's grid and
in a render against the closed form of test_fluorescent_path; a malformed or non-separable matrix is one error
naming the file and the scene key."""

import numpy as np
import pytest

import spectrace as S
from cli_runner import run_spectrace
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.engine.scene_buffers import build_scene_buffers
from spectrace.engine.scene_features import scene_feature_defines
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
def test_the_command_line_reports_a_bad_matrix_in_one_line_and_writes_nothing(tmp_path):
    _write_matrix(tmp_path / "dye.csv", 100 * _separable())
    out = tmp_path / "out.png"
    out.write_bytes(b"kept")
    result = run_spectrace("render", str(_scene_file(tmp_path)), "-o", str(out))
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1, result.stderr
    assert "materials.dye.matrix" in lines[0] and "dye.csv" in lines[0] and "re-emits" in lines[0]
    assert out.read_bytes() == b"kept"


# Two dyes in one matrix, the sum of two separable ones: dye 1 absorbs at 405-440 nm and emits around 520 nm, dye 2
# absorbs at 430-480 nm (the bands overlap) and emits around 620 nm. Its emission changes with the excitation
# wavelength, so no single dye (rank one) is it.
DYES = (
    (0.9, np.where((GRID_NM >= 405) & (GRID_NM <= 440), 0.7, 0.0), _gaussian(520.0, 15.0)),
    (0.6, np.where((GRID_NM >= 430) & (GRID_NM <= 480), 0.5, 0.0), _gaussian(620.0, 20.0)),
)


def _two_dyes() -> np.ndarray:
    matrix = np.zeros((ROWS.sum(), COLUMNS.sum()))
    for quantum_yield, excitation, emission in DYES:
        normalised = emission[COLUMNS] / np.trapezoid(emission[COLUMNS], GRID_NM[COLUMNS])
        matrix += quantum_yield * np.outer(excitation[ROWS], normalised)
    return matrix


def _two_dyes_radiance(light: np.ndarray) -> np.ndarray:
    """The closed form of test_fluorescent_path, summed over the dyes."""
    radiance = np.zeros_like(GRID_NM)
    for quantum_yield, excitation, emission in DYES:
        normalised = emission / np.trapezoid(emission, GRID_NM)
        radiance += quantum_yield * normalised / GRID_NM * np.trapezoid(excitation * light * GRID_NM, GRID_NM)
    return radiance


def test_a_non_separable_matrix_is_kept_as_its_table(tmp_path):
    """Its spectra are its row totals (photons re-emitted per photon arriving, Σ Q a) and its column totals."""
    path = tmp_path / "dyes.csv"
    _write_matrix(path, _two_dyes())
    material = S.fluorescent(S.diffuse(0.0), matrix=path)
    assert material.matrix is not None and material.quantum_yield == 1.0
    np.testing.assert_allclose(material.matrix.values, _two_dyes(), rtol=1e-8)
    expected = sum(quantum_yield * excitation for quantum_yield, excitation, _ in DYES)
    np.testing.assert_allclose(material.excitation.values, expected, atol=1e-7)
    separable = S.fluorescent(S.diffuse(0.0), matrix=_written(tmp_path / "dye.csv", _separable()))
    assert separable.matrix is None
    from_file = load_scene(_scene_file(tmp_path, 'matrix = "dyes.csv"\nquantum_yield = 0.5')).shapes[0].material
    assert from_file.matrix == material.matrix and from_file.quantum_yield == 0.5


def _written(path, matrix: np.ndarray):
    _write_matrix(path, matrix)
    return path


def _grouped(centres, pixels, groups):
    masks = [(centres > lo) & (centres < hi) for lo, hi in groups]
    return masks, np.stack([pixels[:, m].mean(axis=1) for m in masks], axis=1)


@pytest.mark.slow
def test_a_two_dye_matrix_renders_as_the_sum_of_the_two_dyes_in_both_tracers(device, tmp_path):
    """Blue light over both excitation bands on the two-dye matrix over a black base: in 30 nm groups the band
    radiance is the closed form's (the two dyes' sum) within 4 standard errors in the path tracer and in the light
    tracer, the two agree within 5 of their combined errors, and the photons re-emitted are ∫ E(λ) λ R(λ) dλ with
    R(λ) = ∫ D(λ, λ') dλ' each row's photon total."""
    light = np.where((GRID_NM >= 395) & (GRID_NM <= 485), 1.0, 0.0)
    material = S.fluorescent(S.diffuse(0.0), matrix=_written(tmp_path / "dyes.csv", _two_dyes()))
    groups = [(490, 520), (520, 550), (550, 580), (580, 610), (610, 640), (640, 670)]
    expected_photons = np.trapezoid(light[ROWS] * GRID_NM[ROWS] * np.trapezoid(_two_dyes(), axis=1), GRID_NM[ROWS])
    results = {}
    for integrator, spp, replicas in (("path", 256, 1), ("light", 2048, 16)):
        centres, edges, pixels = _bands(device, _scene(material, light, spp=spp, integrator=integrator), replicas)
        expected = _closed_form_bands(edges, _two_dyes_radiance(light))
        masks, grouped = _grouped(centres, pixels, groups)
        grouped_expected = np.array([expected[m].mean() for m in masks])
        mean, error = _mean_and_error(grouped)
        assert np.all(np.abs(mean - grouped_expected) <= SIGMAS * error), (integrator, mean, grouped_expected, error)
        bright = grouped_expected > 0.2 * grouped_expected.max()
        assert bright.sum() >= 3 and np.all(error[bright] < 0.25 * grouped_expected[bright])  # precise enough
        photons, photons_error = _mean_and_error((pixels @ (np.diff(edges) * centres))[:, None])
        assert abs(photons[0] - expected_photons) <= SIGMAS * photons_error[0], (integrator, photons, expected_photons)
        assert photons_error[0] < 0.05 * expected_photons
        results[integrator] = mean, error
    (path_mean, path_error), (light_mean, light_error) = results["path"], results["light"]
    assert np.all(np.abs(path_mean - light_mean) <= 5.0 * np.hypot(path_error, light_error)), (path_mean, light_mean)


@pytest.mark.parametrize("integrator", ["path", "light"])
def test_light_in_one_dye_band_re_emits_that_dye_alone(device, tmp_path, integrator):
    """Narrow light at 410 nm reaches dye 1 only: its 520 nm emission shows, dye 2's 620 nm band stays dark (the
    closed form's ratio of the two bands is below 1e-8; the matrix's best rank-one approximation gives 0.145)."""
    material = S.fluorescent(S.diffuse(0.0), matrix=_written(tmp_path / "dyes.csv", _two_dyes()))
    light = _gaussian(410.0, 3.0)
    centres, _, pixels = _bands(device, _scene(material, light, spp=32, integrator=integrator))
    dye_1 = pixels[:, (centres > 505) & (centres < 535)].mean()
    assert dye_1 > 0.0
    assert pixels[:, (centres > 610) & (centres < 640)].mean() < 1e-6 * dye_1


@pytest.mark.parametrize("integrator", ["path", "light"])
def test_a_matrix_scene_s_own_kernels_render_the_general_kernels_bits(device, tmp_path, integrator):
    """The matrix's code is a scene feature (SCENE_HAS_FLUORESCENCE_MATRIX): on for the two-dye matrix, off for a
    separable one, which keeps the parametric dye's kernels; either way a scene's kernels equal the general ones."""
    light = 0.2 + _gaussian(440.0, 30.0)
    for matrix, feature in ((_two_dyes(), 1), (_separable(), 0)):
        material = S.fluorescent(S.diffuse(0.3), matrix=_written(tmp_path / f"dye{feature}.csv", matrix))
        scene = _scene(material, light, spp=4, integrator=integrator)
        assert scene_feature_defines(build_scene_buffers(scene))["SCENE_HAS_FLUORESCENCE_MATRIX"] == feature
        specialised = Renderer(scene, device, specialise=True).render().xyz
        general = Renderer(scene, device, specialise=False).render().xyz
        assert specialised[..., 1].mean() > 0
        assert np.array_equal(specialised.view(np.uint32), general.view(np.uint32))
