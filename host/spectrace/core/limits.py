"""Limits on sizes and magnitudes a render can honour, each with the reason it exists.

The schema checks scene files against them, the command line checks its overrides, and the renderer checks any
Scene built through the Python API; every message says what the request would cost.
"""

from numbers import Real

import numpy as np

# Deepest nesting accepted in an input file (TOML tables and arrays, Mitsuba XML elements and references). Real
# scenes nest a few levels (shapes[0].transform[1].matrix[2]; scene/shape/bsdf/bsdf/spectrum); far deeper input is
# malformed or hostile, and recursive code further on (validation, error messages) would exhaust Python's stack.
MAX_NESTING = 64

# A film side beyond this is almost certainly a typo (16384 px is the largest image most viewers open).
MAX_FILM_SIDE_PX = 16384
# 2^27 pixels (e.g. 16384 x 8192) need 2.5 GiB of device memory for the film and ray counts alone, and several
# times that on the host while the image is converted and written.
MAX_FILM_PIXELS = 1 << 27
# Per-pixel sums are 32-bit floats: beyond 2^20 samples each new sample is below a few ulps of the running sum and
# is effectively lost. Averaging images rendered with different seeds goes further without that loss.
MAX_SPP = 1 << 20
# The kernels read the seed, max_depth and rr_depth as 32-bit signed ints (RenderParams in kernels/types.h); the
# seed is cast to uint32 there, so negative seeds would only alias positive ones.
MAX_SEED = (1 << 31) - 1
MAX_DEPTH = (1 << 31) - 1
# Exposure scales the RGB outputs by 2**stops: beyond ±64 stops a float32 pixel of any rendered scene is 0 or
# infinite, so a larger value is a typo.
MAX_EXPOSURE_STOPS = 64.0

# Device bytes per pixel: the film (float4: ΣX, ΣY, ΣZ, dropped-sample count) and the ray count (uint32).
FILM_BYTES_PER_PIXEL = 16
RAY_COUNT_BYTES_PER_PIXEL = 4
DEVICE_BYTES_PER_PIXEL = FILM_BYTES_PER_PIXEL + RAY_COUNT_BYTES_PER_PIXEL
# Host bytes per pixel while an image is finished: film and ray counts read back (20), XYZ float32 (12), the
# float64 colour conversion (24) and the float32 linear sRGB (12).
HOST_BYTES_PER_PIXEL = DEVICE_BYTES_PER_PIXEL + 12 + 24 + 12

# Images read from files (pictures on screens, environment maps): the same pixel limit as the film. Their header
# gives the size before anything is decoded, so a small file claiming a huge image (a PNG of zeros compresses
# a thousandfold) is refused without the memory it would take.
MAX_IMAGE_PIXELS = MAX_FILM_PIXELS
# Host bytes per pixel at the peak of loading an image and building its texels (decoded pixels, float64 RGB
# and the drive or luminance tables derived from it, the float32 texel buffer), measured as the growth of the
# peak resident memory: 72 for a 2048x2048 PNG on a screen, 64 for a 4096x2048 EXR environment map.
IMAGE_HOST_BYTES_PER_PIXEL = 72
# On the device every texel is a float4, and a map adds its sampling tables (about 4 bytes per texel).
IMAGE_DEVICE_BYTES_PER_PIXEL = 16

# Every texture of a scene together, on the device (texels and MIP levels): beyond this a scene is refused before
# anything is converted, with the amount (docs/textures.md).
MAX_TEXTURE_BYTES = 1 << 30

# The watertight ray/triangle test forms products of three coordinate differences in 32-bit floats, which
# overflow (3.4e38) near 7e12; 1e12 scene units keeps a margin (the Earth's orbit is 1.5e11 m).
MAX_COORDINATE = 1e12
# Spectral values reach the film multiplied by the CMFs and divided by the wavelength pdf (up to ~1e3 together)
# and summed over up to MAX_SPP samples in 32-bit floats; 1e20 leaves that room. The Sun's spectral radiance is
# about 3e4 W/(m² sr nm).
MAX_SPECTRUM_VALUE = 1e20
# A transform whose smallest singular value is at most this fraction of its largest counts as singular: it
# flattens what it places onto a plane or a line (a scale of 1e-200 twice underflows to exactly 0), and its inverse,
# which turns normals and the kernels' rays into object space, does not exist or overflows. The fraction lies far
# below the 2^-24 relative resolution of 32-bit coordinates, so only maps singular up to rounding are refused.
SINGULAR_RELATIVE = 1e-12


def format_bytes(count: float) -> str:
    """1536 -> '1.5 KiB', in powers of 1024."""
    value = float(count)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if value < 1024.0 or unit == "TiB":
            return f"{value:.0f} {unit}" if unit == "B" else f"{value:.1f} {unit}"
        value /= 1024.0
    raise AssertionError("unreachable")


def whole_number_problem(name: str, value: object) -> str | None:
    """Why `value`, given for `name`, is not a whole number, or None. A scene file's schema refuses other types
    itself; a Python caller may pass anything: True (an int to Python), 16.0, NaN, "16", each of which int()
    or a comparison would take or fail on later."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        return f"{name} must be a whole number, got {value!r}"
    return None


def flag_problem(name: str, value: object) -> str | None:
    """Why `value`, given for `name`, is not True or False, or None (1 or "no" would be read by their truth)."""
    if not isinstance(value, bool | np.bool_):
        return f"{name} must be True or False, got {value!r}"
    return None


def film_side_problem(name: str, pixels: int) -> str | None:
    """Why a film side of `pixels` cannot be rendered, or None."""
    if problem := whole_number_problem(f"film {name}", pixels):
        return problem
    if pixels < 1:
        return f"{name} must be ≥ 1, got {pixels}"
    if pixels > MAX_FILM_SIDE_PX:
        return f"film {name} {pixels} px exceeds the limit of {MAX_FILM_SIDE_PX} px"
    return None


def film_size_problem(width: int, height: int) -> str | None:
    """Why a width x height film cannot be rendered, with the memory it would need, or None."""
    if problem := whole_number_problem("film width", width) or whole_number_problem("film height", height):
        return problem
    if (width < 1 or height < 1) and (problem := film_side_problem("width", width)):
        return problem  # a film of no pixels: its side is the fault, not memory
    if (width < 1 or height < 1) and (problem := film_side_problem("height", height)):
        return problem
    problem = film_side_problem("width", width) or film_side_problem("height", height)
    if problem is None and width * height <= MAX_FILM_PIXELS:
        return None
    pixels = max(width, 0) * max(height, 0)
    cost = (
        f"a {width}x{height} film ({pixels / 1e6:.1f} Mpixels) would need "
        f"{format_bytes(pixels * DEVICE_BYTES_PER_PIXEL)} of device memory and about "
        f"{format_bytes(pixels * HOST_BYTES_PER_PIXEL)} of host memory"
    )
    if problem is not None:
        return f"{problem}: {cost}"
    return f"{cost}; at most {MAX_FILM_PIXELS / 1e6:.1f} Mpixels are allowed (e.g. 16384x8192)"


def image_size_problem(width: int, height: int) -> str | None:
    """Why an image of width x height read from a file is refused, with the memory it would need, or None."""
    pixels = width * height
    if pixels <= MAX_IMAGE_PIXELS:
        return None
    return (
        f"a {width}x{height} image ({pixels / 1e6:.1f} Mpixels) would need about "
        f"{format_bytes(pixels * IMAGE_HOST_BYTES_PER_PIXEL)} of host memory and "
        f"{format_bytes(pixels * IMAGE_DEVICE_BYTES_PER_PIXEL)} of device memory; at most "
        f"{MAX_IMAGE_PIXELS / 1e6:.1f} Mpixels are allowed (e.g. 16384x8192)"
    )


def spp_problem(spp: int) -> str | None:
    """Why `spp` samples per pixel cannot be rendered, or None."""
    if problem := whole_number_problem("spp", spp):
        return problem
    if spp < 1:
        return f"spp must be at least 1, got {spp}"
    if spp > MAX_SPP:
        return (
            f"spp {spp} exceeds the limit of {MAX_SPP}: the film's 32-bit float sums stop gaining precision "
            f"beyond it; average images rendered with different seeds instead"
        )
    return None


def offset_seed(seed: int, offset: int) -> int:
    """Another valid seed `offset` away from `seed` (a render whose noise is independent of the seed's), wrapped
    into 0..MAX_SEED: a seed near the top plus the offset would not fit the kernels' 32-bit signed seed."""
    return (seed + offset) % (MAX_SEED + 1)


def seed_problem(seed: int) -> str | None:
    """Why `seed` cannot seed the kernels' samplers, or None."""
    if problem := whole_number_problem("seed", seed):
        return problem
    if not 0 <= seed <= MAX_SEED:
        return f"seed must lie in 0..{MAX_SEED} (the kernels take it as a 32-bit signed integer), got {seed}"
    return None


def max_depth_problem(depth: int, name: str = "max_depth") -> str | None:
    """Why a path depth cannot be rendered, or None; -1 means unbounded (Russian roulette ends the paths)."""
    if problem := whole_number_problem(name, depth):
        return problem
    if depth == -1 or 1 <= depth <= MAX_DEPTH:
        return None
    if depth > MAX_DEPTH:
        return (
            f"{name} must be at most {MAX_DEPTH} (the kernels take it as a 32-bit signed integer; "
            f"-1 means unbounded), got {depth}"
        )
    return f"{name} must be -1 (unbounded) or >= 1, got {depth}"


def exposure_problem(stops: float) -> str | None:
    """Why an exposure in stops cannot be applied to the outputs, or None."""
    if isinstance(stops, bool | np.bool_) or not isinstance(stops, Real):
        return f"exposure must be a number of stops, got {stops!r}"
    if not np.isfinite(stops):
        return f"exposure must be a finite number of stops, got {stops}"
    if abs(stops) > MAX_EXPOSURE_STOPS:
        return (
            f"exposure {stops:g} stops is beyond ±{MAX_EXPOSURE_STOPS:g}, where every output pixel would be 0 "
            f"or infinite"
        )
    return None


def pass_spp_problem(pass_spp: int | None) -> str | None:
    """Why `pass_spp` samples per pixel cannot be one pass (None: passes sized by their time), or None."""
    if pass_spp is None:
        return None
    if problem := whole_number_problem("pass_spp", pass_spp):
        return problem
    return f"pass_spp must be at least 1, got {pass_spp}" if pass_spp < 1 else None


def choice_problem(name: str, value: object, choices: tuple[str, ...]) -> str | None:
    """Why `value`, given for `name`, is not one of `choices`, or None."""
    if isinstance(value, str) and value in choices:
        return None
    return f"{name} must be one of {', '.join(choices)}, got {value!r}"


def scene_settings_problem(scene) -> str | None:
    """Why a Scene's seed, depths or exposure cannot be used (for scenes built in Python), or None."""
    return (
        seed_problem(scene.seed)
        or max_depth_problem(scene.max_depth)
        or whole_number_problem("rr_depth", scene.rr_depth)
        or (
            f"rr_depth must lie in 1..{MAX_DEPTH}, got {scene.rr_depth}"
            if not 1 <= scene.rr_depth <= MAX_DEPTH
            else None
        )
        or exposure_problem(scene.exposure)
    )


def coordinates_problem(points: np.ndarray) -> str | None:
    """Why these (N, 3) positions cannot be traced (NaN, infinite, or beyond ±MAX_COORDINATE), or None."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if points.size == 0:
        return None
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        first = int(np.flatnonzero(~finite)[0])
        return f"{int((~finite).sum())} point(s) with NaN or infinite coordinates (first: point {first})"
    largest = float(np.abs(points).max())
    if largest > MAX_COORDINATE:
        return (
            f"coordinates reaching {largest:.3g}, beyond ±{MAX_COORDINATE:.0e} scene units, where the device's "
            f"32-bit ray/triangle arithmetic overflows (use larger units, e.g. km instead of m)"
        )
    return None


def linear_map_problem(linear: np.ndarray) -> str | None:
    """Why the (3, 3) linear part of a transform cannot place a shape or a camera (non-finite entries, or singular by
    SINGULAR_RELATIVE), or None. Singular values, not the determinant: the determinant of a finite map can overflow
    or underflow where the map itself is well conditioned (a uniform scale of 1e120 or 1e-120)."""
    matrix = np.asarray(linear, dtype=np.float64)
    if not np.isfinite(matrix).all():
        return "has NaN or infinite entries (the product of its steps overflows)"
    singular = np.linalg.svd(matrix, compute_uv=False)
    if not singular[0] > 0.0 or singular[-1] <= SINGULAR_RELATIVE * singular[0]:
        return (
            f"is singular (largest and smallest singular values {singular[0]:.3g} and {singular[-1]:.3g}): it would "
            "flatten what it places"
        )
    return None


def spectrum_magnitude_problem(values: np.ndarray) -> str | None:
    """Why a spectrum with these values would overflow on the device, or None."""
    largest = float(np.max(np.abs(values))) if np.size(values) else 0.0
    if largest > MAX_SPECTRUM_VALUE:
        return (
            f"spectrum reaches {largest:.3g}, beyond {MAX_SPECTRUM_VALUE:.0e}, where the film's 32-bit sums "
            f"would overflow (scale the scene's radiometric units down)"
        )
    return None


def scene_geometry_problem(scene) -> str | None:
    """Why a resolved Scene (from a file or built in Python) cannot be traced: a shape, the camera or a point
    light with NaN, infinite or overflowing coordinates; or None."""
    for index, shape in enumerate(scene.shapes):
        if problem := coordinates_problem(shape.mesh.vertices):
            return f"shape {index} ('{shape.name}') has {problem}"
    for index, instance in enumerate(getattr(scene, "instances", ())):
        matrix = np.asarray(instance.to_world, dtype=np.float64)
        if matrix.shape != (4, 4) or not np.all(np.isfinite(matrix)):
            return f"instance {index} ('{instance.name}') has a to_world that is not a finite 4 x 4 matrix"
        if problem := linear_map_problem(matrix[:3, :3]):
            return f"instance {index} ('{instance.name}') has a to_world that {problem}"
        for shape in instance.object.shapes:
            # The corners of the shape's box: an affine map keeps every point within their images' hull.
            lo, hi = shape.mesh.vertices.min(axis=0), shape.mesh.vertices.max(axis=0)
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
            with np.errstate(over="ignore", invalid="ignore"):
                placed = corners @ matrix[:3, :3].T + matrix[:3, 3]
            if problem := coordinates_problem(placed):
                return f"instance {index} ('{instance.name}') places shape '{shape.name}' with {problem}"
    camera = scene.camera
    if problem := coordinates_problem(np.array([camera.origin, camera.target, camera.up], dtype=np.float64)):
        return f"the camera has {problem}"
    for index, light in enumerate(scene.lights):
        position = getattr(light, "position", None)
        if position is not None and (problem := coordinates_problem(position)):
            return f"light {index} has {problem}"
    return None
