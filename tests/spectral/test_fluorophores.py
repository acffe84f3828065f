"""The shipped fluorescent spectra against the values their sources publish, and the loader's contract."""

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.resources import spectra_dir
from spectrace.spectral import GRID_NM, library_spectrum
from spectrace.spectral.fluorophores import fluorophore_names, load_fluorophore

# name: (excitation peak nm or None for a quantum dot's edge, its FWHM, emission peak, its FWHM, quantum yield), as
# spectra/fluorescent/README.md cites them (Sjöback 1995, Magde 2002, Wolfbeis 1983, Smet 2011, Dabbousi 1997,
# Won 2019; the brightener's yield is marked assumed there).
CITED = {
    "fluorescein": (490, 35, 514, 40, 0.925),
    "rhodamine6g": (530, 35, 552, 40, 0.95),
    "pyranine": (454, 45, 511, 50, 1.0),
    "stilbene_brightener": (350, 50, 435, 60, 0.7),
    "yag_ce": (455, 60, 555, 115, 0.9),
    "cdse_qd_green": (None, None, 530, 30, 0.5),
    "cdse_qd_red": (None, None, 630, 30, 0.5),
    "inp_qd_red": (None, None, 630, 35, 1.0),
}


def _file_columns(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The file's own samples, read here with numpy rather than through the loader."""
    lines = (spectra_dir() / "fluorescent" / f"{name}.csv").read_text(encoding="utf-8").splitlines()
    rows = [line.split(",") for line in lines if line and not line.startswith("#")]
    assert rows[0] == ["wavelength_nm", "excitation", "emission"]
    numbers = np.array(rows[1:], dtype=float)
    return numbers[:, 0], numbers[:, 1], numbers[:, 2]


def _peak_and_width(nm: np.ndarray, values: np.ndarray, near: float) -> tuple[float, float]:
    """The band's maximum near `near` and its full width at half that maximum (linear interpolation of the edges)."""
    window = np.abs(nm - near) < 60
    peak_index = np.flatnonzero(window)[np.argmax(values[window])]
    half = values[peak_index] / 2
    left = peak_index
    while values[left] > half:
        left -= 1
    right = peak_index
    while values[right] > half:
        right += 1
    left_nm = np.interp(half, [values[left], values[left + 1]], [nm[left], nm[left + 1]])
    right_nm = np.interp(half, [values[right], values[right - 1]], [nm[right], nm[right - 1]])
    return float(nm[peak_index]), float(right_nm - left_nm)


def test_every_shipped_file_is_cited():
    assert fluorophore_names() == sorted(CITED)


@pytest.mark.parametrize("name", sorted(CITED))
def test_peaks_widths_and_yield_are_the_cited_values(name):
    excitation_peak, excitation_fwhm, emission_peak, emission_fwhm, quantum_yield = CITED[name]
    nm, excitation, emission = _file_columns(name)
    peak, width = _peak_and_width(nm, emission, emission_peak)
    assert peak == pytest.approx(emission_peak, abs=1)
    # the band is Gaussian in energy, so its width in nm differs from the cited one by a few per cent at most
    assert width == pytest.approx(emission_fwhm, rel=0.04)
    if excitation_peak is not None:
        peak, width = _peak_and_width(nm, excitation, excitation_peak)
        assert peak == pytest.approx(excitation_peak, abs=1)
        assert width == pytest.approx(excitation_fwhm, rel=0.04)
    else:  # a quantum dot absorbs everything bluer than its first exciton, and not its own emission
        assert excitation[nm == 450][0] > 0.95
        assert excitation[nm == emission_peak][0] < 0.1
    # a Stokes shift: emission redder than excitation
    assert np.average(nm, weights=emission) > np.average(nm, weights=excitation)
    fluorophore = load_fluorophore(name)
    assert fluorophore.quantum_yield == quantum_yield
    np.testing.assert_allclose(fluorophore.emission.values, np.interp(GRID_NM, nm, emission))


def test_emission_pdf_integrates_to_one_and_columns_are_library_spectra():
    yag = load_fluorophore("YAG_Ce")  # names are case-insensitive
    pdf = yag.emission_pdf()
    assert np.sum((pdf[1:] + pdf[:-1]) / 2) == pytest.approx(1.0, rel=1e-12)
    assert 540 < yag.mean_emission_nm() < 590
    assert library_spectrum("fluorescent/yag_ce:emission") == yag.emission
    # the brightener's excitation band lies mostly below the grid: the file reaches 300 nm and the spectrum keeps it
    brightener = load_fluorophore("stilbene_brightener")
    assert brightener.excitation.on_wavelengths(np.array([350.0]))[0] == pytest.approx(1.0)


def test_user_file_and_errors(tmp_path):
    good = tmp_path / "dye.csv"
    good.write_text("# quantum_yield: 0.5\nwavelength_nm,excitation,emission\n400,1,0\n500,0,1\n", encoding="utf-8")
    dye = load_fluorophore(str(good))
    assert dye.name == "dye" and dye.quantum_yield == 0.5
    with pytest.raises(SpectraceError, match="unknown fluorophore 'nope'.*fluorescein"):
        load_fluorophore("nope", where="materials.m.fluorophore")
    for text, message in (
        ("wavelength_nm,excitation,emission\n400,1,0\n500,0,1\n", "needs a '# quantum_yield"),
        ("# quantum_yield: 1.5\nwavelength_nm,excitation,emission\n400,1,0\n500,0,1\n", "in \\[0, 1\\]"),
        ("# quantum_yield: x\nwavelength_nm,excitation,emission\n400,1,0\n500,0,1\n", "got 'x'"),
        ("# quantum_yield: 1\nwavelength_nm,excitation\n400,1\n500,0\n", "unknown column 'emission'"),
        ("# quantum_yield: 1\nwavelength_nm,excitation,emission\n400,1,0\n500,0,0\n", "'emission' is zero"),
    ):
        bad = tmp_path / "bad.csv"
        bad.write_text(text, encoding="utf-8")
        with pytest.raises(SpectraceError, match=message) as error:
            load_fluorophore(str(bad))
        assert str(bad) in str(error.value) and "\n" not in str(error.value)


def test_the_files_are_what_their_writer_writes():
    """The files are written by tests/tooling/fluorescent_spectra.py from its table of cited values: a hand edit to a
    file, or a changed row not written out, fails here, naming the command that writes them."""
    from tests.tooling.fluorescent_spectra import FLUOROPHORES, file_text

    for item in FLUOROPHORES:
        written = (spectra_dir() / "fluorescent" / f"{item.name}.csv").read_text(encoding="utf-8")
        assert written == file_text(item), f"run `python -m tests.tooling.fluorescent_spectra` ({item.name})"
