"""Spectrum loading (CSV, scene values, colour-science, the shipped library), `Spectrum` and `SpectrumTable`."""

from pathlib import Path

import colour
import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.spectral.grid import GRID_NM, GRID_SIZE
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import (
    library_spectrum,
    list_library_spectra,
    load_spectrum_csv,
    parse_inline_spectrum,
    spectrum_from_colour,
)
from spectrace.spectral.table import SpectrumTable


def at(spectrum: Spectrum, wavelength_nm: int) -> float:
    return float(spectrum.values[wavelength_nm - 360])


def write(tmp_path: Path, text: str, name: str = "sample.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


THREE_COLUMNS = """# A measured sample (made up for the test)
# units: reflectance

wavelength_nm,white,red,green
400,0.2,0.1,0.0
500,0.6,0.3,0.9
# a comment between rows
700.5,0.8,0.5,0.4
"""


# ---------------------------------------------------------------- CSV


def test_csv_column_is_linear_between_points_and_held_outside(tmp_path):
    spectrum = load_spectrum_csv(write(tmp_path, THREE_COLUMNS), column="white")
    # by hand: 0.2 + (0.6 - 0.2) * (lambda - 400) / 100 between 400 and 500 nm
    assert at(spectrum, 425) == pytest.approx(0.3)
    assert at(spectrum, 450) == pytest.approx(0.4)
    assert at(spectrum, 480) == pytest.approx(0.52)
    # 0.6 + 0.2 * (600 - 500) / 200.5
    assert at(spectrum, 600) == pytest.approx(0.6 + 0.2 * 100 / 200.5)
    assert at(spectrum, 360) == at(spectrum, 399) == pytest.approx(0.2)  # first value held
    assert at(spectrum, 701) == at(spectrum, 830) == pytest.approx(0.8)  # last value held
    assert spectrum.name == "sample:white"


def test_csv_picks_the_named_column(tmp_path):
    path = write(tmp_path, THREE_COLUMNS)
    assert at(load_spectrum_csv(path, column="green"), 450) == pytest.approx(0.45)
    assert at(load_spectrum_csv(path, column="red"), 500) == pytest.approx(0.3)


def test_csv_with_one_column_needs_no_column_name(tmp_path):
    spectrum = load_spectrum_csv(write(tmp_path, "wavelength_nm,radiance\n402.5,1\n405.5,4\n"), name="lamp")
    assert [at(spectrum, nm) for nm in (403, 404, 405)] == pytest.approx([1.5, 2.5, 3.5])
    assert spectrum.name == "lamp"


@pytest.mark.parametrize(
    ("text", "column", "message", "line"),
    [
        (THREE_COLUMNS, None, "several columns", None),
        (THREE_COLUMNS, "blue", "available: white, red, green", None),
        ("wavelength_nm,v\n400,0.1\n500,abc\n", None, r"'abc' is not a number \(value in column 'v'\)", 3),
        ("wavelength_nm,v\n400,0.1\nfour,0.2\n", None, r"'four' is not a number \(wavelength_nm\)", 3),
        ("wavelength_nm,v\n500,0.1\n400,0.2\n", None, "strictly ascending", 3),
        ("wavelength_nm,v\n400,0.1\n400,0.2\n", None, "strictly ascending", 3),
        ("wavelength_nm,v\n400,0.1\n500,nan\n", None, "finite", 3),
        ("wavelength_nm,v\n400,inf\n500,0.2\n", None, "finite", 2),
        ("wavelength_nm,v\n400,0.1\n500\n", None, "expected 2 comma-separated fields", 3),
        ("wavelength_nm,v\n400,0.1\n", None, "at least 2 samples", None),
        ("# only comments\n", None, "no header", None),
        ("lambda,v\n400,0.1\n500,0.2\n", None, "header must be", 1),
        ("wavelength_nm,v\n0.4,0.1\n0.7,0.2\n", None, "micrometres", None),
        # Python's float() reads these; a CSV author does not mean them
        ("wavelength_nm,v\n400,0.1\n500,0_5\n", None, r"'0_5' is not a number \(value in column 'v'\): '_' is not", 3),
        ("wavelength_nm,v\n400,0.1\n5_00,0.5\n", None, r"'5_00' is not a number \(wavelength_nm\)", 3),
        ("wavelength_nm,v\n400,0.1\n500,\uff15\n", None, "'\uff15' is not a number", 3),  # fullwidth 5
        ("wavelength_nm,v\n400,0.1\n500,\u0665\n", None, "'\u0665' is not a number", 3),  # Arabic-Indic 5
        ("wavelength_nm,v\n400,0.1\n500,Infinity\n", None, "is Infinity; spectra must be finite", 3),
        ("wavelength_nm,v\n400,0.1\n500,-NaN\n", None, "is -NaN; spectra must be finite", 3),
        ("wavelength_nm,v\n400,0.1\n500,1e999\n", None, "beyond the range of a float", 3),
        ("wavelength_nm,v\n400,0.1\n500,0x1\n", None, "'0x1' is not a number", 3),
        # a repeated column: which one a scene's `column` means is a guess
        ("# c\nwavelength_nm,v,w,v\n400,0.1,0,0.9\n500,0.2,0,0.8\n", "v", "column 'v' appears twice", 2),
        ("wavelength_nm,v,wavelength_nm\n400,0.1,1\n500,0.2,2\n", "v", "column 'wavelength_nm' appears twice", 1),
    ],
)
def test_csv_errors_name_the_file_and_line(tmp_path, text, column, message, line):
    path = write(tmp_path, text)
    with pytest.raises(SpectraceError, match=message) as error:
        load_spectrum_csv(path, column=column)
    assert error.value.where == (f"{path}:{line}" if line else str(path))


def test_numbers_in_the_usual_forms_are_read(tmp_path):
    spectrum = load_spectrum_csv(write(tmp_path, "wavelength_nm,v\n+4e2,.25\n500.,5E-1\n 600 , 0.75 \n"))
    assert [at(spectrum, nm) for nm in (400, 450, 500, 600)] == pytest.approx([0.25, 0.375, 0.5, 0.75])


def test_a_byte_order_mark_is_not_part_of_the_header(tmp_path):
    """Spreadsheets on Windows save UTF-8 CSV files with a BOM; the file then reads as without one."""
    plain = load_spectrum_csv(write(tmp_path, THREE_COLUMNS), column="red")
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + THREE_COLUMNS.encode())
    np.testing.assert_array_equal(load_spectrum_csv(path, column="red").values, plain.values)
    path.write_bytes(b"\xef\xbb\xbfwavelength_nm,v\n400,0.1\n500,0.2\n")
    assert at(load_spectrum_csv(path), 450) == pytest.approx(0.15)


def test_missing_csv_names_the_path(tmp_path):
    with pytest.raises(SpectraceError, match="spectrum file does not exist") as error:
        load_spectrum_csv(tmp_path / "absent.csv")
    assert error.value.where == str(tmp_path / "absent.csv")


# ---------------------------------------------------------------- values written in a scene


@pytest.mark.parametrize(
    "written",
    [
        "400:0.2, 500:0.6, 700:0.8",
        [[400, 0.2], [500, 0.6], [700, 0.8]],
        [(400.0, 0.2), (500.0, 0.6), (700.0, 0.8)],
        {"400": 0.2, "500": 0.6, "700": 0.8},
    ],
)
def test_inline_forms_agree(written):
    spectrum = parse_inline_spectrum(written, where="scene.toml: materials.m.reflectance")
    assert [at(spectrum, nm) for nm in (360, 450, 600, 830)] == pytest.approx([0.2, 0.4, 0.7, 0.8])
    assert spectrum.source == "scene.toml: materials.m.reflectance"


@pytest.mark.parametrize(
    ("written", "message"),
    [
        ("400:0.2, 500-0.6", "wavelength_nm:value"),
        ("400:0.2, 500:x", "not a number"),
        ("500:0.2, 400:0.6", "ascending"),
        ("400:0.2, 500:nan", "finite"),
        ("400:0.2", "at least 2"),
        ([[400, 0.2], [500]], "pair"),
        ([[400, 0.2], [500, "0.6"]], "two numbers"),
        ([[400, 0.2], [500, True]], "two numbers"),
        ([[400, 0.2], [500, float("inf")]], "finite"),
        ({"400": 0.2, "blue": 0.6}, "not a number"),
        ({"400": 0.2, "500": "high"}, "must be a number"),
        ({"500": 0.2, "400": 0.6}, "ascending"),
        (0.5, "must be a"),
    ],
)
def test_inline_errors_name_the_key(written, message):
    with pytest.raises(SpectraceError, match=message) as error:
        parse_inline_spectrum(written, where="scene.toml: lights[1].spectrum")
    assert error.value.where == "scene.toml: lights[1].spectrum"


# ---------------------------------------------------------------- colour-science and the library


def test_colour_distribution_is_joined_linearly():
    sd = colour.SpectralDistribution({400: 0.0, 410: 1.0, 420: 0.0, 430: 0.0})
    spectrum = spectrum_from_colour(sd)
    assert [at(spectrum, nm) for nm in (360, 405, 410, 415, 425, 830)] == pytest.approx([0, 0.5, 1, 0.5, 0, 0])


def test_cornell_box_library_values_match_the_published_table():
    # Cornell "Cornell Box Data" table, first and last rows (white, green, red at 400 and 700 nm).
    white = library_spectrum("cornell_box/reflectance:white")
    red = library_spectrum("cornell_box/reflectance:red")
    green = library_spectrum("cornell_box/reflectance:green")
    assert (at(white, 400), at(green, 400), at(red, 400)) == pytest.approx((0.343, 0.092, 0.040))
    assert (at(white, 700), at(green, 700), at(red, 700)) == pytest.approx((0.737, 0.159, 0.642))
    assert at(white, 402) == pytest.approx((0.343 + 0.445) / 2)
    assert at(red, 830) == pytest.approx(0.642)
    light = library_spectrum("cornell_box/light")
    assert [at(light, nm) for nm in (360, 450, 550, 650, 830)] == pytest.approx([0, 4, 11.8, 17, 18.4])


def test_cie_illuminants_come_from_colour_science():
    assert at(library_spectrum("cie:D65"), 560) == pytest.approx(100.0)
    reference_a = colour.sd_CIE_standard_illuminant_A(colour.SpectralShape(360, 830, 1)).values
    np.testing.assert_allclose(library_spectrum("cie:A").values, reference_a, rtol=1e-12)


def test_library_lists_shipped_files_and_illuminants():
    names = list_library_spectra()
    expected = {"cornell_box/reflectance:white", "cornell_box/reflectance:red", "cornell_box/light", "cie:D65"}
    assert expected <= set(names)
    for name in names:
        if not name.startswith("cie:"):
            assert library_spectrum(name).name == name


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("cornell_box/nothing", "unknown library spectrum"),
        ("cornell_box/reflectance:blue", "available: white, red, green"),
        ("cornell_box/reflectance", "several columns"),
        ("cie:D66", "unknown CIE illuminant"),
    ],
)
def test_library_errors_name_the_key(name, message):
    with pytest.raises(SpectraceError, match=message) as error:
        library_spectrum(name, where="scene.toml: materials.wall.reflectance")
    assert error.value.where == "scene.toml: materials.wall.reflectance"


# ---------------------------------------------------------------- Spectrum and SpectrumTable


def test_spectrum_is_read_only_and_scales():
    spectrum = Spectrum(np.linspace(0, 1, GRID_SIZE), name="ramp")
    with pytest.raises(ValueError):
        spectrum.values[0] = 5
    assert (2 * spectrum).max() == pytest.approx(2.0) and (spectrum * 2).mean() == pytest.approx(1.0)
    assert spectrum.evaluate(360.5) == pytest.approx(0.5 / (GRID_SIZE - 1))
    assert Spectrum.zeros().max() == 0.0 and Spectrum.constant(0.25).min() == 0.25
    with pytest.raises(SpectraceError):
        Spectrum(np.full(GRID_SIZE, np.nan), source="x.csv")


def test_table_stores_each_spectrum_once_at_its_offset():
    table = SpectrumTable()
    ramp = Spectrum(GRID_NM / 830.0)
    half = Spectrum.constant(0.5)
    assert table.add(ramp) == 0
    assert table.add(half) == GRID_SIZE
    assert table.add(Spectrum(GRID_NM / 830.0, name="same values")) == 0
    assert len(table) == 2
    assert table.data.dtype == np.float32 and table.data.shape == (2 * GRID_SIZE,)
    np.testing.assert_array_equal(table.data[GRID_SIZE:], np.float32(0.5))
    np.testing.assert_allclose(table.data[:GRID_SIZE], ramp.values, rtol=1e-7)
