"""`spectrace display list | compare | match | metamerism` as a user runs them: what they print, through the command
line's entry point in this process; their refusals (exit status, one line on stderr) in a subprocess."""

import json

import colour
import numpy as np
import pytest

from cli_runner import run_here, run_spectrace
from spectrace.displays import display_names

TRIPLE = ["0.6", "0.3", "0.2"]


def _run(*args, check=True):
    if not check:
        return run_spectrace("display", *args, timeout=300)
    result = run_here("display", *args)
    assert result.returncode == 0, result.stderr
    return result


def _json(*args):
    return json.loads(_run(*args, "--json").stdout)


def test_list_shows_every_display_with_its_chromaticities():
    listing = _json("list")["displays"]
    assert [item["name"] for item in listing] == display_names()
    by_name = {item["name"]: item for item in listing}
    dell = by_name["LCD-Dell_CCFL"]
    assert dell["technology"] == "LCD with CCFL backlight (inferred)"
    assert dell["white_luminance_cd_m2"] == pytest.approx(165.8, abs=0.1)
    # the data's own notes give white xy (0.3167, 0.3384) from colour-science on the file's native sampling
    assert dell["white_xy"] == pytest.approx([0.3167, 0.3384], abs=3e-4)
    assert by_name["LCD-CCFL_HDRVDP2"]["white_luminance_cd_m2"] is None  # relative data
    assert by_name["LCD-CCFL_HDRVDP2"]["white_xy"] == pytest.approx([0.3127, 0.3290], abs=2e-4)  # D65 by design


@pytest.mark.slow
def test_compare_json_and_plot(tmp_path):
    plot = tmp_path / "compare.png"
    result = _json(
        "compare", "--rgb", *TRIPLE, "-d", "CRT-Dell", "-d", "OLED-SonyPVM2541", "-d", "CRT-Dell", "--plot", str(plot)
    )
    first, second, again = result["displays"]
    assert first["xyz_cd_m2"][1] == pytest.approx(first["luminance_cd_m2"])
    assert first["xy"] == pytest.approx(colour.XYZ_to_xy(np.array(first["xyz_cd_m2"])), abs=1e-12)
    assert set(first["lab"]) == {"cie1931_2", "cie1964_10", "cie2012_2"}
    pairs = {(pair["first"], pair["second"]): pair["delta_e_2000"] for pair in result["pairs"]}
    assert all(value == pytest.approx(0, abs=1e-9) for value in pairs[("CRT-Dell", "CRT-Dell")].values())
    reference = colour.delta_E(first["lab"]["cie1964_10"], second["lab"]["cie1964_10"], method="CIE 2000")
    assert pairs[("CRT-Dell", "OLED-SonyPVM2541")]["cie1964_10"] == pytest.approx(reference)
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and plot.stat().st_size > 10_000


def test_compare_table_of_all_displays():
    output = _run("compare", "--rgb", *TRIPLE).stdout
    assert all(name in output for name in display_names())
    assert "CIEDE2000" in output


def test_match_in_gamut_and_out_of_gamut():
    exact = _json("match", "--rgb", *TRIPLE, "--from", "CRT-Dell", "--to", "LCD-HP_narrowband", "--encoding", "srgb")
    assert exact["in_gamut"] and exact["delta_e_2000"]["cie1931_2"] < 0.5
    assert exact["from_xyz_cd_m2"] == pytest.approx(exact["to_xyz_cd_m2"], rel=1e-9)
    assert exact["to_rgb"] == pytest.approx(colour.cctf_encoding(np.array(exact["to_drive"]), function="sRGB"))

    closest = _json("match", "--rgb", "0", "1", "0", "--from", "LCD-HP_narrowband", "--to", "CRT-Dell")
    assert not closest["in_gamut"]
    assert min(closest["exact_drive"]) < 0 and all(0 <= value <= 1 for value in closest["to_drive"])
    assert closest["delta_e_2000"]["cie1931_2"] > 1


def test_user_csv_display_from_the_command_line(tmp_path):
    path = tmp_path / "three_lines.csv"
    wavelengths_nm = np.arange(380, 781, 10)
    rows = [
        ",".join([str(nm), *(str(np.exp(-(((nm - centre) / 15) ** 2))) for centre in (620, 530, 460))])
        for nm in wavelengths_nm
    ]
    path.write_text("# units: W/(sr m^2 nm)\nwavelength_nm,red,green,blue\n" + "\n".join(rows) + "\n")
    listing = _json("list", "--display", str(path))["displays"]
    assert listing[-1]["name"] == "three_lines" and listing[-1]["absolute"]


@pytest.mark.subprocess
@pytest.mark.slow
def test_bad_input_is_one_line_without_traceback(tmp_path):
    path = tmp_path / "bad_display.csv"
    path.write_text("wavelength_nm,red,green\n400,1,1\n500,1,1\n")
    result = _run("compare", "--rgb", *TRIPLE, "--display", str(path), check=False)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "Traceback" not in result.stderr
    assert str(path) in result.stderr and "wavelength_nm,red,green,blue" in result.stderr

    result = _run("match", "--rgb", "0.5", "0.5", "1.5", "--from", "CRT-Dell", "--to", "CRT-HP", check=False)
    assert result.returncode == 2 and "[0, 1]" in result.stderr and "Traceback" not in result.stderr


RGB_OUT_OF_RANGE = [
    (["compare"], ["2", "0", "0"], "(2, 0, 0)"),
    (["match", "--from", "CRT-Dell", "--to", "CRT-HP"], ["0.5", "-0.5", "1"], "(0.5, -0.5, 1)"),
    (["metamerism", "--from", "CRT-Dell", "--to", "CRT-HP"], ["1", "1", "1.01"], "(1, 1, 1.01)"),
]


@pytest.mark.parametrize(("command", "triple", "shown"), RGB_OUT_OF_RANGE)
def test_an_rgb_triple_out_of_range_names_the_option_as_typed(command, triple, shown):
    """Every display command checks --rgb where it reads it: one line naming the option (not the library's
    argument name), the values as given and the command's help, before any display is loaded or rendered."""
    _check_rgb_refusal(run_here("display", *command, "--rgb", *triple), command, shown)


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_real_process_refuses_an_rgb_triple_out_of_range_in_one_line():
    command, triple, shown = RGB_OUT_OF_RANGE[1]
    _check_rgb_refusal(_run(*command, "--rgb", *triple, check=False), command, shown)


def _check_rgb_refusal(result, command, shown):
    assert result.returncode == 2 and result.stdout == "", result
    line = result.stderr
    assert line.count("\n") == 1 and line.startswith(f"error: --rgb: RGB values must lie in [0, 1], got {shown} (see `")
    assert line.endswith(f"spectrace display {command[0]} --help`)\n"), line


def _file_primaries_on_grid(name: str, white_cd_m2: float) -> np.ndarray:
    """The shipped CSV's three columns on the 1 nm grid (linear, end values held), scaled so that the white has
    `white_cd_m2` by colour-science's integration: an independent route to the display's emission."""
    from spectrace.resources import spectra_dir

    path = spectra_dir() / "displays" / f"{name}.csv"
    lines = path.read_text(encoding="utf-8").splitlines()
    rows = np.genfromtxt([line for line in lines if not line.startswith("#")], delimiter=",", names=True)
    grid = np.arange(360.0, 831.0)
    primaries = np.array([np.interp(grid, rows["wavelength_nm"], rows[c]) for c in ("red", "green", "blue")])
    white = colour.SpectralDistribution(primaries.sum(axis=0), grid)
    return primaries * white_cd_m2 / _xyz_683(white)[1]


def _xyz_683(sd: colour.SpectralDistribution) -> np.ndarray:
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    return colour.sd_to_XYZ(sd, cmfs=cmfs, k=683, method="Integration")


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_metamerism_per_patch_delta_e_matches_colour_science():
    """`display metamerism`: the two matched lights have one XYZ, and every patch's ΔE2000 is the
    one colour-science gives for Ohta's ColorChecker reflectance times each light, relative to the light itself."""
    report = _json("metamerism", "--from", "LCD-Dell_CCFL", "--to", "LCD-Apple_WLED")
    grid = np.arange(360.0, 831.0)
    lights = [
        np.asarray(report[drive]) @ _file_primaries_on_grid(report[name], 100.0)
        for drive, name in (("source_drive", "source"), ("target_drive", "target"))
    ]
    xyz_lights = [_xyz_683(colour.SpectralDistribution(light, grid)) for light in lights]
    np.testing.assert_allclose(xyz_lights[0], xyz_lights[1], rtol=1e-4)  # a metameric pair of lights

    white = xyz_lights[0]
    checker = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    assert [patch["patch"] for patch in report["patches"]] == list(checker)
    for patch in report["patches"]:
        reflectance = checker[patch["patch"]]
        on_grid = np.interp(grid, reflectance.wavelengths, reflectance.values)
        lab = [
            colour.XYZ_to_Lab(
                _xyz_683(colour.SpectralDistribution(on_grid * light, grid)) / white[1], colour.XYZ_to_xy(white)
            )
            for light in lights
        ]
        expected = colour.delta_E(*lab, method="CIE 2000")
        assert patch["delta_e_2000"] == pytest.approx(expected, abs=1e-3), patch["patch"]
    assert report["max_delta_e_2000"] > 1.0  # the lights match, the lit charts do not
