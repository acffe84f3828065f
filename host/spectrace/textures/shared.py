"""What the image textures share: where a lookup lands on the image (uv_scale, uv_offset, wrap), how it is
filtered, and the MIP pyramid (Williams 1983, "Pyramidal Parametrics") that trilinear filtering reads."""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from numbers import Real

import numpy as np

from spectrace.core.contract import (
    FILTER_BILINEAR,
    FILTER_NEAREST,
    FILTER_TRILINEAR,
    WRAP_CLAMP,
    WRAP_MIRROR,
    WRAP_REPEAT,
)
from spectrace.core.parameters import REQUIRED, Parameter
from spectrace.errors import SpectraceError

WRAPS = {"repeat": WRAP_REPEAT, "mirror": WRAP_MIRROR, "clamp": WRAP_CLAMP}
FILTERS = {"nearest": FILTER_NEAREST, "bilinear": FILTER_BILINEAR, "trilinear": FILTER_TRILINEAR}

FILE = Parameter("file", "string", default=REQUIRED, doc="the image file, relative to the scene file")
WRAP = Parameter(
    "wrap",
    "wrap",
    default="repeat",
    doc="outside [0, 1)²: `repeat` tiles the image, `mirror` tiles it mirrored, `clamp` holds the edge texels",
    type_doc='`"repeat"`, `"mirror"` or `"clamp"`',
    default_doc='`"repeat"`',
)
FILTER = Parameter(
    "filter",
    "filter",
    default="bilinear",
    doc="`nearest`: the texel containing the point; `bilinear`: the four around it, blended; `trilinear`: bilinear "
    "on the two MIP levels that bracket the lookup's footprint, blended (builds the pyramid)",
    type_doc='`"nearest"`, `"bilinear"` or `"trilinear"`',
    default_doc='`"bilinear"`',
)
UV_OFFSET = Parameter(
    "uv_offset",
    "uv",
    default=(0.0, 0.0),
    doc="added after uv_scale: the texture is looked up at st = uv · uv_scale + uv_offset",
    type_doc="2 floats",
    default_doc="`[0, 0]`",
)


def uv_scale(default: float) -> Parameter:
    return Parameter(
        "uv_scale",
        "uv",
        default=default,
        doc="multiplies the surface's texture coordinates: the number of repeats across them",
        type_doc="float or 2 floats",
        default_doc=f"{default:g}",
    )


def uv_pair(value, name: str, where: str | None) -> tuple[float, float]:
    """A float (both axes) or two floats, finite."""
    items = list(value) if isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, str) else [value]
    if len(items) == 1:
        items = items * 2
    if len(items) != 2 or not all(isinstance(v, Real) and not isinstance(v, bool) for v in items):
        raise SpectraceError(f"{name} must be a number or two numbers, got {value!r}", where=where or name)
    pair = (float(items[0]), float(items[1]))
    if not all(np.isfinite(pair)):
        raise SpectraceError(f"{name} must be finite, got {value!r}", where=where or name)
    return pair


def choice(value: str, options: dict, name: str, where: str | None) -> str:
    if value not in options:
        raise SpectraceError(
            f"{name} must be one of {', '.join(repr(o) for o in options)}, got {value!r}", where=where or name
        )
    return value


@dataclass(frozen=True)
class Placement:
    """How an image lies on the surface: st = uv · uv_scale + uv_offset, `wrap` outside [0, 1)², `filter`."""

    uv_scale: tuple[float, float] = (1.0, 1.0)
    uv_offset: tuple[float, float] = (0.0, 0.0)
    wrap: str = "repeat"
    filter: str = "bilinear"
    mapping: str = "uv"  # where uv comes from (textures/mapping.py)
    mapping_rows: tuple[float, ...] = ()  # a mapping's world-to-texture rows, as the kernel reads them

    @property
    def uv_transform(self) -> tuple[float, float, float, float]:
        return (*self.uv_scale, *self.uv_offset)


def placement(spec, where: str) -> Placement:
    """The Placement of a validated scene table; `where` (file and key path) is named in errors."""
    from spectrace.textures.mapping import with_mapping

    return with_mapping(checked_placement(spec.uv_scale, spec.uv_offset, spec.wrap, spec.filter, where), spec, where)


def checked_placement(uv_scale, uv_offset, wrap: str, filter: str, where: str | None = None) -> Placement:
    """A Placement from its four values (the Python API's keyword arguments when `where` is None)."""
    return Placement(
        uv_scale=uv_pair(uv_scale, "uv_scale", where and f"{where}.uv_scale"),
        uv_offset=uv_pair(uv_offset, "uv_offset", where and f"{where}.uv_offset"),
        wrap=choice(wrap, WRAPS, "wrap", where and f"{where}.wrap"),
        filter=choice(filter, FILTERS, "filter", where and f"{where}.filter"),
    )


def level_count(width: int, height: int) -> int:
    """Levels of a pyramid down to 1 × 1, each max(1, size >> 1) of the one before (kernels/texture.cl)."""
    return int(max(width, height)).bit_length()


def _box_axis(values: np.ndarray, size: int, axis: int) -> np.ndarray:
    """`values` box-filtered to `size` samples along `axis`: each new sample is the mean of the old samples over
    its interval of n/size old ones (exact area weights, so odd sizes lose nothing)."""
    n = values.shape[axis]
    if size == n:
        return values
    ratio = n / size
    start = np.arange(size) * ratio
    end = start + ratio
    out = np.zeros(values.shape[:axis] + (size,) + values.shape[axis + 1 :])
    first = np.floor(start).astype(int)
    for k in range(int(np.ceil(ratio)) + 1):
        index = first + k
        overlap = np.clip(np.minimum(end, index + 1) - np.maximum(start, index), 0.0, None) / ratio
        valid = index < n
        taken = np.take(values, np.minimum(index, n - 1), axis=axis)
        shape = [1] * values.ndim
        shape[axis] = size
        out += taken * np.where(valid, overlap, 0.0).reshape(shape)
    return out


def mip_pyramid(level0: np.ndarray) -> list[np.ndarray]:
    """Level 0 (height, width, channels) and every coarser level to 1 × 1, box-filtered from the one before."""
    levels = [np.asarray(level0, np.float64)]
    for _ in range(level_count(level0.shape[1], level0.shape[0]) - 1):
        previous = levels[-1]
        height, width = max(1, previous.shape[0] >> 1), max(1, previous.shape[1] >> 1)
        levels.append(_box_axis(_box_axis(previous, height, 0), width, 1))
    return levels


def value_problem(values: np.ndarray, upper: float | None, reflectance: bool = True) -> str | None:
    """Why texel values cannot be used (negative, or beyond `upper`: for a reflectance, 1), or None."""
    low, high = float(values.min()), float(values.max())
    if low < 0.0:
        return f"has negative values (min {low:.4g})"
    if upper is not None and high > upper + 1e-6:
        why = ", which as a reflectance would create energy" if reflectance else ""
        return f"has values above {upper:g} (max {high:.4g}){why}"
    return None


class ImageTextures:
    """What a composite's API constructor checks its operands against: the image textures' models and their value
    check, both read from the registry, which lists the composites themselves. The package hands them over once its
    registry is built (spectrace.textures), before any constructor can run, so this module needs no import of it."""

    models: tuple[type, ...] = ()
    check: Callable[..., None] | None = None


def api_operand(value, name: str):
    """An operand given to the Python API's constructor of a composite: an image texture as it is, anything else a
    spectrum (anything `spectrace.spectrum` takes, an RGB triple uplifted as a reflectance) of values >= 0, whose
    upper bound is the using parameter's (checked where the texture is used: textures.check_texture_values)."""
    from spectrace.spectral import spectrum_input

    if isinstance(value, ImageTextures.models):
        return value
    if spectrum_input.is_rgb(value):
        return spectrum_input.reflectance(value, name)
    return spectrum_input.within_bounds(spectrum_input.spectrum(value), True, name)


def api_factor(value, name: str, upper: float | None, kind: str = "float"):
    """A composite's number given to the Python API: a float within [0, upper], or a one-channel image texture."""
    if isinstance(value, ImageTextures.models):
        assert ImageTextures.check is not None
        ImageTextures.check(value, kind, name, upper)
        return value
    number = float(value)
    if not (number >= 0.0 and (upper is None or number <= upper)):
        raise SpectraceError(f"{name} must lie in [0, {upper if upper is not None else 'inf'}], got {value}", name)
    return number


def composite_factor(value, resolver, key: str, upper: float | None, kind: str = "float"):
    """A scale's factor or a mix's amount from its validated scene value: a number in [0, upper], or a one-channel
    image texture (checked by the resolver as `kind`: a mix's "amount" also takes a solid noise texture); a spectrum
    given instead (`{ value = ... }`) must be constant and is its number."""
    from spectrace.spectral.spectrum import Spectrum

    name = key.rsplit(".", 1)[-1]
    where = resolver.where(key)
    if not isinstance(value, (int, float)):
        value = resolver.spectrum_or_texture(value, key, kind, inner=True)
        if not isinstance(value, Spectrum):
            if kind == "float" and upper is not None and (high := float(value.values.max())) > upper + 1e-6:
                raise SpectraceError(f"texture '{value.source}' has values above {upper:g} (max {high:.4g})", where)
            return value
        if np.ptp(value.values) > 0.0:
            raise SpectraceError(f"{name} is a number or a grey texture, not a spectrum that varies", where)
        value = float(value.values[0])
    if not (value >= 0.0 and (upper is None or value <= upper)):
        bound = f"[0, {upper:g}]" if upper is not None else ">= 0"
        raise SpectraceError(f"{name} must be {'in ' if upper is not None else ''}{bound}, got {value:g}", where)
    return float(value)


def two_sided_from_spec(model, sides: tuple[str, str], spec, resolver, key: str):
    """A texture of two sides (checkerboard, dots) from its scene-file table: each side a spectrum or an inner
    texture under `key`.NAME, and its placement."""
    from spectrace.textures.mapping import with_mapping

    values = [
        resolver.spectrum_or_texture(getattr(spec, name), f"{key}.{name}", "spectrum", inner=True) for name in sides
    ]
    where = resolver.where(key)
    return model(
        values[0],
        values[1],
        placement=with_mapping(
            Placement(
                uv_scale=uv_pair(spec.uv_scale, "uv_scale", f"{where}.uv_scale"),
                uv_offset=uv_pair(spec.uv_offset, "uv_offset", f"{where}.uv_offset"),
            ),
            spec,
            where,
        ),
    )


def pbrt_two_sided(context, texture, uv: tuple[float, float, float, float], name: str, sides: dict) -> dict:
    """A two-sided texture's table from a pbrt-v4 one: `sides` maps each of pbrt's side names to ours, in order
    (pbrt's defaults 1 then 0); `uv` pbrt's (uscale, vscale, udelta, vdelta). This texture's v is 1 − the file's v
    (mesh files store v up), so s = us u + ud, t = vs (1 − v) + vd."""
    table: dict = {"texture": name}
    for (side, ours), default in zip(sides.items(), (1.0, 0.0), strict=True):
        value = context.spectrum(texture, side, "albedo") or context.texture_reference(texture, side)
        table[ours] = value or {"value": default}
    us, vs, ud, vd = uv
    return table | {"uv_scale": [us, -vs], "uv_offset": [ud, vs + vd]}
