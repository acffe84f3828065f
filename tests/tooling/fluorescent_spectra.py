"""Writes spectra/fluorescent/*.csv from the published band positions, widths and quantum yields listed here.

Run `python -m tests.tooling.fluorescent_spectra` after changing a row. No measured fluorescence table with an open
licence was at hand, so each spectrum is the common parametrisation of an electronic band: a Gaussian in photon
energy (wavenumber ν = 10⁷/λ) with its peak at the cited wavelength and its full width at half maximum, given in nm
at the peak, converted as Δν = 10⁷ Δλ / λ_peak². A quantum dot absorbs everything bluer than its first exciton, so
its excitation is a step in wavenumber (a logistic) instead of a band. tests/spectral/test_fluorophores.py measures
the written files' peaks and widths and compares them with the cited values, which it holds itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spectrace.resources import spectra_dir

FOLDER = "fluorescent"
WAVELENGTHS_NM = np.arange(300.0, 831.0, 1.0)


@dataclass(frozen=True)
class Band:
    peak_nm: float
    fwhm_nm: float
    weight: float = 1.0

    def text(self) -> str:
        weight = "" if self.weight == 1.0 else f" × {self.weight:g}"
        return f"Gaussian in wavenumber, peak {self.peak_nm:g} nm, FWHM {self.fwhm_nm:g} nm{weight}"

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        peak = 1e7 / self.peak_nm
        width = 1e7 * self.fwhm_nm / self.peak_nm**2
        return self.weight * np.exp(-4.0 * math.log(2.0) * ((1e7 / nm - peak) / width) ** 2)


@dataclass(frozen=True)
class Edge:
    """Absorption of a quantum dot: 1/2 at `half_nm`, rising toward the blue over `width_nm` (logistic scale)."""

    half_nm: float
    width_nm: float

    def text(self) -> str:
        half, scale = f"{self.half_nm:g}", f"{self.width_nm:g}"
        return f"absorption edge, logistic in wavenumber, half height at {half} nm, scale {scale} nm"

    def __call__(self, nm: np.ndarray) -> np.ndarray:
        scale = 1e7 * self.width_nm / self.half_nm**2
        return 1.0 / (1.0 + np.exp(-(1e7 / nm - 1e7 / self.half_nm) / scale))


@dataclass(frozen=True)
class Fluorophore:
    name: str
    title: str
    excitation: tuple[Band | Edge, ...]
    emission: tuple[Band, ...]
    quantum_yield: float
    yield_source: str
    band_source: str


MAGDE_2002 = (
    "D. Magde, R. Wong, P. G. Seybold, 'Fluorescence quantum yields and their relation to lifetimes of rhodamine 6G "
    "and fluorescein in nine solvents', Photochem. Photobiol. 75(4), 327-334 (2002)"
)
SJOBACK_1995 = (
    "R. Sjöback, J. Nygren, M. Kubista, 'Absorption and fluorescence properties of fluorescein', Spectrochim. Acta A "
    "51(6), L7-L21 (1995)"
)
WOLFBEIS_1983 = (
    "O. S. Wolfbeis, E. Fürlinger, H. Kroneis, H. Marsoner, 'Fluorimetric analysis 1. A study on fluorescent "
    "indicators for measuring near neutral (physiological) pH values', Fresenius Z. Anal. Chem. 314, 119-124 (1983)"
)
BARNADAS_2008 = (
    "R. Barnadas-Rodríguez, J. Estelrich, 'Effect of salts on the excited state of pyranine as determined by "
    "steady-state fluorescence', J. Photochem. Photobiol. A 198, 262-267 (2008): the phenolate's emission at 511 nm"
)
SMET_2011 = (
    "P. F. Smet, A. B. Parmentier, D. Poelman, 'Selecting conversion phosphors for white light-emitting diodes', "
    "J. Electrochem. Soc. 158(6), R37-R54 (2011)"
)
DABBOUSI_1997 = (
    "B. O. Dabbousi et al., '(CdSe)ZnS core-shell quantum dots: synthesis and characterization of a size series of "
    "highly luminescent nanocrystallites', J. Phys. Chem. B 101(46), 9463-9475 (1997)"
)
WON_2019 = (
    "Y.-H. Won et al., 'Highly efficient and stable InP/ZnSe/ZnS quantum dot light-emitting diodes', Nature 575, "
    "634-638 (2019)"
)
WIDTHS = "widths approximate (±10 nm), read from the published spectra's shapes; the papers tabulate peaks, not widths"

FLUOROPHORES = (
    Fluorophore(
        "fluorescein",
        "fluorescein dianion in 0.1 M NaOH (the dye of green highlighters and leak tracers)",
        (Band(490, 35),),
        (Band(514, 40),),
        0.925,
        f"{MAGDE_2002}: 0.925 ± 0.015 in 0.1 M NaOH",
        f"peaks {SJOBACK_1995}; {WIDTHS}",
    ),
    Fluorophore(
        "rhodamine6g",
        "rhodamine 6G in ethanol (laser dye; pink/orange fluorescent inks)",
        (Band(530, 35),),
        (Band(552, 40),),
        0.95,
        f"{MAGDE_2002}: 0.950 ± 0.015 in ethanol",
        f"peaks {MAGDE_2002}; {WIDTHS}",
    ),
    Fluorophore(
        "pyranine",
        "pyranine (HPTS, 8-hydroxypyrene-1,3,6-trisulfonate), basic form in water (the dye of yellow highlighters)",
        (Band(454, 45),),
        (Band(511, 50),),
        1.0,
        f"{WOLFBEIS_1983}: near unity for the phenolate form",
        f"peaks {WOLFBEIS_1983}; {BARNADAS_2008}; {WIDTHS}",
    ),
    Fluorophore(
        "stilbene_brightener",
        "optical brightener, 4,4'-diaminostilbene-2,2'-disulfonic acid type (white paper, detergents)",
        (Band(350, 50),),
        (Band(435, 60),),
        0.7,
        "ASSUMED: no published yield for the class as a whole was found; 0.7 is a placeholder",
        "the class's typical absorption (about 350 nm) and emission (about 435 nm) maxima; widths approximate (±15 nm)",
    ),
    Fluorophore(
        "yag_ce",
        "YAG:Ce phosphor, Y3Al5O12:Ce3+ (the yellow converter of white LEDs)",
        (Band(455, 60), Band(340, 40, 0.35)),
        (Band(555, 115),),
        0.9,
        f"{SMET_2011}: quantum efficiency about 0.9 for commercial YAG:Ce",
        f"{SMET_2011}: excitation bands near 455 nm and 340 nm (the second weaker), broad emission peaking "
        "550-560 nm; widths approximate (±15 nm), the emission's two Ce3+ components merged into one band",
    ),
    Fluorophore(
        "cdse_qd_green",
        "CdSe/ZnS core-shell quantum dots emitting green",
        (Edge(505, 8),),
        (Band(530, 30),),
        0.5,
        f"{DABBOUSI_1997}: 0.3-0.5 for (CdSe)ZnS; the upper value",
        f"{DABBOUSI_1997}: size-tuned emission, FWHM below 40 nm; absorption rises from the first exciton, "
        "modelled as an edge 25 nm bluer than the emission peak",
    ),
    Fluorophore(
        "cdse_qd_red",
        "CdSe/ZnS core-shell quantum dots emitting red",
        (Edge(605, 8),),
        (Band(630, 30),),
        0.5,
        f"{DABBOUSI_1997}: 0.3-0.5 for (CdSe)ZnS; the upper value",
        f"{DABBOUSI_1997}: size-tuned emission, FWHM below 40 nm; absorption edge 25 nm bluer than the emission",
    ),
    Fluorophore(
        "inp_qd_red",
        "InP/ZnSe/ZnS quantum dots emitting red (cadmium-free display QDs)",
        (Edge(605, 8),),
        (Band(630, 35),),
        1.0,
        f"{WON_2019}: near 100 %",
        f"{WON_2019}: emission 630 nm, FWHM 35 nm; absorption edge 25 nm bluer than the emission",
    ),
)


def _curve(parts, nm: np.ndarray) -> np.ndarray:
    values = sum(part(nm) for part in parts)
    return values / values.max()


def file_text(item: Fluorophore) -> str:
    lines = [
        f"# {item.title}",
        "# excitation: relative excitation efficiency (absorption of the emitting species), peak 1, dimensionless",
        "# emission: relative photon emission per nm (a quantum spectrum), peak 1",
        f"# quantum_yield: {item.quantum_yield:g}",
        f"# quantum_yield_source: {item.yield_source}",
        f"# band_source: {item.band_source}",
        "# excitation_model: " + " + ".join(part.text() for part in item.excitation),
        "# emission_model: " + " + ".join(part.text() for part in item.emission),
        "# sampling: 300-830 nm, 1 nm, written by tests/tooling/fluorescent_spectra.py",
        "wavelength_nm,excitation,emission",
    ]
    excitation = _curve(item.excitation, WAVELENGTHS_NM)
    emission = _curve(item.emission, WAVELENGTHS_NM)
    lines += [f"{nm:g},{a:.6f},{e:.6f}" for nm, a, e in zip(WAVELENGTHS_NM, excitation, emission)]
    return "\n".join(lines) + "\n"


def main() -> None:
    folder = spectra_dir() / FOLDER
    folder.mkdir(exist_ok=True)
    for item in FLUOROPHORES:
        (folder / f"{item.name}.csv").write_text(file_text(item), encoding="utf-8")
        print(f"wrote {folder.name}/{item.name}.csv")


if __name__ == "__main__":
    main()
