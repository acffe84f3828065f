"""`fluorescent`: a bispectral surface, a fluorescent layer over a non-fluorescent `base` material. Light reaching
it at λ_in is re-emitted at longer wavelengths λ_out, diffusely, by the common parametric model (a separable
re-radiation or Donaldson matrix):

    f(λ_in → λ_out, ωi, ωo) = f_base(λ, ωi, ωo) δ(λ_in − λ_out) + a(λ_in) · Q · e(λ_out) · (λ_in / λ_out) / π

with a(λ) the fraction of photons absorbed by the dye at λ (its excitation spectrum, in [0, 1]), Q the quantum
yield (photons re-emitted per photon absorbed), e(λ) the emission spectrum normalised here to ∫ e dλ = 1 (a
distribution of the emitted photons over wavelength, 1/nm), and λ_in / λ_out the energy of an emitted photon
relative to an absorbed one (the Stokes shift's energy loss: photons are conserved, energy is not). The base
holds what is reflected without a change of wavelength, the diagonal of the Donaldson matrix: for a dyed surface it
is the surface's measured (non-fluorescent) reflectance, which already includes the dye's absorption, so that a
yield of 0 renders the base exactly. Energy is conserved where the base's albedo plus a(λ) stays within 1. A
measured matrix (`matrix`, spectrace.spectral.donaldson) gives a(λ)·Q and e(λ) when it is separable; one that is
not replaces a(λ_in)·Q·e(λ_out) by its own table D(λ_in, λ_out) (`FluorescentMaterial.matrix`,
kernels/fluorescence_matrix.cl). Its yield is in it, so Q then scales it.

It has no BSDF of its own: kernels/fluorescence.cl replaces it, where a path meets it, either by its base (the
elastic part) or by the Lambertian re-emission at a wavelength drawn from the excitation spectrum (the path's
wavelength changes there). Its row (kernels/types.h) holds the base's row index in `eta_offset` and that of a
white Lambertian row (the re-emission's lobe) in `k_offset`; `reflectance_offset` the excitation a(λ),
`transmittance_offset` the normalised emission e(λ) and, a row on, its CDF, `coat_table_offset` the CDF of
a(λ)·λ over the spectrum table's grid (the excitation wavelength's sampling density), `coat_internal_reflectance`
∫ a dλ (nm), `alpha` Q (a textured Q: its largest value, the texture in `roughness_texture`), `ior_model` a
non-separable matrix's block in the spectra table (MATERIAL_NO_SPECTRUM: none).
spectrace.materials appends the two rows after it. The path tracer, the light tracer, BDPT
(kernels/bdpt_fluorescence.cl) and the local model (`direct`, the dye's re-emission of direct light) transport light
through it; the other integrators refuse a scene holding one (`integrator_problem`).
"""

from dataclasses import dataclass, field

import numpy as np

from spectrace.core.contract import MATERIAL_NO_SPECTRUM
from spectrace.core.parameters import Parameter, Range, reflectance
from spectrace.errors import SpectraceError
from spectrace.materials.base import Material
from spectrace.spectral.donaldson import TabulatedMatrix, device_block
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

NAME = "fluorescent"
# No bsdf_fluorescent.cl: the material is resolved at each vertex before any BSDF is called (kernels/fluorescence.cl).
COMPOSITE = True
KERNEL_FILE = "fluorescence.cl"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no fluorescent BSDF: each of its wavelengths is transported independently"
PBRT_MATERIALS: tuple[str, ...] = ()
PBRT_NONE = "pbrt-v4 has no fluorescent material: each of its wavelengths is transported independently"
# The Material row fields holding the base's row index and the re-emission lobe's.
ROW_FIELDS = ("eta_offset", "k_offset")
# The integrators that transport light through a change of wavelength.
INTEGRATORS = ("path", "light", "bdpt", "direct")
YIELD_RANGE = Range(0.0, 1.0)
PARAMETERS = (
    Parameter(
        "base",
        "material",
        doc="the non-fluorescent material under the dye, by name ([materials.NAME] of this file): what is reflected "
        "without a change of wavelength",
        type_doc="material name",
    ),
    reflectance(
        None,
        "a(λ), the fraction of the photons arriving at λ that the dye absorbs (required without `matrix`)",
        name="excitation",
    ),
    Parameter(
        "emission",
        "spectrum",
        default=None,
        range=Range(0.0, None),
        doc="e(λ), the spectrum of the re-emitted photons (its shape only: it is normalised to ∫ e dλ = 1; required "
        "without `matrix`)",
    ),
    Parameter(
        "quantum_yield",
        "float",
        default=1.0,
        range=YIELD_RANGE,
        doc="Q, photons re-emitted per photon absorbed (a grey texture: the dye's yield, or its concentration, "
        "varying over the surface); with `matrix`, a factor on the matrix, which holds the yield already",
        textured=True,
        texture_field="roughness_texture",
    ),
    Parameter(
        "matrix",
        "string",
        default=None,
        doc="a measured re-radiation (Donaldson) matrix, a CSV file (rows λ_in, columns λ_out, photons re-emitted "
        "per nm per photon arriving), instead of excitation and emission; separable or not",
        type_doc="file",
    ),
)
_YIELD = PARAMETERS[3]


@dataclass(frozen=True)
class FluorescentMaterial(Material):
    """A fluorescent dye (excitation a(λ), emission e(λ), quantum yield Q) over a non-fluorescent base."""

    base: Material
    excitation: Spectrum
    emission: Spectrum
    quantum_yield: object = 1.0  # a float in [0, 1], or a one-channel texture of it
    key: str = field(default="", compare=False)  # where the scene file defined it, for the integrators' refusals
    # A non-separable re-radiation matrix, which the device renders instead of excitation ⊗ emission (these two
    # then its row and column totals); None for the parametric (separable) dye.
    matrix: TabulatedMatrix | None = None

    @property
    def is_delta(self) -> bool:
        return False

    @property
    def has_transmission(self) -> bool:
        return bool(self.base.has_transmission)

    @property
    def is_dispersive(self) -> bool:
        return bool(self.base.is_dispersive)

    @property
    def is_diffuse(self) -> bool:
        return bool(self.base.is_diffuse)


MODEL = FluorescentMaterial


def check(base, excitation, emission, quantum_yield, where, key: str = "", matrix=None) -> FluorescentMaterial:
    """The fluorescent material, or a SpectraceError naming the key (`where(name)`): a non-fluorescent base
    (a mix of such materials included), an excitation in [0, 1], an emission that is not zero everywhere."""
    from spectrace.materials import mix

    if not isinstance(base, Material):
        raise SpectraceError("base must be a material", where=where("base"))
    if _holds_fluorescent(base):
        raise SpectraceError("the base of a fluorescent material must not fluoresce itself", where=where("base"))
    if mix.depth(base) >= mix.MAX_DEPTH:
        raise SpectraceError(f"a base mix nests at most {mix.MAX_DEPTH - 1} deep", where=where("base"))
    for name, spectrum in (("excitation", excitation), ("emission", emission)):
        if not isinstance(spectrum, Spectrum):
            raise SpectraceError(f"{name} must be a spectrum", where=where(name))
        if np.any(spectrum.values < 0):
            raise SpectraceError("spectrum has negative values", where=where(name))
    if np.any(excitation.values > 1.0 + 1e-6):
        raise SpectraceError(
            f"excitation exceeds 1 (max {excitation.values.max():.4g}): it is a fraction absorbed",
            where=where("excitation"),
        )
    if not np.any(emission.values > 0):
        raise SpectraceError("emission is zero at every wavelength", where=where("emission"))
    from spectrace.textures import check_texture_values, is_texture

    if is_texture(quantum_yield):
        check_texture_values(quantum_yield, "float", where("quantum_yield"), upper=1.0)
    else:
        quantum_yield = _YIELD.check(quantum_yield, where("quantum_yield"))
    return FluorescentMaterial(base, excitation, emission, quantum_yield, key=key, matrix=matrix)


def _holds_fluorescent(material) -> bool:
    from spectrace.materials import mix

    if isinstance(material, FluorescentMaterial):
        return True
    return isinstance(material, mix.MixMaterial) and any(_holds_fluorescent(m) for m in material.materials)


def from_spec(spec, resolver, key: str) -> FluorescentMaterial:
    base = resolver.material_named(spec.base, f"{key}.base")
    matrix = None
    if spec.matrix is not None:
        excitation, emission, matrix = matrix_spectra(resolver.folder / spec.matrix, resolver.where(f"{key}.matrix"))
    else:
        excitation = resolver.spectrum(spec.excitation, f"{key}.excitation", emission=False)
        emission = resolver.spectrum(spec.emission, f"{key}.emission", emission=True)
    quantum_yield = spec.quantum_yield
    if not isinstance(quantum_yield, float):
        quantum_yield = resolver.texture(quantum_yield, f"{key}.quantum_yield")
    return check(base, excitation, emission, quantum_yield, lambda name: resolver.where(f"{key}.{name}"), key, matrix)


def matrix_spectra(path, where: str | None = None) -> tuple[Spectrum, Spectrum, TabulatedMatrix | None]:
    """The excitation a(λ)·Q and the emission e(λ) of a re-radiation (Donaldson) matrix CSV
    (spectrace.spectral.donaldson), and the matrix itself where it is not separable; its errors, which name the
    file, also name `where`."""
    from spectrace.spectral.donaldson import donaldson_matrix

    try:
        measured = donaldson_matrix(path)
    except SpectraceError as exc:
        raise SpectraceError(str(exc), where=where) from None
    return measured.excitation, measured.emission, measured.tabulated


def make(base, excitation=None, emission=None, quantum_yield=1.0, matrix=None) -> FluorescentMaterial:
    """A fluorescent dye over `base` (a non-fluorescent material): photons arriving at λ_in are absorbed with
    probability `excitation` a(λ_in) and re-emitted, `quantum_yield` of them, diffusely at λ_out distributed as
    `emission` (its shape only). Spectra as every material takes them (a Spectrum, a constant, a name); the yield a
    number in [0, 1] or a grey texture of it. Or, instead of the two spectra, `matrix`: the path of a measured
    re-radiation (Donaldson) matrix CSV (rows λ_in, columns λ_out, photons re-emitted per nm of λ_out per photon
    arriving at λ_in; spectrace.spectral.donaldson, separable or not), which holds the yield already:
    `quantum_yield` scales it."""
    from spectrace.spectral.spectrum_input import role_spectrum

    if matrix is not None:
        if excitation is not None or emission is not None:
            raise SpectraceError("give either matrix or excitation and emission, not both", where="matrix")
        excitation, emission, tabulated = matrix_spectra(matrix, "matrix")
        return check(base, excitation, emission, quantum_yield, lambda name: name, matrix=tabulated)
    if excitation is None or emission is None:
        raise SpectraceError(
            "a fluorescent material needs excitation and emission, or a matrix",
            where="excitation" if excitation is None else "emission",
        )
    excitation = role_spectrum(excitation, False, "excitation")
    emission = role_spectrum(emission, True, "emission")
    return check(base, excitation, emission, quantum_yield, lambda name: name)


def cell_cdf(weighted: np.ndarray, wavelengths_nm: np.ndarray) -> np.ndarray:
    """The CDF, at each grid wavelength, of the density ∝ `weighted` that is constant over each 1 nm cell (its value
    the cell's mean of the grid values): the kernel picks a cell by it and a point uniformly within the cell."""
    weighted = np.asarray(weighted, np.float64)
    cells = 0.5 * (weighted[1:] + weighted[:-1]) * np.diff(wavelengths_nm)
    cdf = np.concatenate([[0.0], np.cumsum(cells)])
    total = cdf[-1]
    if not total > 0.0:
        return cdf
    cdf /= total
    cdf[-1] = 1.0
    return cdf


def write_row(row: np.ndarray, material: FluorescentMaterial, table: SpectrumTable) -> None:
    # The base's and the re-emission lobe's row indices (ROW_FIELDS) are written by spectrace.materials once their
    # rows are placed.
    grid = table.wavelengths_nm
    excitation = material.excitation.on_wavelengths(grid)
    emission = np.clip(material.emission.on_wavelengths(grid, extend_rgb=table.extend_rgb), 0.0, None)
    emission_total = float(np.trapezoid(emission, grid))
    absorbed_total = float(np.trapezoid(excitation, grid))
    row["reflectance_offset"] = table.add_block(excitation)
    # Zero emission within the film's range: nothing is re-emitted where the film sees. Its CDF follows it, one row
    # on (the light tracer draws the re-emitted wavelength by it).
    emission = emission / emission_total if emission_total > 0 else emission
    row["transmittance_offset"] = table.add_block(np.concatenate([emission, cell_cdf(emission, grid)]))
    row["coat_table_offset"] = table.add_block(cell_cdf(excitation * grid, grid))
    row["coat_internal_reflectance"] = absorbed_total
    absorbs = absorbed_total > 0.0 and emission_total > 0.0
    row["ior_model"] = MATERIAL_NO_SPECTRUM
    if material.matrix is not None:
        block = device_block(material.matrix, grid)
        absorbs = block is not None
        if block is not None:
            row["ior_model"] = table.add_block(block)
    # A textured yield stands here as its largest value (material_row): 0 only where the texture is 0 everywhere.
    row["alpha"] = float(material.quantum_yield) if absorbs else 0.0  # type: ignore[arg-type]


def reemission_lobe() -> Material:
    """The white Lambertian lobe of the re-emission (its factors are the path's, kernels/fluorescence.cl)."""
    from spectrace.materials.diffuse import DiffuseMaterial

    return DiffuseMaterial(Spectrum.constant(1.0, name="fluorescent re-emission"))


def surface_detail_problem(material: FluorescentMaterial) -> str | None:
    """Why the material's own surface detail cannot be honoured, or None: a normal or bump map belongs to its base."""
    detail = material.detail
    if detail is not None and (getattr(detail, "normal_map", None) is not None or getattr(detail, "bump_map", None)):
        return "a fluorescent material takes no normal or bump map of its own; give them to its base"
    return None


def check_spec(spec) -> None:
    if spec.normal_map is not None or spec.bump_map is not None:
        raise ValueError("a fluorescent material takes no normal or bump map of its own; give them to its base")
    spectra = [name for name in ("excitation", "emission") if getattr(spec, name) is not None]
    if spec.matrix is not None and spectra:
        raise ValueError(f"give either matrix or excitation and emission, not both ({', '.join(spectra)} given)")
    if spec.matrix is None and len(spectra) < 2:
        raise ValueError("a fluorescent material needs excitation and emission, or a matrix")


SPEC_CHECKS = (check_spec,)


def fluorescent_materials(scene) -> list[FluorescentMaterial]:
    """The fluorescent materials of `scene`'s shapes and instanced objects (within mixes too), in order."""
    from spectrace.materials import mix

    found: list[FluorescentMaterial] = []

    def visit(material) -> None:
        if isinstance(material, FluorescentMaterial) and material not in found:
            found.append(material)
        elif isinstance(material, mix.MixMaterial):
            for part in material.materials:
                visit(part)

    for shape in scene.every_shape:
        visit(shape.material)
    return found


def integrator_problem(scene, integrator: str) -> str | None:
    """Why `integrator` cannot render `scene`'s fluorescent materials (it transports each wavelength on its own),
    or None."""
    if integrator in INTEGRATORS:
        return None
    materials = fluorescent_materials(scene)
    if not materials:
        return None
    where = materials[0].key or "a material"
    return (
        f"integrator '{integrator}' does not transport light through a change of wavelength ({where} is "
        f"fluorescent); use integrator " + ", ".join(f"'{name}'" for name in INTEGRATORS)
    )
