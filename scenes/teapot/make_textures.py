"""Makes the textures of scenes/teapot.toml, procedurally: nothing is downloaded, and the same code gives the same
files. Rerun it from the repository root after changing it, and commit what it writes:

    PYTHONPATH=host python scenes/teapot/make_textures.py

It writes, next to itself:
- glaze.png (512 x 256, sRGB): the teapot's painted glaze, cobalt blue on a cream white in the manner of Delft
  faience: bands at the rim and the base, eight flowers around the body. The teapot's body maps the image once
  around itself, u around and v from the rim (top) to the base.
- wood.png (256 x 256, sRGB): a table top of straight-grained planks (value noise from a fixed seed).
- tablecloth.exr: a spectral OpenEXR (36 bands, 380-730 nm every 10 nm, half floats; the layout spectrace reads as a
  `spectral` texture) of a gingham of two measured reflectances of the ColorChecker (N. Ohta's measurements, as
  colour-science ships them: "moderate red" and "neutral 8 (.23 D)"), each check holding a diamond painted in a
  *metamer* of the check: a reflectance with the same CIE 1931 XYZ as the check under D65 and a different one under
  CIE illuminant A. Under daylight the diamonds vanish; under a tungsten lamp (illuminant A) they show. An RGB
  texture cannot hold them: both would become the same three numbers.

The metamers are the check's spectrum plus a "metameric black" b (CIE 1931 XYZ of b under D65 zero, in the
renderer's colorimetry: linear interpolation between the bands, the 1 nm grid, trapezoid integrals), found by a
linear programme (scipy's HiGHS) that pushes the colour under illuminant A as far as it can along one direction while
the reflectance stays in [0.02, 0.97] and moves at most 0.15 between neighbouring bands (smooth, paint-like spectra).
It prints each pair's CIELAB Delta E (1976) under D65 and under A, each relative to its illuminant's white.
"""

from pathlib import Path

import numpy as np

BANDS_NM = np.arange(380.0, 731.0, 10.0)
CHECKS = 8  # checks along each side of the tablecloth
CHECK_TEXELS = 16
METAMER_RANGE = (0.02, 0.97)
METAMER_STEP = 0.15  # largest change of the metamer's reflectance between neighbouring bands
SUPERSAMPLING = 4  # per axis, for the painted images' antialiasing

CREAM = np.array([0.86, 0.82, 0.70])  # linear sRGB of the glaze
COBALT = np.array([0.035, 0.07, 0.34])


def _srgb_png(path: Path, linear: np.ndarray) -> None:
    from PIL import Image

    from spectrace.spectral import srgb_encode

    codes = np.round(np.clip(srgb_encode(np.clip(linear, 0.0, 1.0)), 0.0, 1.0) * 255.0).astype(np.uint8)
    Image.fromarray(codes, "RGB").save(path, optimize=True)


def _box_down(image: np.ndarray, factor: int) -> np.ndarray:
    h, w = image.shape[0] // factor, image.shape[1] // factor
    return image.reshape(h, factor, w, factor, -1).mean(axis=(1, 3))


def glaze(width: int = 512, height: int = 256) -> np.ndarray:
    """Linear sRGB (height, width, 3): the blue coverage painted over the cream glaze."""
    s = SUPERSAMPLING
    v, u = np.meshgrid((np.arange(height * s) + 0.5) / (height * s), (np.arange(width * s) + 0.5) / (width * s))
    u, v = u.T, v.T
    ink = np.zeros_like(u)
    # Rim and base bands, each with a thin line beside it.
    ink = np.maximum(ink, (v < 0.07) | ((v > 0.095) & (v < 0.11)) | (v > 0.93) | ((v > 0.89) & (v < 0.905)))
    # A wave between the rim band and the flowers.
    wave = 0.17 + 0.025 * np.sin(2.0 * np.pi * 16.0 * u)
    ink = np.maximum(ink, np.abs(v - wave) < 0.008)
    # Eight flowers around the body: a five-petalled rose curve, a dot at the heart, leaves between them.
    cell = (u * 8.0) % 1.0
    dx = (cell - 0.5) * (width / 8.0) / height  # in units of the image's height, so the flowers are round
    dy = v - 0.52
    radius = np.hypot(dx, dy)
    angle = np.arctan2(dy, dx)
    petals = radius < 0.16 * (0.35 + 0.65 * np.abs(np.cos(2.5 * angle)))
    heart = radius < 0.035
    ring = np.abs(radius - 0.05) < 0.006
    ink = np.maximum(ink, petals & ~ring | heart)
    # A stem with two leaves between neighbouring flowers.
    between = (((u * 8.0) + 0.5) % 1.0 - 0.5) * (width / 8.0) / height
    stem = (np.abs(between) < 0.006) & (v > 0.68) & (v < 0.86)
    leaf_l = np.hypot((between + 0.035) / 0.035, (v - 0.76) / 0.015) < 1.0
    leaf_r = np.hypot((between - 0.035) / 0.035, (v - 0.79) / 0.015) < 1.0
    ink = np.maximum(ink, stem | leaf_l | leaf_r).astype(np.float64)
    coverage = _box_down(ink[..., None], s)
    return CREAM * (1.0 - coverage) + COBALT * coverage


def _value_noise(rng: np.random.Generator, shape: tuple[int, int], cells: tuple[int, int]) -> np.ndarray:
    """Smooth noise in [0, 1], periodic over the image (so the texture tiles), from a lattice of random values."""
    lattice = rng.random(cells)
    y = np.arange(shape[0]) * cells[0] / shape[0]
    x = np.arange(shape[1]) * cells[1] / shape[1]
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = y - y0, x - x0
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    y1, x1 = (y0 + 1) % cells[0], (x0 + 1) % cells[1]
    top = lattice[y0][:, x0] * (1 - fx) + lattice[y0][:, x1] * fx
    bottom = lattice[y1][:, x0] * (1 - fx) + lattice[y1][:, x1] * fx
    return top * (1 - fy)[:, None] + bottom * fy[:, None]


def wood(size: int = 256) -> np.ndarray:
    """Linear sRGB (size, size, 3): four planks along u, grain lines bent by noise, a dark gap between planks."""
    rng = np.random.default_rng(1975)
    v, u = np.meshgrid(np.arange(size) / size, np.arange(size) / size, indexing="ij")
    plank = np.floor(v * 4.0)
    bend = 0.6 * _value_noise(rng, (size, size), (4, 2)) + 0.15 * _value_noise(rng, (size, size), (16, 8))
    grain = np.sin(2.0 * np.pi * (v * 4.0 * 9.0 + bend * 3.0 + plank * 0.37))
    figure = 0.5 + 0.5 * grain**3
    fine = _value_noise(rng, (size, size), (64, 8))
    tone = 0.75 + 0.25 * figure - 0.12 * fine + 0.06 * np.sin(plank * 2.1)
    light, dark = np.array([0.42, 0.21, 0.08]), np.array([0.16, 0.065, 0.02])
    colour = dark + (light - dark) * np.clip(tone, 0.0, 1.0)[..., None]
    gap = np.abs((v * 4.0) - np.round(v * 4.0)) < 0.012
    colour[gap] *= 0.35
    return colour


def _band_matrix(illuminant: np.ndarray) -> np.ndarray:
    """(3, bands): XYZ of a reflectance given at BANDS_NM, as the renderer sees it under `illuminant` (on the 1 nm
    grid): bands interpolated linearly (held beyond the ends), trapezoid integral, a perfect white at Y = 1."""
    from spectrace.spectral import CIE_1931_CMFS, GRID_NM
    from spectrace.spectral.grid import TRAPEZOID_WEIGHTS_NM

    interpolation = np.stack([np.interp(GRID_NM, BANDS_NM, np.eye(len(BANDS_NM))[i]) for i in range(len(BANDS_NM))])
    weights = CIE_1931_CMFS * (illuminant * TRAPEZOID_WEIGHTS_NM)[:, None]  # (grid, 3)
    white_y = (illuminant * TRAPEZOID_WEIGHTS_NM) @ CIE_1931_CMFS[:, 1]
    return (interpolation @ weights).T / white_y


def _lab(xyz: np.ndarray, white: np.ndarray) -> np.ndarray:
    t = xyz / white
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def metamer(reflectance: np.ndarray, daylight: np.ndarray, lamp: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The metamer of `reflectance` (at BANDS_NM) under `daylight` that differs most from it under `lamp`, over a few
    directions of change; with its Delta E under each light."""
    from scipy.optimize import linprog

    n = len(BANDS_NM)
    same = _band_matrix(daylight)
    seen = _band_matrix(lamp)
    white_d, white_l = same @ np.ones(n), seen @ np.ones(n)
    step = np.eye(n)[1:] - np.eye(n)[:-1]
    low, high = METAMER_RANGE
    best = (reflectance, 0.0, 0.0)
    # Directions in XYZ under the lamp: redder, greener, bluer, yellower.
    for direction in (
        [1.0, -1.0, 0.0],
        [-1.0, 1.0, 0.0],
        [-0.5, -0.5, 1.0],
        [0.5, 0.5, -1.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
    ):
        result = linprog(
            -(np.array(direction) @ seen),
            A_ub=np.vstack([step, -step]),
            b_ub=np.concatenate([METAMER_STEP - step @ reflectance, METAMER_STEP + step @ reflectance]),
            A_eq=same,
            b_eq=np.zeros(3),
            bounds=[(low - r, high - r) for r in reflectance],
            method="highs",
        )
        if not result.success:
            continue
        candidate = reflectance + result.x
        de_lamp = float(np.linalg.norm(_lab(seen @ candidate, white_l) - _lab(seen @ reflectance, white_l)))
        if de_lamp > best[2]:
            de_day = float(np.linalg.norm(_lab(same @ candidate, white_d) - _lab(same @ reflectance, white_d)))
            best = (candidate, de_day, de_lamp)
    return best


def tablecloth() -> tuple[np.ndarray, list[str]]:
    """(height, width, bands) reflectances of the gingham, and a line per metameric pair."""
    import colour

    from spectrace.spectral import cie_illuminant

    patches = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    d65, lamp = cie_illuminant("D65").values, cie_illuminant("A").values
    checks, lines = [], []
    for name in ("moderate red", "neutral 8 (.23 D)"):
        measured = patches[name]
        reflectance = np.interp(BANDS_NM, measured.wavelengths, measured.values)
        twin, de_day, de_lamp = metamer(reflectance, d65, lamp)
        checks.append((reflectance, twin))
        lines.append(f"{name}: Delta E 1976 under D65 {de_day:.3f}, under A {de_lamp:.1f}")
    size = CHECKS * CHECK_TEXELS
    y, x = np.meshgrid(np.arange(size) + 0.5, np.arange(size) + 0.5, indexing="ij")
    which = ((y // CHECK_TEXELS + x // CHECK_TEXELS) % 2).astype(int)
    cy, cx = (y % CHECK_TEXELS) / CHECK_TEXELS - 0.5, (x % CHECK_TEXELS) / CHECK_TEXELS - 0.5
    diamond = np.abs(cx) + np.abs(cy) < 0.3
    values = np.empty((size, size, len(BANDS_NM)))
    for k, (reflectance, twin) in enumerate(checks):
        values[(which == k) & ~diamond] = reflectance
        values[(which == k) & diamond] = twin
    return values, lines


def _spectral_exr(path: Path, values: np.ndarray) -> None:
    import OpenEXR

    from spectrace.io.exr import spectral_channel_name

    channels = {
        spectral_channel_name(nm): np.ascontiguousarray(values[..., i], np.float16) for i, nm in enumerate(BANDS_NM)
    }
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "spectralLayoutVersion": "1.0",
    }
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))


def main() -> None:
    folder = Path(__file__).resolve().parent
    _srgb_png(folder / "glaze.png", glaze())
    _srgb_png(folder / "wood.png", wood())
    values, lines = tablecloth()
    _spectral_exr(folder / "tablecloth.exr", values)
    for line in lines:
        print(line)


if __name__ == "__main__":
    main()
