"""`hair`: the fibre scattering model of Chiang, Bitterli, Tappan & Burley 2016, as pbrt-v4's `hair` material
(docs/materials.md, kernels/bsdf_hair.cl). The fibre's absorption is given as `sigma_a`, as melanin concentrations
or as the colour a fibre should have (the paper's inversion); the surface's dp/du is the fibre's direction and its
v texture coordinate the offset across it (h = 2v − 1)."""

import math
from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.errors import SpectraceError
from spectrace.materials.base import Material
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.spectral.uplift import uplift_unbounded

NAME = "hair"
MITSUBA_PLUGINS = ("hair",)
PBRT_MATERIALS = ("hair",)

# The absorption of a unit concentration of each melanin per unit fibre radius, in linear sRGB (the paper's sec.
# 4.1, after d'Eon et al. 2011).
EUMELANIN_RGB = (0.419, 0.697, 1.37)
PHEOMELANIN_RGB = (0.187, 0.4, 1.05)
# Eumelanin where no absorption is given: a brown fibre, pbrt-v4's default.
DEFAULT_EUMELANIN = 1.3
# Reflectances below this are read as it: the inversion's σa grows without bound toward black.
MIN_REFLECTANCE = 1e-4

PARAMETERS = (
    Parameter(
        "sigma_a",
        "spectrum",
        "1/radius",
        default=None,
        range=Range(0.0),
        doc="absorption of the fibre's interior per unit fibre radius (an rgb is uplifted as an absorption); give "
        "at most one of sigma_a, reflectance, eumelanin/pheomelanin (none: eumelanin 1.3)",
    ),
    reflectance(
        None,
        "the colour the fibre should have after multiple scattering: σa(λ) = (ln c(λ) / (5.969 − 0.215 βn + "
        "2.532 βn² − 10.73 βn³ + 5.574 βn⁴ + 0.245 βn⁵))², the paper's inversion, per wavelength",
        default_doc="—",
    ),
    Parameter(
        "eumelanin",
        "float",
        "dimensionless",
        default=None,
        range=Range(0.0),
        default_doc="—",
        doc="eumelanin concentration (brown-black): σa = eumelanin · σ_eu + pheomelanin · σ_pheo, σ_eu the linear "
        "sRGB absorption (0.419, 0.697, 1.37), σ_pheo (0.187, 0.4, 1.05), uplifted",
    ),
    Parameter(
        "pheomelanin",
        "float",
        "dimensionless",
        default=None,
        range=Range(0.0),
        default_doc="—",
        doc="pheomelanin concentration (red-yellow)",
    ),
    Parameter("eta", "float", "dimensionless", 1.55, Range(1.0, low_open=True), doc="fibre index of refraction"),
    Parameter("beta_m", "float", "dimensionless", 0.3, Range(0.0, 1.0, low_open=True), doc="longitudinal roughness"),
    Parameter("beta_n", "float", "dimensionless", 0.3, Range(0.0, 1.0, low_open=True), doc="azimuthal roughness"),
    Parameter("alpha", "float", "degrees", 2.0, Range(-90.0, 90.0), doc="tilt of the cuticle's scales"),
)
_PARAMETER = {p.name: p for p in PARAMETERS}


@dataclass(frozen=True)
class HairMaterial(Material):
    """A fibre of index `eta` absorbing `sigma_a` per unit radius, longitudinal and azimuthal roughness `beta_m`,
    `beta_n`, scales tilted by `alpha` degrees."""

    sigma_a: Spectrum
    eta: float = 1.55
    beta_m: float = 0.3
    beta_n: float = 0.3
    alpha: float = 2.0

    is_delta = False
    has_transmission = True
    is_dispersive = False


MODEL = HairMaterial


def melanin_sigma_a(eumelanin: float, pheomelanin: float) -> Spectrum:
    """σa of the given melanin concentrations: the uplift of the paper's linear sRGB absorption."""
    rgb = eumelanin * np.array(EUMELANIN_RGB) + pheomelanin * np.array(PHEOMELANIN_RGB)
    return uplift_unbounded(rgb)


def reflectance_sigma_a(colour: Spectrum, beta_n: float) -> Spectrum:
    """σa whose fibre, after multiple scattering, shows reflectance `colour` (the paper's eq. 9, per wavelength)."""
    b = beta_n
    denominator = 5.969 - 0.215 * b + 2.532 * b**2 - 10.73 * b**3 + 5.574 * b**4 + 0.245 * b**5
    values = (np.log(np.clip(colour.values, MIN_REFLECTANCE, 1.0)) / denominator) ** 2
    return Spectrum(values, name=colour.name, source="hair reflectance inverted to σa (Chiang et al. 2016)")


def source_problem(sigma_a, colour, eumelanin, pheomelanin) -> str | None:
    """Why more than one way of giving the absorption is given, or None."""
    given = [
        name
        for name, value in (("sigma_a", sigma_a), ("reflectance", colour), ("eumelanin/pheomelanin", eumelanin))
        if value is not None
    ]
    if pheomelanin is not None and eumelanin is None:
        given.append("eumelanin/pheomelanin")
    given = list(dict.fromkeys(given))
    if len(given) > 1:
        return f"give one of sigma_a, reflectance or eumelanin/pheomelanin, not {' and '.join(given)}"
    return None


def check_spec(spec) -> None:
    if problem := source_problem(spec.sigma_a, spec.reflectance, spec.eumelanin, spec.pheomelanin):
        raise ValueError(problem)


SPEC_CHECKS = (check_spec,)


def _absorption(sigma_a, colour, eumelanin, pheomelanin, beta_n: float) -> Spectrum:
    if sigma_a is not None:
        return sigma_a
    if colour is not None:
        return reflectance_sigma_a(colour, beta_n)
    if eumelanin is None and pheomelanin is None:
        eumelanin = DEFAULT_EUMELANIN
    return melanin_sigma_a(eumelanin or 0.0, pheomelanin or 0.0)


def from_spec(spec, resolver, key: str) -> HairMaterial:
    sigma_a = None
    if spec.sigma_a is not None:
        if spec.sigma_a.rgb is not None:
            sigma_a = uplift_unbounded(spec.sigma_a.rgb, where=resolver.where(f"{key}.sigma_a"))
        else:
            sigma_a = spectrum_input.within_bounds(
                resolver.spectrum(spec.sigma_a, f"{key}.sigma_a", emission=True), True, resolver.where(f"{key}.sigma_a")
            )
    colour = resolver.spectrum(spec.reflectance, f"{key}.reflectance", emission=False) if spec.reflectance else None
    absorption = _absorption(sigma_a, colour, spec.eumelanin, spec.pheomelanin, spec.beta_n)
    return HairMaterial(absorption, eta=spec.eta, beta_m=spec.beta_m, beta_n=spec.beta_n, alpha=spec.alpha)


def make(
    sigma_a: SpectrumLike | None = None,
    *,
    reflectance: SpectrumLike | None = None,
    eumelanin: float | None = None,
    pheomelanin: float | None = None,
    eta: float = 1.55,
    beta_m: float = 0.3,
    beta_n: float = 0.3,
    alpha: float = 2.0,
) -> HairMaterial:
    """A hair fibre (Chiang et al. 2016): its absorption as `sigma_a` (per unit fibre radius; an RGB triple is
    uplifted as an absorption), as the `reflectance` its fibres should show, or as `eumelanin` and `pheomelanin`
    concentrations (none given: eumelanin 1.3); `eta` its index, `beta_m`, `beta_n` its longitudinal and azimuthal
    roughness in (0, 1], `alpha` its scales' tilt in degrees. On a surface, dp/du runs along the fibre and the v
    texture coordinate across it."""
    if problem := source_problem(sigma_a, reflectance, eumelanin, pheomelanin):
        raise SpectraceError(problem)
    numbers = {
        name: _PARAMETER[name].check(value)
        for name, value in (("eta", eta), ("beta_m", beta_m), ("beta_n", beta_n), ("alpha", alpha))
    }
    for name, value in (("eumelanin", eumelanin), ("pheomelanin", pheomelanin)):
        if value is not None:
            _PARAMETER[name].check(value)
    absorption = None
    if sigma_a is not None:
        absorption = (
            uplift_unbounded(sigma_a, where="sigma_a")  # type: ignore[arg-type]
            if spectrum_input.is_rgb(sigma_a)
            else spectrum_input.within_bounds(spectrum_input.spectrum(sigma_a), True, "sigma_a")
        )
    colour = spectrum_input.reflectance(reflectance, "reflectance") if reflectance is not None else None
    return HairMaterial(_absorption(absorption, colour, eumelanin, pheomelanin, numbers["beta_n"]), **numbers)


# Mitsuba 3's `hair` parameters that are spectrace's under another name.
_MITSUBA_NAMES = {"longitudinal_roughness": "beta_m", "azimuthal_roughness": "beta_n", "scale_tilt": "alpha"}


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba 3's `hair` (the same paper): `sigma_a` times `scale`, else `eumelanin` (default 1.3) and `pheomelanin`
    (default 0.2, where pbrt-v4 has 0); int_ior / ext_ior (amber / air) as `eta`; its roughnesses and scale tilt.
    Mitsuba takes h from ωo and the normal (a cylinder's entry point), spectrace from the v coordinate: the same on
    a curve, where the normal is the fibre's."""
    named = importer.NAMED_IOR
    table: dict = {"type": NAME}
    table["eta"] = importer.ior(bsdf, properties, "int_ior", named["amber"]) / importer.ior(
        bsdf, properties, "ext_ior", named["air"]
    )
    if "sigma_a" in properties:
        if "eumelanin" in properties or "pheomelanin" in properties:
            raise importer.fail(bsdf, "hair: give sigma_a or eumelanin/pheomelanin, not both")
        if importer.resolve(properties["sigma_a"]).tag == "texture":
            importer.unsupported_plugin(bsdf, " with a textured sigma_a")
            return None
        sigma_a = importer.spectrum(properties["sigma_a"], "sigma_a")
        if sigma_a is None:
            return None
        scale = importer.number(properties["scale"]) if "scale" in properties else 1.0
        if scale != 1.0:
            if "value" in sigma_a:
                sigma_a = {"value": sigma_a["value"] * scale}
            elif "rgb" in sigma_a:
                sigma_a = {"rgb": [c * scale for c in sigma_a["rgb"]]}
            else:
                raise importer.fail(bsdf, f"hair: scale {scale:g} on a sigma_a that is no number or rgb")
        table["sigma_a"] = sigma_a
    else:
        table["eumelanin"] = importer.number(properties["eumelanin"]) if "eumelanin" in properties else 1.3
        table["pheomelanin"] = importer.number(properties["pheomelanin"]) if "pheomelanin" in properties else 0.2
    for theirs, ours in _MITSUBA_NAMES.items():
        if theirs in properties:
            table[ours] = importer.number(properties[theirs])
    for key in ("eta", "eumelanin", "pheomelanin", "beta_m", "beta_n", "alpha"):
        if key in table and (problem := _PARAMETER[key].range_problem(table[key])):
            raise importer.fail(bsdf, f"hair: {problem}")
    return table


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's HairMaterial: `sigma_a`, else `reflectance`, else `eumelanin` (default 1.3) and `pheomelanin`;
    `eta` 1.55, `beta_m` 0.3, `beta_n` 0.3, `alpha` 2 degrees, as here."""
    table: dict = {"type": "hair"}
    sigma_a = context.spectrum(material, "sigma_a", "unbounded")
    colour = context.spectrum(material, "reflectance", "albedo")
    if sigma_a is not None:
        table["sigma_a"] = sigma_a
    elif colour is not None:
        table["reflectance"] = colour
    else:
        table["eumelanin"] = context.one(material, "eumelanin", DEFAULT_EUMELANIN)
        pheomelanin = context.one(material, "pheomelanin", 0.0)
        if pheomelanin:
            table["pheomelanin"] = pheomelanin
    for key, default in (("eta", 1.55), ("beta_m", 0.3), ("beta_n", 0.3), ("alpha", 2.0)):
        value = context.one(material, key, default)
        if problem := _PARAMETER[key].range_problem(value):
            raise context.error(material.location, f"hair {problem}")
        table[key] = value
    return table


def write_row(row: np.ndarray, material: HairMaterial, table: SpectrumTable) -> None:
    """σa in the reflectance slot, η in `ior`, (β_m, β_n, α in radians) in ior_coefficients_b, and a frame along
    dp/du: the fibre's direction (kernels/bsdf_hair.cl)."""
    row["reflectance_offset"] = table.add(material.sigma_a)
    row["ior"] = material.eta
    row["ior_coefficients_b"] = (material.beta_m, material.beta_n, math.radians(material.alpha), 0.0)
    row["tangent_frame"] = 1
