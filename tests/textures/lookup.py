"""The texture harness (kernels/testing/texture.cl) driven from numpy, and an independent numpy reference of the
lookups (wrap modes, nearest, bilinear, a 2 × 2-mean MIP pyramid, trilinear level choice) written from the
definitions in docs/textures.md, not from spectrace's host preparation."""

import numpy as np

from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import TextureRows

HARNESS = "testing/texture.cl"


class TextureHarness:
    """Textures written as a scene would write them, then looked up on the device."""

    def __init__(self, runner, uses: list[tuple[object, str]]):
        self.runner = runner
        table = SpectrumTable()
        chunks = [np.zeros((1, 4), np.float32)]
        rows = TextureRows(table, chunks)
        self.indices = [rows.add(texture, kind) for texture, kind in uses]
        self.rows = rows.array()
        if len(table) == 0:
            table.add(Spectrum.zeros())
        self.textures = runner.buffer(rows.array())
        self.texels = runner.buffer(np.concatenate(chunks))
        self.spectra = runner.buffer(table.data)

    def lookup(self, which: int, uv: np.ndarray, footprint=0.0, lambdas=(400.0, 500.0, 600.0, 700.0)) -> np.ndarray:
        """(N, 4) values at uv (N, 2) with footprint (scalar or (N,)), at the four wavelengths."""
        points = np.zeros((len(uv), 4), np.float32)
        points[:, :2] = uv
        points[:, 2] = footprint
        return self._run("texture_lookup", which, points, lambdas)

    def lookup_points(self, which: int, points: np.ndarray, lambdas=(400.0, 500.0, 600.0, 700.0)) -> np.ndarray:
        """(N, 4) values at the world-space points (N, 3) (a solid texture's lookup), at the four wavelengths."""
        padded = np.zeros((len(points), 4), np.float32)
        padded[:, :3] = points
        return self._run("texture_lookup_point", which, padded, lambdas)

    def _run(self, kernel: str, which: int, points: np.ndarray, lambdas) -> np.ndarray:
        """Texture `which` looked up by `kernel` at each float4 of `points`: (N, 4) values at the four wavelengths."""
        out = np.zeros((len(points), 4), np.float32)
        args = [
            self.textures,
            self.texels,
            self.spectra,
            np.int32(self.indices[which]),
            self.runner.buffer(np.asarray(lambdas, np.float32)),
            self.runner.buffer(points),
            self.runner.buffer(out, True),
        ]
        self.runner.run(kernel, len(points), args, {6: out})
        return out.astype(np.float64)


# ---------------------------------------------------------------- the reference


def half_sigmoid_spectrum(coefficients_nm: np.ndarray, lambdas) -> np.ndarray:
    """The spectrum at `lambdas` of sigmoid coefficients (..., 3) of λ in nm as half storage keeps them
    (docs/textures.md, Memory): the same quadratic rewritten in t = (λ − 595) / 235 (the 360..830 nm grid's middle
    and half width), its coefficients rounded to IEEE half; saturated black and white stay exactly 0 and 1."""
    c = np.asarray(coefficients_nm, np.float64)
    lam = np.asarray(lambdas, np.float64)
    middle, half_width = 595.0, 235.0
    # x(middle + half_width t) expanded in powers of t.
    a = c[..., 0] * half_width**2
    b = half_width * (2.0 * c[..., 0] * middle + c[..., 1])
    k = c[..., 0] * middle**2 + c[..., 1] * middle + c[..., 2]
    t = (lam - middle) / half_width
    with np.errstate(over="ignore"):  # the saturated constants, replaced below
        rounded = [np.asarray(v, np.float16).astype(np.float64)[..., None] for v in (a, b, k)]
    x = (rounded[0] * t + rounded[1]) * t + rounded[2]
    x = np.where(np.abs(k)[..., None] >= 1e4, np.sign(k)[..., None] * 1e6, x)
    return 0.5 + x / (2.0 * np.sqrt(1.0 + x * x))


def wrap_index(i: np.ndarray, n: int, mode: str) -> np.ndarray:
    if mode == "clamp":
        return np.clip(i, 0, n - 1)
    if mode == "mirror":
        m = np.mod(i, 2 * n)
        return np.where(m < n, m, 2 * n - 1 - m)
    return np.mod(i, n)


def nearest(image: np.ndarray, st: np.ndarray, mode: str) -> np.ndarray:
    """image (H, W, C); st (N, 2): the texel whose square contains the point."""
    height, width = image.shape[:2]
    x = wrap_index(np.floor(st[:, 0] * width).astype(int), width, mode)
    y = wrap_index(np.floor(st[:, 1] * height).astype(int), height, mode)
    return image[y, x]


def bilinear(image: np.ndarray, st: np.ndarray, mode: str) -> np.ndarray:
    """Texel centres at ((i + ½)/W, (j + ½)/H); the four around the point weighted by the tent."""
    height, width = image.shape[:2]
    x, y = st[:, 0] * width - 0.5, st[:, 1] * height - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    xa, xb = wrap_index(x0, width, mode), wrap_index(x0 + 1, width, mode)
    ya, yb = wrap_index(y0, height, mode), wrap_index(y0 + 1, height, mode)
    top = image[ya, xa] * (1 - fx) + image[ya, xb] * fx
    bottom = image[yb, xa] * (1 - fx) + image[yb, xb] * fx
    return top * (1 - fy) + bottom * fy


def pyramid(image: np.ndarray) -> list[np.ndarray]:
    """A power-of-two image and its 2 × 2 means down to 1 × 1."""
    levels = [np.asarray(image, np.float64)]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        a = levels[-1]
        h, w = max(a.shape[0] // 2, 1), max(a.shape[1] // 2, 1)
        a = a.reshape(h, a.shape[0] // h, w, a.shape[1] // w, -1)
        levels.append(a.mean(axis=(1, 3)))
    return levels


def trilinear(levels: list[np.ndarray], st: np.ndarray, footprint_st: float, mode: str) -> np.ndarray:
    """Level l = log2(footprint · max(W, H)) (texels of level l are 2^l/max(W, H) wide), clamped to the pyramid;
    bilinear on floor(l) and floor(l) + 1, blended linearly."""
    finest = max(levels[0].shape[:2])
    level = 0.0 if footprint_st * finest <= 1 else min(np.log2(footprint_st * finest), len(levels) - 1)
    lower = int(np.floor(level))
    frac = level - lower
    value = bilinear(levels[lower], st, mode)
    if frac > 0:
        value = (1 - frac) * value + frac * bilinear(levels[lower + 1], st, mode)
    return value


SIDE = 32


def render_quad(texture, device) -> np.ndarray:
    """Y of a diffuse quad (z = 0, x and y in [−1, 1]) of reflectance `texture` seen head-on under a uniform
    environment of radiance 1 (one bounce: Y is the reflectance's Y at the point), 16 independent samples a pixel."""
    import spectrace
    from spectrace.engine.renderer import Renderer
    from spectrace.scene.model import Camera, Scene

    scene = Scene(
        camera=Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=SIDE,
        height=SIDE,
        shapes=[spectrace.shape("rectangle", spectrace.diffuse(texture))],
        lights=[spectrace.constant_environment(1.0)],
        max_depth=2,
        spp=16,
        seed=3,
        sampler="independent",
    )
    return Renderer(scene, device).render().xyz[..., 1]
