"""Displays as spectral emitters: data loading, additivity, colorimetry against colour-science, comparison
and matching (spectrace.displays)."""

import itertools
from pathlib import Path

import colour
import numpy as np
import pytest

from spectrace.displays import (
    ALL_OBSERVERS,
    Display,
    Encoding,
    Observer,
    ViewingConditions,
    compare_displays,
    decode_to_drive,
    display_names,
    encode_drive,
    load_all_displays,
    load_display,
    load_display_csv,
    match_colour,
    observer_cmfs,
)
from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir
from spectrace.spectral import CIE_1931_CMFS, GRID_NM

# colour-science warns each time it aligns a spectrum to a CMF table's range; that is the intended behaviour here.
pytestmark = pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")

TRIPLE = (0.6, 0.3, 0.2)
SHIPPED_FILES = sorted((spectra_dir() / "displays").glob("*.csv"))
COLOUR_SCIENCE_KEYS = {
    "CRT-Brainard1997": "Typical CRT Brainard 1997",
    "LCD-AppleStudioDisplay_CCFL": "Apple Studio Display",
}


def _colour_cmfs(observer: Observer) -> colour.MultiSpectralDistributions:
    return colour.MSDS_CMFS[observer.colour_science_name]


def _colour_xyz_683(values_on_grid: np.ndarray, observer: Observer) -> np.ndarray:
    """Independent reference: colour-science's integration of a radiance on the grid, times 683 lm/W."""
    sd = colour.SpectralDistribution(values_on_grid, GRID_NM)
    return colour.sd_to_XYZ(sd, cmfs=_colour_cmfs(observer), k=683, method="Integration")


def _ybar_1931() -> np.ndarray:
    return colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values[:, 1]  # tabulated 360..830 nm, 1 nm


def _luminance_683(values_on_grid: np.ndarray) -> float:
    return 683 * np.trapezoid(values_on_grid * _ybar_1931(), GRID_NM)


def _csv_columns(path):
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    rows = np.genfromtxt([line for line in lines if not line.startswith("#")], delimiter=",", names=True)
    return rows["wavelength_nm"], [rows[channel] for channel in ("red", "green", "blue")]


@pytest.fixture(scope="module")
def displays() -> dict[str, Display]:
    return {display.name: display for display in load_all_displays()}


# ---------------------------------------------------------------- catalogue and data


def test_catalogue_has_every_shipped_file_and_the_colour_science_displays(displays):
    assert len(SHIPPED_FILES) == 9
    assert set(display_names()) == {path.stem for path in SHIPPED_FILES} | set(COLOUR_SCIENCE_KEYS)
    assert displays["LCD-Dell_CCFL"].technology == "LCD with CCFL backlight (inferred)"
    assert displays["OLED-SonyPVM2541"].technology == "OLED"
    assert displays["CRT-Dell"].absolute and not displays["LCD-CCFL_HDRVDP2"].absolute
    assert load_display("lcd-dell_ccfl").name == "LCD-Dell_CCFL"  # names are case-insensitive


@pytest.mark.parametrize("path", SHIPPED_FILES, ids=lambda path: path.stem)
def test_shipped_primaries_are_the_file_columns(path, displays):
    wavelengths_nm, columns = _csv_columns(path)
    display = displays[path.stem]
    inside = (wavelengths_nm[0] <= GRID_NM) & (wavelengths_nm[-1] >= GRID_NM)
    for primary, column in zip(display.primaries, columns):
        np.testing.assert_allclose(
            primary.values[inside], np.interp(GRID_NM[inside], wavelengths_nm, column), rtol=1e-12, atol=0
        )


@pytest.mark.parametrize("name", sorted(COLOUR_SCIENCE_KEYS))
def test_colour_science_displays_are_its_data(name, displays):
    reference = colour.MSDS_DISPLAY_PRIMARIES[COLOUR_SCIENCE_KEYS[name]]
    on_table = np.isin(GRID_NM, reference.wavelengths)
    for channel, primary in enumerate(displays[name].primaries):
        np.testing.assert_allclose(primary.values[on_table], reference.values[:, channel], rtol=1e-12)
    assert not displays[name].absolute


def test_white_point_of_measured_data_agrees_with_colour_science_on_native_sampling(displays):
    # LCD-Dell: 4 nm samples; colour-science integrates them interpolated to 1 nm over the file's own range.
    wavelengths_nm, columns = _csv_columns(spectra_dir() / "displays" / "LCD-Dell_CCFL.csv")
    white = colour.SpectralDistribution(np.sum(columns, axis=0), wavelengths_nm)
    white = white.interpolate(colour.SpectralShape(380, 780, 1), interpolator=colour.LinearInterpolator)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().trim(colour.SpectralShape(380, 780, 1))
    reference_xyz = colour.sd_to_XYZ(white, cmfs=cmfs, k=683, method="Integration")
    display = displays["LCD-Dell_CCFL"]
    np.testing.assert_allclose(display.white_xy(), colour.XYZ_to_xy(reference_xyz), atol=2e-4)
    assert display.white_luminance_cd_m2 == pytest.approx(reference_xyz[1], rel=2e-3)


def test_observer_tables():
    np.testing.assert_allclose(observer_cmfs(Observer.CIE_1931_2), CIE_1931_CMFS, rtol=1e-12, atol=1e-15)
    cmfs_2012 = observer_cmfs(Observer.CIE_2012_2)
    assert np.all(cmfs_2012[GRID_NM < 390] == 0)  # the 2012 observer is tabulated from 390 nm
    reference = colour.MSDS_CMFS["CIE 2015 2 Degree Standard Observer"]
    np.testing.assert_allclose(cmfs_2012[GRID_NM >= 390], reference.values, rtol=1e-12)


# ---------------------------------------------------------------- emission and colorimetry


def test_emission_of_a_sum_of_triples_is_the_sum_of_emissions(displays):
    a, b = np.array([0.25, 0.1, 0.4]), np.array([0.35, 0.55, 0.2])
    for display in displays.values():
        total = display.emission(a + b).values
        np.testing.assert_allclose(
            total, display.emission(a).values + display.emission(b).values, rtol=1e-12, atol=1e-12 * total.max()
        )
        np.testing.assert_array_equal(display.emission((0, 0, 0)).values, 0.0)
        np.testing.assert_allclose(display.emission((1, 1, 1)).values, np.sum(display.primaries_values, axis=0))


@pytest.mark.parametrize("observer", ALL_OBSERVERS, ids=str)
def test_photometric_xyz_matches_colour_science(observer, displays):
    for display in displays.values():
        reference = _colour_xyz_683(display.emission(TRIPLE).values, observer)
        np.testing.assert_allclose(display.photometric_xyz(TRIPLE, observer), reference, rtol=1e-5)


def test_film_xyz_is_photometric_xyz_over_683_times_ybar_integral(displays):
    ybar_integral = np.trapezoid(_ybar_1931(), GRID_NM)
    for display in displays.values():
        reference = _colour_xyz_683(display.emission(TRIPLE).values, Observer.CIE_1931_2) / (683 * ybar_integral)
        np.testing.assert_allclose(display.film_xyz(TRIPLE), reference, rtol=1e-5)


def test_measured_white_luminance_is_683_times_the_ybar_integral(displays):
    display = displays["LCD-HP_narrowband"]
    assert display.white_luminance_cd_m2 == pytest.approx(_luminance_683(display.primaries_values.sum(axis=0)))
    assert 50 < display.white_luminance_cd_m2 < 1000  # a plausible desktop-monitor white, so the units are right


@pytest.mark.parametrize("name", ["CRT-Dell", "LCD-CCFL_HDRVDP2", "CRT-Brainard1997"])
def test_rescaling_sets_the_white_luminance_and_keeps_chromaticity(name, displays):
    display = displays[name]
    scaled = display.scaled_to_white_luminance(250.0)
    assert _luminance_683(scaled.primaries_values.sum(axis=0)) == pytest.approx(250.0, rel=1e-10)
    np.testing.assert_allclose(scaled.primaries_xy(), display.primaries_xy(), atol=1e-12)
    assert scaled.absolute


def test_transfer_curves_match_the_standard_formulas(displays):
    display = displays["OLED-SamsungNote3"]
    encoded = np.array(TRIPLE)
    srgb_linear = colour.cctf_decoding(encoded, function="sRGB")
    np.testing.assert_allclose(
        display.with_transfer(Encoding.SRGB).emission(encoded).values, display.emission(srgb_linear).values, rtol=1e-12
    )
    np.testing.assert_allclose(
        display.with_transfer(Encoding.GAMMA_2_2).emission(encoded).values,
        display.emission(encoded**2.2).values,
        rtol=1e-12,
    )
    for encoding in Encoding:
        np.testing.assert_allclose(encode_drive(decode_to_drive(encoded, encoding), encoding), encoded, rtol=1e-12)


@pytest.mark.parametrize("rgb", [(0.5, 0.5, 1.2), (-0.1, 0, 0), (np.nan, 0, 0)])
def test_drive_outside_zero_one_is_rejected(rgb, displays):
    with pytest.raises(SpectraceError, match=r"\[0, 1\]"):
        displays["CRT-Dell"].emission(rgb)


# ---------------------------------------------------------------- comparison


def _independent_white_xyz(observer: Observer, white_cd_m2: float) -> np.ndarray:
    """D65 (colour-science's table) scaled to `white_cd_m2` cd/m^2, integrated with `observer`."""
    d65 = colour.SDS_ILLUMINANTS["D65"]
    luminance = colour.sd_to_XYZ(d65, cmfs=_colour_cmfs(Observer.CIE_1931_2), k=683, method="Integration")[1]
    return colour.sd_to_XYZ(d65, cmfs=_colour_cmfs(observer), k=683, method="Integration") * white_cd_m2 / luminance


def _independent_lab(display: Display, drive, observer: Observer, white_cd_m2: float = 100.0) -> np.ndarray:
    """CIELAB of linear drive values (last axis RGB) with the display's white scaled to `white_cd_m2`, and D65 at
    that luminance as the reference white, from colour-science's tables and integration only."""
    scale = white_cd_m2 / _luminance_683(display.primaries_values.sum(axis=0))
    primaries_xyz = np.array([_colour_xyz_683(primary.values * scale, observer) for primary in display.primaries])
    white = _independent_white_xyz(observer, white_cd_m2)
    return colour.XYZ_to_Lab(np.asarray(drive, dtype=float) @ primaries_xyz / white[1], colour.XYZ_to_xy(white))


def test_compare_a_display_with_itself_gives_zero(displays):
    display = displays["LCD-Apple_WLED"]
    comparison = compare_displays([display, display], TRIPLE)
    (pair,) = comparison.pairs
    assert all(pair.delta_e_2000[observer] == pytest.approx(0.0, abs=1e-9) for observer in ALL_OBSERVERS)


@pytest.mark.parametrize("observer", ALL_OBSERVERS, ids=str)
def test_compare_delta_e_matches_an_independent_computation(observer, displays):
    first, second = displays["CRT-Dell"], displays["LCD-HP_narrowband"]
    comparison = compare_displays([first, second], TRIPLE)
    lab_first, lab_second = (_independent_lab(item, TRIPLE, observer) for item in (first, second))
    np.testing.assert_allclose(comparison.colours[0].lab[observer], lab_first, atol=0.02)
    reference = colour.delta_E(lab_first, lab_second, method="CIE 2000")
    assert comparison.pairs[0].delta_e_2000[observer] == pytest.approx(reference, abs=0.02)
    assert reference > 2  # these two displays really differ for this triple


def test_compare_luminance_scales(displays):
    dell, hdrvdp = displays["LCD-Dell_CCFL"], displays["LCD-CCFL_HDRVDP2"]
    common = compare_displays([dell, hdrvdp], (1, 1, 1), ViewingConditions(white_luminance_cd_m2=80))
    assert [item.luminance_cd_m2 for item in common.colours] == pytest.approx([80, 80])
    measured = compare_displays([dell, hdrvdp], (1, 1, 1), ViewingConditions(80, keep_measured_radiance=True))
    assert measured.colours[0].luminance_cd_m2 == pytest.approx(_luminance_683(dell.primaries_values.sum(axis=0)))
    assert measured.colours[1].luminance_cd_m2 == pytest.approx(80)  # relative data: set to the common white


def test_reference_white_is_srgb_white():
    viewing = ViewingConditions()
    np.testing.assert_allclose(viewing.linear_srgb(viewing.reference_white_xyz(Observer.CIE_1931_2)), 1.0, atol=2e-3)


# ---------------------------------------------------------------- matching


@pytest.mark.parametrize(
    ("source", "target", "rgb"),
    [
        ("CRT-Dell", "LCD-HP_narrowband", TRIPLE),
        ("CRT-HP", "OLED-SonyPVM2541", (0.2, 0.5, 0.3)),
        ("LCD-Dell_CCFL", "OLED-SamsungNote3", (0.4, 0.4, 0.4)),
    ],
)
def test_match_in_gamut_has_no_visible_difference_for_the_1931_observer(source, target, rgb, displays):
    result = match_colour(displays[source], rgb, displays[target])
    assert result.in_gamut
    lab_source = _independent_lab(displays[source], rgb, Observer.CIE_1931_2)
    lab_target = _independent_lab(displays[target], result.target_rgb, Observer.CIE_1931_2)
    assert colour.delta_E(lab_source, lab_target, method="CIE 2000") < 0.5
    assert result.delta_e_2000[Observer.CIE_1931_2] < 0.5


def test_match_reads_and_writes_the_stated_encoding(displays):
    source = displays["CRT-Dell"].with_transfer(Encoding.SRGB)
    target = displays["OLED-SonyPVM2541"].with_transfer(Encoding.SRGB)
    result = match_colour(source, TRIPLE, target)
    assert result.in_gamut
    linear_source = colour.cctf_decoding(np.array(TRIPLE), function="sRGB")
    linear_target = colour.cctf_decoding(result.target_rgb, function="sRGB")
    lab_source = _independent_lab(displays["CRT-Dell"], linear_source, Observer.CIE_1931_2)
    lab_target = _independent_lab(displays["OLED-SonyPVM2541"], linear_target, Observer.CIE_1931_2)
    assert colour.delta_E(lab_source, lab_target, method="CIE 2000") < 0.5


def test_match_out_of_gamut_returns_the_closest_drive_in_gamut(displays):
    source, target = displays["LCD-HP_narrowband"], displays["CRT-Dell"]
    result = match_colour(source, (0, 1, 0), target)  # the wide-gamut green lies outside the CRT's gamut
    assert not result.in_gamut
    assert np.all((result.target_drive >= 0) & (result.target_drive <= 1))

    # brute force: a coarse grid over [0, 1]^3, then a fine grid around its best point; the optimiser must do at
    # least as well as the best point found (the clipped exact solution, ΔE 9.14 here, would not)
    lab_goal = _independent_lab(source, (0, 1, 0), Observer.CIE_1931_2)

    def best_on_grid(axes_values):
        drives = np.array(list(itertools.product(*axes_values)))
        differences = colour.delta_E(_independent_lab(target, drives, Observer.CIE_1931_2), lab_goal, method="CIE 2000")
        return drives[np.argmin(differences)], differences.min()

    coarse_drive, _ = best_on_grid([np.linspace(0, 1, 21)] * 3)
    _, fine_best = best_on_grid([np.clip(np.linspace(value - 0.05, value + 0.05, 41), 0, 1) for value in coarse_drive])
    lab_found = _independent_lab(target, result.target_drive, Observer.CIE_1931_2)
    found = colour.delta_E(lab_found, lab_goal, method="CIE 2000")
    assert found == pytest.approx(result.delta_e_2000[Observer.CIE_1931_2], abs=0.02)
    assert 1 < found <= fine_best + 1e-3


# ---------------------------------------------------------------- user CSV files


def _gaussian(wavelengths_nm: np.ndarray, centre_nm: float, width_nm: float) -> np.ndarray:
    return np.exp(-0.5 * ((wavelengths_nm - centre_nm) / width_nm) ** 2)


def _write_display_csv(path, units_line: str | None) -> np.ndarray:
    wavelengths_nm = np.arange(380, 781, 5.0)
    columns = np.stack([2e-3 * _gaussian(wavelengths_nm, centre, 12) for centre in (630, 532, 455)], axis=-1)
    lines = ["# technology: LCD with quantum-dot backlight (invented for a test)"]
    if units_line:
        lines.append(units_line)
    lines.append("wavelength_nm,red,green,blue")
    lines += [f"{nm:g},{r!r},{g!r},{b!r}" for nm, (r, g, b) in zip(wavelengths_nm, columns)]
    path.write_text("\n".join(lines) + "\n")
    return np.interp(GRID_NM, wavelengths_nm, columns.sum(axis=1))


def test_a_user_csv_display_loads(tmp_path):
    path = tmp_path / "my_qd_lcd.csv"
    white_on_grid = _write_display_csv(path, "# units: W/(sr m^2 nm) per channel at full drive")
    display = load_display(str(path))
    assert display.name == "my_qd_lcd" and display.technology == "LCD with quantum-dot backlight"
    assert display.absolute and display.radiance_scale == "measured"
    assert display.white_luminance_cd_m2 == pytest.approx(_luminance_683(white_on_grid), rel=1e-9)
    assert display.primaries_xy()[1, 1] > 0.7  # narrow 532 nm green: close to the spectral locus

    relative = tmp_path / "relative.csv"
    _write_display_csv(relative, None)
    assert not load_display_csv(relative).absolute


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("wavelength_nm,red,green\n400,1,1\n500,1,1\n", "needs the header"),
        ("wavelength_nm,red,green,blue\n400,1,1,1\n500,1,x,1\n", "'x' is not a number"),
        ("wavelength_nm,red,green,blue\n400,1,1,-1\n500,1,1,1\n", "blue primary has negative radiance"),
        ("wavelength_nm,red,green,blue\n400,1,0,1\n500,1,0,1\n", "green primary emits no visible light"),
        ("wavelength_nm,red,green,blue\n500,1,1,1\n400,1,1,1\n", "strictly ascending"),
        ("# only a comment\n", "needs the header"),
    ],
)
def test_bad_display_csv_is_one_line_naming_the_file(tmp_path, content, message):
    path = tmp_path / "broken.csv"
    path.write_text(content)
    with pytest.raises(SpectraceError, match=message) as error:
        load_display(str(path))
    assert str(path) in str(error.value) and "\n" not in str(error.value)


def test_unknown_display_and_missing_file(tmp_path):
    with pytest.raises(SpectraceError, match="unknown display 'LCD-Nope'.*CRT-Dell"):
        load_display("LCD-Nope", where="--display")
    missing = tmp_path / "missing.csv"
    with pytest.raises(SpectraceError, match="display file does not exist") as error:
        load_display(str(missing))
    assert error.value.where == str(missing)


def test_illuminant_metamerism_of_matched_displays():
    from spectrace.displays import load_display
    from spectrace.displays.metamerism import patch_metamerism

    dell = load_display("LCD-Dell_CCFL")
    same = patch_metamerism(dell, (0.8, 0.8, 0.8), dell)
    assert max(p.delta_e_2000 for p in same.patches) < 1e-6  # a display matched to itself lights alike

    report = patch_metamerism(dell, (0.8, 0.8, 0.8), load_display("LCD-Apple_WLED"))
    assert report.match.in_gamut
    assert len(report.patches) == 24
    neutrals = [p.delta_e_2000 for p in report.patches if p.patch.startswith(("white", "neutral", "black"))]
    assert max(neutrals) < 0.5  # near-flat reflectances see little of the spectral difference
    assert report.max_delta_e > 1.0  # chromatic patches do: CCFL lines vs a white LED's phosphor hump
