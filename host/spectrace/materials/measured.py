"""`measured`: a BRDF measured by the RGL material database (rgl.epfl.ch/materials), read from its spectral `.bsdf`
file, in the adaptive parameterisation of Dupuy & Jakob 2018 ("An Adaptive Parameterization for Efficient
Material Acquisition and Rendering", ACM Trans. Graph. 37(6)), as Mitsuba 3's and pbrt-v4's `measured` read it
(docs/materials.md, kernels/bsdf_measured.cl).

The file (a tensor file, spectrace.io.tensor_file) holds, over the viewer's direction ωo (angles θo `theta_i`, φo
`phi_i`; one φo for an isotropic material): the microfacet distribution D (`ndf`) and its projected area σ (`sigma`)
on the square u = (√(2θ/π), φ/2π + ½); per ωo the visible-normal distribution (`vndf`) in that square, a 2-D table
whose inverse sampling map takes the square of microfacet normals to the unit square of the measurement; and on
that unit square the BRDF's spectra (`spectra`, one table per wavelength of `wavelengths`, in nm) and their
luminance (`luminance`, which sampling follows). The BRDF is
    f(ωo, ωi) cos θi = R(s, λ) D(ωm) / (4 σ(ωo)),   ωm the half vector, s the measurement's point of ωm,
with R interpolated linearly between the file's wavelengths at each path wavelength: the measured spectra are
used as spectra. Files with RGB data (`_rgb.bsdf`, an `rgb` field in place of `wavelengths` and `spectra`) are
refused: they are a projection of the same measurement, whose `_spec` file renders it without loss.

On the device the tables and the sampling tables of their interpolants (Mitsuba's continuous Marginal2D: a
bilinear density, its rows' and its marginal's integrals) are one block of the spectrum table (Material.eta_offset),
its layout in HEADER."""

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from spectrace.core.equality import fields_equal
from spectrace.core.parameters import REQUIRED, Parameter
from spectrace.errors import SpectraceError
from spectrace.io.tensor_file import read_tensor_file
from spectrace.materials.base import Material
from spectrace.spectral.table import SpectrumTable

NAME = "measured"
MITSUBA_PLUGINS = ("measured",)
PBRT_MATERIALS = ("measured",)

PARAMETERS = (
    Parameter(
        "filename",
        "string",
        "",
        REQUIRED,
        doc="an RGL material database's spectral measurement (`*_spec.bsdf`), relative to the scene file; an RGB "
        "one (`*_rgb.bsdf`) is refused",
    ),
)

# The block's header: int32 fields (stored as their bits), offsets counted from the block's first float.
HEADER = (
    "phi_count",
    "theta_count",
    "wavelength_count",
    "isotropic",
    "jacobian",
    "reduction",
    "phi_values",
    "theta_values",
    "wavelength_values",
    *(f"{table}_{part}" for table in ("ndf", "sigma", "spectra") for part in ("data", "width", "height")),
    *(
        f"{table}_{part}"
        for table in ("vndf", "luminance")
        for part in ("data", "marginal", "conditional", "width", "height")
    ),
)


@dataclass(frozen=True, eq=False)
class MeasuredTables:
    """A measured BRDF's tables as its file holds them (shapes as Mitsuba 3 checks them): phi_i (P,), theta_i (T,)
    in radians, wavelengths (L,) in nm, ndf and sigma (rows, columns), vndf and luminance (P, T, n, n), spectra
    (P, T, L, n, n); jacobian: the spectra still need D / (4σ) (the files' usual form); reduction: the φo symmetry
    of an anisotropic file (its phi_i covers 2π / reduction)."""

    description: str
    phi_i: np.ndarray
    theta_i: np.ndarray
    wavelengths: np.ndarray
    ndf: np.ndarray
    sigma: np.ndarray
    vndf: np.ndarray
    luminance: np.ndarray
    spectra: np.ndarray
    jacobian: bool
    reduction: int

    __eq__ = fields_equal
    __hash__ = object.__hash__

    @property
    def isotropic(self) -> bool:
        return self.phi_i.size <= 2

    @cached_property
    def device_block(self) -> np.ndarray:
        """What the kernel reads (device_block), made once: a live session writes every material's row again at
        each edit."""
        return device_block(self)


@dataclass(frozen=True)
class MeasuredMaterial(Material):
    """The BRDF measured in file `filename` (its name as given) with its tables."""

    filename: str
    tables: MeasuredTables = field(repr=False)

    is_delta = False
    has_transmission = False
    is_dispersive = False


MODEL = MeasuredMaterial


def read_measured(path: str | Path, where: str | None = None) -> MeasuredTables:
    """The tables of the RGL measurement at `path`; a file of another shape, an RGB one, or one with values no BRDF
    has is refused in one line."""
    fields = read_tensor_file(path, where, "measured BSDF file")
    return measured_tables(fields, where or str(path), Path(path).name)


def measured_tables(fields: dict[str, np.ndarray], where: str, name: str) -> MeasuredTables:
    """The tables of a measurement's tensor-file fields (read_measured)."""

    def bad(problem: str) -> SpectraceError:
        return SpectraceError(f"measured BSDF file '{name}' {problem}", where=where)

    if "wavelengths" not in fields and "rgb" in fields:
        raise bad("holds RGB data (an '_rgb' file): give the material's spectral '_spec.bsdf' file")
    required = ("description", "jacobian", "phi_i", "theta_i", "wavelengths", "ndf", "sigma", "vndf", "luminance")
    for key in (*required, "spectra"):
        if key not in fields:
            raise bad(f"has no field '{key}'")

    def floats(key: str, ndim: int) -> np.ndarray:
        value = fields[key]
        if value.dtype != np.float32 or value.ndim != ndim:
            raise bad(f"field '{key}' is {value.dtype} of {value.ndim} dimensions, where float32 of {ndim} is read")
        if not np.all(np.isfinite(value)):
            raise bad(f"field '{key}' has NaN or infinite values")
        return value

    phi_i, theta_i, wavelengths = floats("phi_i", 1), floats("theta_i", 1), floats("wavelengths", 1)
    ndf, sigma = floats("ndf", 2), floats("sigma", 2)
    vndf, luminance, spectra = floats("vndf", 4), floats("luminance", 4), floats("spectra", 5)
    if fields["description"].dtype != np.uint8 or fields["jacobian"].dtype != np.uint8:
        raise bad("has a 'description' or 'jacobian' field that is not uint8")
    if fields["jacobian"].shape != (1,):
        raise bad(f"has a 'jacobian' field of shape {fields['jacobian'].shape}, where (1,) is read")
    counts = (phi_i.size, theta_i.size)
    n = spectra.shape[3]
    shapes = {
        "vndf": (vndf.shape[:2] == counts and vndf.shape[2] >= 2 and vndf.shape[3] >= 2, "(phi_i, theta_i, ≥2, ≥2)"),
        "luminance": (luminance.shape == (*counts, n, n), "(phi_i, theta_i, n, n) as spectra's last two"),
        "spectra": (
            spectra.shape[:3] == (*counts, wavelengths.size) and spectra.shape[4] == n and n >= 2,
            "(phi_i, theta_i, wavelengths, n, n)",
        ),
        "ndf": (min(ndf.shape) >= 2, "(≥2, ≥2)"),
        "sigma": (min(sigma.shape) >= 2, "(≥2, ≥2)"),
    }
    for key, (fits, expected) in shapes.items():
        if not fits:
            raise bad(f"has a '{key}' field of shape {fields[key].shape}, where {expected} is read")
    for key, values in (("phi_i", phi_i), ("theta_i", theta_i), ("wavelengths", wavelengths)):
        if values.size == 0 or np.any(np.diff(values) <= 0):
            raise bad(f"has '{key}' values that do not increase")
    for key, values in (("ndf", ndf), ("sigma", sigma), ("vndf", vndf), ("luminance", luminance)):
        if np.any(values < 0):
            raise bad(f"has negative '{key}' values")
    if not np.all(sigma > 0):
        raise bad("has a projected area ('sigma') of 0 somewhere, by which the BRDF is divided")
    for key, values in (("vndf", vndf), ("luminance", luminance)):
        if not np.all(values.reshape(*counts, -1).sum(axis=-1) > 0):
            raise bad(f"has a '{key}' table that is 0 everywhere, which sampling cannot follow")
    reduction = 1
    if phi_i.size > 2:
        reduction = int(round(2.0 * math.pi / float(phi_i[-1] - phi_i[0])))
        if reduction not in (1, 2, 4):
            raise bad(f"spans {float(phi_i[-1] - phi_i[0]):.4g} rad of phi_i, no 2π / (1, 2 or 4)")
    return MeasuredTables(
        description=bytes(fields["description"]).decode("utf-8", "replace"),
        phi_i=phi_i,
        theta_i=theta_i,
        wavelengths=wavelengths,
        ndf=ndf,
        sigma=sigma,
        vndf=vndf,
        luminance=luminance,
        spectra=spectra,
        jacobian=bool(fields["jacobian"][0]),
        reduction=reduction,
    )


def from_spec(spec, resolver, key: str) -> MeasuredMaterial:
    return MeasuredMaterial(
        spec.filename, read_measured(resolver.folder / spec.filename, resolver.where(f"{key}.filename"))
    )


def make(filename: str | Path) -> MeasuredMaterial:
    """The BRDF measured in an RGL material database file (`*_spec.bsdf`, Dupuy & Jakob 2018), its spectra used at
    the path's wavelengths."""
    return MeasuredMaterial(str(filename), read_measured(filename, "filename"))


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    """Mitsuba 3's `measured`: its `filename` (black from the back outside a `twosided`, as Mitsuba's is)."""
    return {
        "type": NAME,
        "filename": importer.input_file(importer.child(properties, "filename", bsdf), "measured BSDF"),
    }


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's `measured` (MeasuredBxDF): its `filename`; pbrt reflects on both faces, as spectrace does."""
    if context.absent(material, "filename", "a diffuse material of reflectance 0.5"):
        return {"type": "diffuse", "reflectance": {"value": 0.5}}
    path = context.file_path(material, "filename")
    if path is None:
        raise context.error(material.location, 'measured material needs "filename"')
    return {"type": NAME, "filename": context.relative(path)}


def _warp_tables(density: np.ndarray, normalise: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(data, marginal, conditional) of the continuous bilinear warp of `density` (..., height, width): per slice
    the conditional integrals along each row (height × (width − 1)) of the piecewise-linear rows and the marginal
    integral (height − 1) of their totals, by the trapezoid rule on the unit square, everything scaled so the
    total is 1 where `normalise`."""
    d = np.asarray(density, np.float64)
    height, width = d.shape[-2:]
    conditional = np.cumsum(0.5 / (width - 1) * (d[..., :-1] + d[..., 1:]), axis=-1)
    rows = conditional[..., -1]
    marginal = np.cumsum(0.5 / (height - 1) * (rows[..., :-1] + rows[..., 1:]), axis=-1)
    if normalise:
        norm = 1.0 / marginal[..., -1]
        d = d * norm[..., None, None]
        conditional = conditional * norm[..., None, None]
        marginal = marginal * norm[..., None]
    return d, marginal, conditional


def device_block(tables: MeasuredTables) -> np.ndarray:
    """The float32 block kernels/bsdf_measured.cl reads: the HEADER's int32 fields, then the parameter values and
    tables they point to."""
    parts: list[np.ndarray] = []
    at = len(HEADER)
    header: dict[str, int] = {}

    def put(name: str, values: np.ndarray) -> None:
        nonlocal at
        header[name] = at
        flat = np.asarray(values, np.float32).ravel()
        parts.append(flat)
        at += flat.size

    header |= {
        "phi_count": tables.phi_i.size,
        "theta_count": tables.theta_i.size,
        "wavelength_count": tables.wavelengths.size,
        "isotropic": int(tables.isotropic),
        "jacobian": int(tables.jacobian),
        "reduction": tables.reduction,
    }
    put("phi_values", tables.phi_i)
    put("theta_values", tables.theta_i)
    put("wavelength_values", tables.wavelengths)
    for name in ("ndf", "sigma", "spectra"):
        values = getattr(tables, name)
        put(f"{name}_data", values)
        header[f"{name}_height"], header[f"{name}_width"] = values.shape[-2:]
    for name in ("vndf", "luminance"):
        values = getattr(tables, name)
        data, marginal, conditional = _warp_tables(values, normalise=True)
        put(f"{name}_data", data)
        put(f"{name}_marginal", marginal)
        put(f"{name}_conditional", conditional)
        header[f"{name}_height"], header[f"{name}_width"] = values.shape[-2:]
    if at >= 2**31:
        raise SpectraceError(f"measured BSDF '{tables.description}' needs {at} floats, beyond a 32-bit index")
    head = np.array([header[name] for name in HEADER], np.int32).view(np.float32)
    return np.concatenate([head, *parts])


def write_row(row: np.ndarray, material: MeasuredMaterial, table: SpectrumTable) -> None:
    """The block (device_block) in the spectrum table, its offset in eta_offset."""
    row["eta_offset"] = table.add_block(material.tables.device_block, key=material.tables)
