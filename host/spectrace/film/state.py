"""The film's state on the host: the sums the render kernels add pixel samples to (kernels/film.cl; their device
buffers are spectrace.film.setup's `Film`), the whole of a render's progress that a checkpoint stores
(spectrace.engine.checkpoint writes and reads the file; what goes in it is here), and their image.

Per pixel the film holds four float32 sums (X, Y, Z and the count of non-finite samples left out), a uint32 count
of rays traced, when asked for, `spectral_bins` float32 band sums over `spectral_range_nm`, one float32 sum per
channel of the film's response (spectrace.film.response: more observers, a measured sensor) and, when any AOV
is asked for, the AOV_FLOATS_PER_PIXEL float32 AOV sums of kernels/aov.cl (albedo XYZ and ΣY², normal, position
and depth, the emission sampled and expected).
Together with the number of samples per pixel added so far they are the entire state of a render: the samplers are
counter-based and every pixel adds its samples in sample order, so restoring them continues the render bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.film.aovs import AOV_FLOATS_PER_PIXEL, STOKES_AOV_FLOATS_PER_PIXEL, aov_images, with_companions
from spectrace.film.image import Image, SpectralBands
from spectrace.film.response import WAVELENGTH_LIMITS_NM, FilmResponse

SPECTRAL_LIMITS_NM = (360.0, 830.0)  # the wavelengths the renders sample
# Saved-state buffers: element type, and elements per pixel (None: a positive whole number of them, the bands).
STATE_LAYOUT = {
    "film": (np.float32, 4),
    "ray_counts": (np.uint32, 1),
    "spectral_film": (np.float32, None),
    "aov_film": (np.float32, AOV_FLOATS_PER_PIXEL),
    "response_film": (np.float32, None),
}


@dataclass
class RenderState:
    """The film's accumulation buffers (host copies, by name) and how many samples per pixel they hold."""

    samples_done: int
    render_seconds: float
    buffers: dict[str, np.ndarray]


def spectral_range(scene) -> tuple[float, float]:
    """The wavelengths a scene's spectral bands span by default: its film's (film.wavelengths), the range its samples
    are drawn from, so no band lies where no sample falls and none of the film's range goes without a band."""
    response = getattr(scene, "film_response", None)
    lo, hi = response.wavelengths if response is not None else SPECTRAL_LIMITS_NM
    return float(lo), float(hi)


def spectral_bins_problem(bins: int, range_nm: tuple[float, float]) -> str | None:
    """Why `bins` equal bands cannot span `range_nm`, or None: at most one band per nanometre of the 1 nm grid the
    spectra are tabulated on (its nodes: hi - lo + 1), as 471 bands over the default 360-830 nm."""
    lo, hi = range_nm
    most = int(hi - lo) + 1
    if bins > most:
        return (
            f"{bins} bands over the film's {lo:g}-{hi:g} nm would be narrower than the 1 nm grid the spectra are "
            f"tabulated on: give at most {most} (film.wavelengths sets the range)"
        )
    return None


def spectral_defines(bins: int, range_nm: tuple[float, float]) -> dict[str, int | float]:
    """Kernel defines that make kernels/film.cl accumulate equal bands (none for 0 bins). Their count and range
    are run-time values (FilmSetup.write_params), so any `bins` over any `range_nm` shares one program."""
    if bins <= 0:
        return {}
    lo, hi = range_nm
    if not (WAVELENGTH_LIMITS_NM[0] <= lo < hi <= WAVELENGTH_LIMITS_NM[1]):
        raise SpectraceError(
            f"spectral range must lie within {WAVELENGTH_LIMITS_NM[0]:g}-{WAVELENGTH_LIMITS_NM[1]:g} nm, got {lo}-{hi}"
        )
    if problem := spectral_bins_problem(bins, range_nm):
        raise SpectraceError(problem, where="--spectral-bins")
    return {"SPECTRAL_FILM": 1}


# A render fails, rather than give its image, when at least this fraction of its samples were NaN or infinite and
# dropped: the image then holds less than half of the light it should, wherever the rest would have gone, so it is no
# picture of the scene (an image of every sample dropped is black). A few dropped samples (a rare overflow on a long
# path) only warn. The cause is an input whose numbers overflow 32-bit floats or divide by zero.
DROPPED_FAIL_FRACTION = 0.5
# An emitter's radiance, times the CMFs over the wavelength pdf (up to about 1e3 together) and a path's throughput,
# overflows 32-bit floats (3.4e38) from about here on: the likeliest input when samples are dropped.
_OVERFLOWING_EMISSION = 1e30


def dropped_samples_problem(dropped: int, samples: int, scene=None) -> str | None:
    """Why a render of `samples` samples, `dropped` of them non-finite, has no image to give (see
    DROPPED_FAIL_FRACTION), naming the scene's likeliest input at fault; or None."""
    if samples <= 0 or dropped < DROPPED_FAIL_FRACTION * samples:
        return None
    share = "every one" if dropped >= samples else f"{dropped} ({100.0 * dropped / samples:.0f} %)"
    cause = likely_non_finite_input(scene) if scene is not None else None
    cause = cause or "look for numbers in the scene that overflow 32-bit floats (above about 1e38) or divide by zero"
    source = f" of {scene.source}" if scene is not None and getattr(scene, "source", None) else ""
    return (
        f"{share} of the render's {samples} samples{source} came out NaN or infinite and was dropped, so the image "
        f"would be black or too dark; {cause}"
    )


def likely_non_finite_input(scene) -> str | None:
    """The input of `scene` that most likely makes its samples non-finite, as a phrase, or None: a pixel filter or a
    film response whose device numbers are not finite, else an emitter bright enough to overflow 32-bit floats."""
    pixel_filter = getattr(scene, "pixel_filter", None)
    if pixel_filter is not None:
        with np.errstate(all="ignore"):
            try:
                numbers = np.concatenate([pixel_filter.device_shape(), pixel_filter.device_cdf()])
            except (ArithmeticError, ValueError):
                numbers = np.array([np.nan])
        if not np.all(np.isfinite(numbers)):
            return f"the pixel filter (film.filter, {pixel_filter.type}) has no finite weights"
    response = getattr(scene, "film_response", None)
    if response is not None and not response.is_default:
        with np.errstate(all="ignore"):
            table = response.device_table()
        if not np.all(np.isfinite(table)):
            return "the film's observers or sensor have no finite wavelength pdf over film.wavelengths"
    brightest, name = 0.0, ""
    for shape in getattr(scene, "shapes", ()):
        if shape.emitter is not None and np.size(shape.emitter.radiance.values):
            peak = float(np.max(np.abs(shape.emitter.radiance.values)))
            if not peak <= brightest:
                brightest, name = peak, f"the emitter of shape '{shape.name}'"
    for index, light in enumerate(getattr(scene, "lights", ())):
        scale = float(getattr(light, "scale", 1.0))
        for value in vars(light).values() if hasattr(light, "__dict__") else ():
            array = getattr(value, "values", value)
            if isinstance(array, np.ndarray) and array.size and array.dtype.kind == "f":
                with np.errstate(over="ignore"):
                    peak = float(np.max(np.abs(array))) * (scale if value is getattr(light, "rgb", None) else 1.0)
                if not peak <= brightest:
                    brightest, name = peak, f"light {index} ({type(light).__name__})"
    if not brightest <= _OVERFLOWING_EMISSION:
        return f"{name} reaches {brightest:.3g} W/(m² sr nm), which overflows 32-bit floats on the way to the film"
    return None


def state_problem(state: RenderState, width: int, height: int) -> str | None:
    """Why `state` cannot be the saved state of a width x height film, or None (any number of spectral bands and
    response channels)."""
    if not 0 <= state.samples_done <= limits.MAX_SPP:
        return f"sample count {state.samples_done} is outside 0..{limits.MAX_SPP}"
    if not (np.isfinite(state.render_seconds) and state.render_seconds >= 0):
        return f"render time {state.render_seconds} s is not a finite non-negative number"
    pixels = width * height
    for name in ("film", "ray_counts"):
        if name not in state.buffers:
            return f"the {name} buffer is missing"
    for name, array in state.buffers.items():
        if name not in STATE_LAYOUT:
            return f"unknown buffer '{name}'"
        dtype, per_pixel = STATE_LAYOUT[name]
        if name == "aov_film" and array.ndim == 2 and array.shape[1] == STOKES_AOV_FLOATS_PER_PIXEL:
            per_pixel = STOKES_AOV_FLOATS_PER_PIXEL  # a polarised render's (spectrace.film.aovs)
        shape = (pixels, per_pixel) if per_pixel and per_pixel > 1 else (pixels,)
        if per_pixel is None:
            fits = array.ndim == 1 and array.size > 0 and array.size % pixels == 0
            needs = f"a positive multiple of {pixels} values"
        else:
            fits = array.shape == shape
            needs = f"shape {shape}"
        if array.dtype != dtype or not fits:
            return (
                f"the {name} buffer is {array.dtype} of shape {array.shape}; a {width}x{height} "
                f"film needs {np.dtype(dtype)} of {needs}"
            )
        if array.dtype.kind == "f" and not np.isfinite(array).all():
            return f"the {name} buffer holds {int((~np.isfinite(array)).sum())} NaN or infinite values"
    return None


def state_image(
    state: RenderState,
    width: int,
    height: int,
    spectral_range_nm: tuple[float, float],
    seed: int,
    device: str,
    exposure: float = 0.0,
    extra: dict | None = None,
    aovs: tuple[str, ...] | list[str] = (),
    albedo_scale: np.ndarray | None = None,
    response: FilmResponse | None = None,
) -> Image:
    """The image of a saved state: the mean of its samples per pixel, labelled with how it was made (a film's own
    image, or one merged on the host from tiles rendered elsewhere, spectrace.engine.tiles). `aovs` names the AOVs
    to make from its AOV sums, whose albedo channels `albedo_scale` (the film's CMF weights) turns into means;
    `response` the film's observers or sensor, whose channels it makes from the response sums."""
    film, rays = state.buffers["film"], state.buffers["ray_counts"]
    count = max(state.samples_done, 1)
    xyz = (film[:, :3] / np.float32(count)).reshape(height, width, 3)
    spectral = None
    if "spectral_film" in state.buffers:
        bands = state.buffers["spectral_film"].reshape(height, width, -1)
        lo, hi = spectral_range_nm
        spectral = SpectralBands(np.linspace(lo, hi, bands.shape[2] + 1), bands / np.float32(count))
    channels: dict[str, np.ndarray] = {}
    if response is not None and not response.is_default:
        sums = state.buffers.get("response_film", np.zeros(0, np.float32))  # absent: a film without channels
        responses = sums.reshape(height, width, -1) / np.float32(count)
        xyz, channels = response.outputs(xyz, responses)
    images = {}
    if aovs:
        scale = np.ones(3, np.float32) if albedo_scale is None else albedo_scale
        every = aov_images(state.buffers["aov_film"], film, state.samples_done, scale, (height, width))
        images = {name: every[name] for name in with_companions(aovs)}
    return Image(
        aovs=images,
        channels=channels,
        spectral=spectral,
        xyz=xyz,
        spp=state.samples_done,
        seed=seed,
        device=device,
        render_seconds=state.render_seconds,
        dropped_samples=int(film[:, 3].astype(np.float64).sum()),  # float32 would round totals above 2^24
        rays_traced=int(rays.astype(np.uint64).sum()),
        exposure=exposure,
        extra=extra or {},
    )
