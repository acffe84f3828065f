"""Displays through a linear polariser: Malus's law on polarised light, one half of unpolarised light at every angle,
the catalogue's record of each display's polarisation, and the command line's answers and refusals."""

import json

import numpy as np
import pytest

from cli_runner import run_in_process, run_spectrace
from spectrace.displays import load_display
from spectrace.displays.polarizer import through_polarizer
from spectrace.errors import SpectraceError
from spectrace.spectral.display_polarization import Polarization, parse_polarization, transmitted_fraction

ANGLES = np.arange(0.0, 181.0, 7.5)


@pytest.mark.parametrize("axis", [0.0, 45.0, 90.0, 117.0])
def test_malus_law_on_linearly_polarised_light(axis):
    fractions = transmitted_fraction(Polarization("linear", axis), ANGLES)
    np.testing.assert_allclose(fractions, np.cos(np.radians(ANGLES - axis)) ** 2, atol=1e-15)


@pytest.mark.parametrize("kind", ["unpolarized", "circular"])
def test_unpolarised_and_circular_light_pass_one_half_at_every_angle(kind):
    np.testing.assert_allclose(transmitted_fraction(Polarization(kind), ANGLES), 0.5, atol=1e-15)


def test_a_real_polariser_passes_k1_parallel_k2_crossed_and_their_mean_of_unpolarised_light():
    """Its Mueller matrix (a partial polariser rotated by θ, built here from the rotation matrices) applied to the
    display's Stokes vector."""
    k1, k2 = 0.86, 0.004
    for axis in (0.0, 30.0, 45.0):
        for angle in ANGLES[:5]:
            c, s = np.cos(np.radians(2 * angle)), np.sin(np.radians(2 * angle))
            rotation = np.array([[1, 0, 0, 0], [0, c, s, 0], [0, -s, c, 0], [0, 0, 0, 1]])
            aligned = 0.5 * np.array([[k1 + k2, k1 - k2, 0, 0], [k1 - k2, k1 + k2, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]])
            stokes = Polarization("linear", axis).stokes()
            expected = (rotation.T @ aligned @ rotation @ stokes)[0]
            assert transmitted_fraction(Polarization("linear", axis), angle, k1, k2) == pytest.approx(expected)
        assert transmitted_fraction(Polarization("linear", axis), axis, k1, k2) == pytest.approx(k1)
        assert transmitted_fraction(Polarization("linear", axis), axis + 90, k1, k2) == pytest.approx(k2)
    assert transmitted_fraction(Polarization("unpolarized"), 10.0, k1, k2) == pytest.approx((k1 + k2) / 2)
    with pytest.raises(SpectraceError, match="0 <= k2 <= k1 <= 1"):
        through_polarizer([load_display("CRT-Dell")], (0.0,), transmittances=(0.5, 0.6))


def test_catalogue_records_polarisation():
    assert load_display("LCD-Dell_CCFL").polarization.kind == "linear"
    assert load_display("LCD-Dell_CCFL").polarization.note.startswith("assumed")
    assert load_display("CRT-Dell").polarization.kind == "unpolarized"
    assert load_display("CRT-Brainard1997").polarization.kind == "unpolarized"


def test_through_a_polariser_luminance_follows_malus_and_chromaticity_stays():
    lcd, crt = load_display("LCD-Dell_CCFL"), load_display("CRT-Dell")
    result = through_polarizer([lcd, crt], tuple(ANGLES), (0.6, 0.3, 0.2))
    axis = lcd.polarization.axis_deg
    full = [row[0].xyz_cd_m2 / max(row[0].fraction, 1e-300) for row in result.rows if row[0].fraction > 0.5]
    unfiltered = full[0]
    for angle, (seen_lcd, seen_crt) in zip(ANGLES, result.rows):
        malus = np.cos(np.radians(angle - axis)) ** 2
        np.testing.assert_allclose(seen_lcd.xyz_cd_m2, malus * unfiltered, rtol=1e-12, atol=1e-12)
        assert seen_crt.fraction == pytest.approx(0.5)
        if malus > 1e-6:
            np.testing.assert_allclose(seen_lcd.xy, result.rows[0][0].xy, atol=1e-12)
    assert json.dumps(result.to_json())  # plain data


def test_polarisation_specs_and_their_errors():
    assert parse_polarization("linear 90 (assumed)") == Polarization("linear", 90.0, "assumed")
    assert parse_polarization("Unpolarised").kind == "unpolarized"
    assert parse_polarization("linear 225").axis_deg == 45.0
    for text, message in (("linear", "needs its axis"), ("sideways", "must be 'linear"), ("circular 3", "no angle")):
        with pytest.raises(SpectraceError, match=message):
            parse_polarization(text, where="f.csv: # polarization")


def test_a_bad_polarization_line_in_a_display_file_names_the_file_and_key(tmp_path):
    path = tmp_path / "screen.csv"
    path.write_text("# polarization: linear north\nwavelength_nm,red,green,blue\n400,1,0,0\n500,0,1,0\n600,0,0,1\n")
    with pytest.raises(SpectraceError) as error:
        load_display(str(path))
    assert str(error.value).startswith(f"{path}: # polarization: 'linear' needs its axis")


def _run(*args):
    return run_spectrace("display", *args, timeout=300)


@pytest.mark.subprocess
@pytest.mark.slow
def test_polarizer_command_json():
    result = _run("polarizer", "-d", "LCD-Apple_WLED", "-d", "CRT-HP", "-a", "0", "-a", "45", "-a", "135", "--json")
    assert result.returncode == 0, result.stderr
    angles = json.loads(result.stdout)["angles"]
    lcd = [angle["displays"][0] for angle in angles]
    crt = [angle["displays"][1] for angle in angles]
    assert [item["fraction"] for item in lcd] == pytest.approx([0.5, 1.0, 0.0], abs=1e-12)
    assert [item["luminance_cd_m2"] for item in crt] == pytest.approx([50.0] * 3)
    assert lcd[1]["luminance_cd_m2"] == pytest.approx(100.0)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--polarization", "CRT-HP=linear up"], "--polarization CRT-HP: 'linear' needs its axis"),
        (["--polarization", "OLED-SonyPVM2541=circular"], "--polarization: 'oled-sonypvm2541' is not one"),
        (["--polarization", "CRT-HP=unknown"], "--polarization: the polarisation of CRT-HP's light is unknown"),
        (["--transmittances", "0.5", "0.6"], "--transmittances: a polariser's principal transmittances need"),
        (["-d", "nope"], "--display: unknown display 'nope'"),
    ],
)
def test_polarizer_refusals_are_one_line(args, expected, monkeypatch, capsys):
    status, stderr = run_in_process(monkeypatch, capsys, ["display", "polarizer", "-d", "CRT-HP", *args])
    assert status == 2 and stderr.count("\n") == 1 and expected in stderr, stderr


def test_a_polarisation_given_on_the_command_line_replaces_the_catalogues(monkeypatch, capsys):
    monkeypatch.setattr(
        "sys.argv",
        [
            "spectrace",
            "display",
            "polarizer",
            "-d",
            "CRT-HP",
            "-d",
            "CRT-Dell",
            "--polarization",
            "crt-hp=linear 90",
            "-a",
            "0",
            "--json",
        ],
    )
    from spectrace import cli

    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    assert exit_info.value.code in (0, None)
    shown = json.loads(capsys.readouterr().out)["angles"][0]["displays"]
    assert shown[0]["fraction"] == pytest.approx(0.0, abs=1e-12) and shown[1]["fraction"] == 0.5


@pytest.mark.subprocess
@pytest.mark.slow
def test_model_command_json():
    result = _run("model", "LCD-GeChic1303H_WLED", "--json")
    assert result.returncode == 0, result.stderr
    fit = json.loads(result.stdout)
    assert fit["backlight"] == "wled_yag"
    assert all(item["delta_xy"] < 0.003 for item in fit["primaries"].values())
    assert [variant["name"] for variant in fit["variants"]][1:] == [
        "YAG:Ce phosphor backlight",
        "CdSe QD film backlight",
        "filters narrowed 10 nm",
    ]


def test_model_refusals_are_one_line_and_keep_files(tmp_path, monkeypatch, capsys):
    kept = tmp_path / "kept.png"
    kept.write_bytes(b"old")
    for args, expected in (
        (["OLED-SonyPVM2541"], "NAME: OLED-SonyPVM2541 is not an LCD"),
        (["LCD-Dell_CCFL", "--backlight", "led"], "--backlight: unknown backlight 'led'"),
        (["LCD-Dell_CCFL", "--plot", str(tmp_path / "no" / "such.png")], "such.png"),
        (["LCD-Dell_CCFL", "--plot", str(tmp_path / "plot.xyz")], "plot.xyz"),
    ):
        status, stderr = run_in_process(monkeypatch, capsys, ["display", "model", *args])
        assert status == 2 and stderr.count("\n") == 1 and expected in stderr, stderr
    assert kept.read_bytes() == b"old" and sorted(path.name for path in tmp_path.iterdir()) == ["kept.png"]
