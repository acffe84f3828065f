"""Measured-BSDF files written here, in the tensor format of the RGL material database (Dupuy & Jakob 2018), from a
closed-form BRDF: an isotropic GGX microfacet reflector of roughness α with a spectral reflectance F(λ) and the
height-correlated Smith masking-shadowing term,
    f(ωo, ωi) = F(λ) D(ωm) G2(ωo, ωi) / (4 cos θo cos θi),
so that a reader of the format can be checked against the formula and against another reader (Mitsuba 3's
`measured`) on the same bytes.

The format's tables, written from their definitions (the paper, sec. 4–5): on the square u(θ, φ) = (√(2θ/π),
(φ + π) / 2π), `ndf` holds D and `sigma` the projected area σ(ω) = ∫ D(ωm) ⟨ω·ωm⟩ dωm; per viewer elevation θo
(`theta_i`; one φo, 0: isotropic) `vndf` holds the density of visible normals on the square, D ⟨ωo·ωm⟩ / σ times the
Jacobian dω/du = 2π² u_θ sin θm (φm counted from φo); the measurement's square s is the visible-normal density's
sampling map (the rows' marginal, then the conditional along x, each inverting its cumulative integral), and
`spectra` (per wavelength) and `luminance` hold R(s) = f cos θi · 4σ / D at the direction each node s maps to,
here F (1 + Λo) / (1 + Λo + Λi). The sampling map is inverted numerically on a fine grid (not in the closed form a
reader uses), so a reader that parameterises otherwise disagrees."""

import functools
import struct
import tempfile
from pathlib import Path

import numpy as np

# Mitsuba's Struct type codes of the types written here.
_TYPE_CODES = {np.dtype("uint8"): 1, np.dtype("float32"): 10, np.dtype("float64"): 11}


def tensor_file_bytes(fields: dict[str, np.ndarray]) -> bytes:
    """A tensor file: 'tensor_file\\0', version 1.0, the field count, each field's name, rank, type, offset and
    shape, then the data, each field 8-byte aligned."""
    arrays = {name: np.ascontiguousarray(value) for name, value in fields.items()}
    header_size = 12 + 2 + 4 + sum(2 + len(name) + 2 + 1 + 8 + 8 * a.ndim for name, a in arrays.items())
    header = bytearray(b"tensor_file\0" + struct.pack("<BBI", 1, 0, len(arrays)))
    body = bytearray()
    offset = header_size
    for name, array in arrays.items():
        offset += -offset % 8
        body += bytes(offset - header_size - len(body))
        header += (
            struct.pack("<H", len(name))
            + name.encode()
            + struct.pack("<HBQ", array.ndim, _TYPE_CODES[array.dtype], offset)
        )
        header += struct.pack(f"<{array.ndim}Q", *array.shape)
        body += array.astype(array.dtype.newbyteorder("<")).tobytes()
        offset += array.nbytes
    return bytes(header + body)


def ggx_d(cos_m: np.ndarray, alpha: float) -> np.ndarray:
    c2 = cos_m**2
    return np.where(cos_m > 0, 1.0 / (np.pi * alpha**2 * c2**2 * (1.0 + (1.0 - c2) / (c2 * alpha**2)) ** 2), 0.0)


def ggx_lambda(cos_theta: np.ndarray, alpha: float) -> np.ndarray:
    c2 = np.clip(cos_theta, 1e-12, 1.0) ** 2
    return 0.5 * (-1.0 + np.sqrt(1.0 + alpha**2 * (1.0 - c2) / c2))


def ggx_projected_area(cos_theta: np.ndarray, alpha: float) -> np.ndarray:
    """σ = cos θ (1 + Λ), in the form that stays finite at grazing angles."""
    c = np.clip(cos_theta, 0.0, 1.0)
    return 0.5 * (c + np.sqrt(c**2 + alpha**2 * (1.0 - c**2)))


def ggx_brdf_cos(wo: np.ndarray, wi: np.ndarray, alpha: float) -> np.ndarray:
    """D G2 / (4 cos θo) (times F: f cos θi), for unit directions (n, 3) above the surface."""
    m = wo + wi
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    g2 = 1.0 / (1.0 + ggx_lambda(wo[:, 2], alpha) + ggx_lambda(wi[:, 2], alpha))
    value = ggx_d(m[:, 2], alpha) * g2 / (4.0 * wo[:, 2])
    return np.where((wo[:, 2] > 0) & (wi[:, 2] > 0), value, 0.0)


def _u_to_angles(ux, uy):
    return ux**2 * (np.pi / 2.0), (2.0 * uy - 1.0) * np.pi


def _sampling_map(density: np.ndarray, s: np.ndarray, fine: int = 1024) -> np.ndarray:
    """The point (x, y) of the unit square to which the bilinear density (height, width) on its nodes maps each
    s (k, 2): y from the marginal of y, x from the conditional at that y, each cumulative integral tabulated on
    `fine` points and inverted by linear interpolation."""
    height, width = density.shape
    fine_grid = np.linspace(0.0, 1.0, fine)
    row_nodes, column_nodes = np.linspace(0.0, 1.0, height), np.linspace(0.0, 1.0, width)

    def cumulative(values: np.ndarray) -> np.ndarray:
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (values[1:] + values[:-1]) * np.diff(fine_grid))])
        return cdf / cdf[-1]

    totals = np.trapezoid(density, column_nodes, axis=1)  # each row's integral, linear in y between rows
    marginal = cumulative(np.interp(fine_grid, row_nodes, totals))
    out = np.empty_like(s)
    out[:, 1] = np.interp(s[:, 1], marginal, fine_grid)
    j = np.minimum((out[:, 1] * (height - 1)).astype(int), height - 2)
    t = (out[:, 1] * (height - 1) - j)[:, None]
    rows = (1.0 - t) * density[j] + t * density[j + 1]  # (k, width): the density along x at each point's y
    # Each row on the fine grid (linear between its nodes), its running integral, and where that reaches s_x.
    spread = np.array([np.interp(fine_grid, column_nodes, np.eye(width)[c]) for c in range(width)])
    fine_rows = rows @ spread
    cdf = np.concatenate([np.zeros((len(s), 1)), np.cumsum(0.5 * (fine_rows[:, 1:] + fine_rows[:, :-1]), axis=1)], 1)
    cdf /= np.where(cdf[:, -1:] > 0, cdf[:, -1:], 1.0)
    above = np.clip((cdf < s[:, :1]).sum(axis=1), 1, fine - 1)
    c0, c1 = cdf[np.arange(len(s)), above - 1], cdf[np.arange(len(s)), above]
    fraction = np.where(c1 > c0, (s[:, 0] - c0) / np.where(c1 > c0, c1 - c0, 1.0), 0.0)
    out[:, 0] = fine_grid[above - 1] + fraction * (fine_grid[1] - fine_grid[0])
    return out


def ramp_reflectance(nm):
    """The default reflectance of the measurements: 0.5 at 360 nm rising linearly to 0.9 at 830 nm."""
    return 0.5 + 0.4 * (np.asarray(nm, np.float64) - 360.0) / 470.0


def ggx_measurement(
    alpha: float,
    reflectance=None,
    wavelengths=None,
    size: int = 32,
    theta_count: int = 12,
    phi_i=None,
) -> dict[str, np.ndarray]:
    """The fields of a GGX measurement of roughness `alpha` and reflectance F(λ) (default: rising linearly from 0.5
    at 360 nm to 0.9 at 830 nm, which the readers' linear interpolation between `wavelengths` reproduces), every
    table `size` × `size`, at `theta_count` viewer elevations up to 85°. `phi_i`: the viewer azimuths of a file
    written as an anisotropic one (its microfacet azimuths absolute, not from φo), spanning 2π, or π or π/2 for a
    file folded by the symmetries GGX has (the readers mirror directions into φ ∈ [−π, 0] or [−π, −π/2]); none: an
    isotropic file."""
    if reflectance is None:
        reflectance = ramp_reflectance
    wavelengths = np.linspace(360.0, 830.0, 5) if wavelengths is None else np.asarray(wavelengths, np.float64)
    phi_values = np.array([0.0]) if phi_i is None else np.asarray(phi_i, np.float64)
    theta_i = np.linspace(0.0, np.radians(85.0), theta_count)
    grid = np.linspace(0.0, 1.0, size)
    ux, uy = np.meshgrid(grid, grid)  # [row = φ coordinate, column = θ coordinate]
    theta, phi = _u_to_angles(ux, uy)
    ndf = ggx_d(np.cos(theta), alpha)
    sigma = ggx_projected_area(np.cos(theta), alpha)
    m = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    shape = (phi_values.size, theta_count)
    vndf, luminance = np.empty((*shape, size, size)), np.empty((*shape, size, size))
    spectra = np.empty((*shape, wavelengths.size, size, size))
    s = np.stack([ux.ravel(), uy.ravel()], axis=-1)
    for p, ph in enumerate(phi_values):
        for t, th in enumerate(theta_i):
            wo = np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
            visible = np.clip(m @ wo, 0.0, None)
            jacobian = 2.0 * np.pi**2 * ux * np.sin(theta)
            vndf[p, t] = ndf * visible / ggx_projected_area(np.cos(th), alpha) * jacobian
            point = _sampling_map(vndf[p, t], s)
            th_m, ph_m = _u_to_angles(point[:, 0], point[:, 1])
            mm = np.stack([np.sin(th_m) * np.cos(ph_m), np.sin(th_m) * np.sin(ph_m), np.cos(th_m)], axis=-1)
            wi = 2.0 * (mm @ wo)[:, None] * mm - wo
            lam_o, lam_i = ggx_lambda(np.cos(th), alpha), ggx_lambda(wi[:, 2], alpha)
            shadowing = np.where(wi[:, 2] > 0, (1.0 + lam_o) / (1.0 + lam_o + lam_i), 0.0).reshape(size, size)
            spectra[p, t] = reflectance(wavelengths)[:, None, None] * shadowing
            luminance[p, t] = shadowing
    return {
        "description": np.frombuffer(f"GGX alpha {alpha}".encode(), np.uint8),
        "jacobian": np.array([1], np.uint8),
        "phi_i": phi_values.astype(np.float32),
        "theta_i": theta_i.astype(np.float32),
        "wavelengths": wavelengths.astype(np.float32),
        "ndf": ndf.astype(np.float32),
        "sigma": sigma.astype(np.float32),
        "vndf": vndf.astype(np.float32),
        "luminance": luminance.astype(np.float32),
        "spectra": spectra.astype(np.float32),
    }


@functools.cache
def ggx_material(alpha: float):
    """A measured material of the GGX measurement of roughness `alpha` (ggx_measurement), read from the file's
    bytes as a file's are."""
    from spectrace.io.tensor_file import parse_tensor_file
    from spectrace.materials.measured import MeasuredMaterial, measured_tables

    name = f"ggx_{alpha}_spec.bsdf"
    fields = parse_tensor_file(tensor_file_bytes(ggx_measurement(alpha)), name)
    return MeasuredMaterial(name, measured_tables(fields, name, name))


@functools.cache
def ggx_file(alpha: float) -> Path:
    """The GGX measurement of roughness `alpha` as a file, written once per session into a folder of its own."""
    path = Path(tempfile.mkdtemp(prefix="spectrace-measured-")) / f"ggx_{alpha}_spec.bsdf"
    path.write_bytes(tensor_file_bytes(ggx_measurement(alpha)))
    return path
