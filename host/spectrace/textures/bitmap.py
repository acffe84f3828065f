"""`bitmap`: an RGB or grey image (PNG, JPEG, TIFF, ... as Pillow reads them, 8 or 16 bits; 32-bit float TIFF; OpenEXR
R, G, B or Y; Radiance RGBE). Integer-coded images are sRGB-encoded and decoded to linear values unless `raw = true`;
float images hold linear values. As a reflectance each texel's linear sRGB colour becomes the sigmoid coefficients of
its smooth spectrum (Jakob & Hanika 2019; spectrace.spectral.uplift), evaluated per wavelength on the device; as a
scalar (a future roughness) it must have one channel and is used as stored. docs/textures.md."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.contract import TEXEL_RGB, TEXEL_SCALAR, TEXEL_SIGMOID, TEXEL_VECTOR
from spectrace.core.equality import fields_equal, identity_hash
from spectrace.core.parameters import Parameter
from spectrace.errors import SpectraceError
from spectrace.textures.mapping import PARAMETERS as MAPPING_PARAMETERS
from spectrace.textures.mapping import api_mapping
from spectrace.textures.shared import (
    FILE,
    FILTER,
    UV_OFFSET,
    WRAP,
    Placement,
    checked_placement,
    mip_pyramid,
    placement,
    uv_scale,
)

NAME = "bitmap"
API_NAME = NAME
COMPOSITE = False
RAW = Parameter(
    "raw",
    "bool",
    default=False,
    doc="use the code values as they are (data such as a roughness map) instead of decoding the sRGB curve",
)
LUMINANCE = Parameter(
    "luminance",
    "bool",
    default=False,
    doc="read an RGB image as one channel, the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of its linear values "
    "(as Mitsuba 3 reads an RGB bitmap where it needs one number, e.g. a bump map); a grey image stays as it is",
)
PARAMETERS = (FILE, RAW, LUMINANCE, WRAP, FILTER, uv_scale(1.0), UV_OFFSET, *MAPPING_PARAMETERS)
# The Y row of the linear sRGB -> XYZ matrix (IEC 61966-2-1; Rec. ITU-R BT.709 primaries, D65 white), the weights
# Mitsuba 3's luminance() uses.
_LUMINANCE_WEIGHTS = np.array([0.212671, 0.715160, 0.072169])
MITSUBA_PLUGINS = ("bitmap",)
PBRT_TEXTURES = ("imagemap",)
# pbrt-v4's filters -> this texture's (EWA is its trilinear filter's anisotropic refinement).
PBRT_FILTERS = {"point": "nearest", "bilinear": "bilinear", "trilinear": "trilinear", "ewa": "trilinear"}
# Mitsuba 3's bitmap filters and wraps, by the names both use; Mitsuba has no MIP mapping (no trilinear).
MITSUBA_FILTERS = ("bilinear", "nearest")
MITSUBA_WRAPS = ("repeat", "mirror", "clamp")
# Properties that change how Mitsuba stores or accelerates the texture, not what it looks like.
_MITSUBA_STORAGE = ("format", "accel")


@dataclass(frozen=True, eq=False)
class BitmapTexture:
    """An image of linear values, (height, width, channels) with 1 or 3 channels, row 0 at the top (v = 0)."""

    __eq__ = fields_equal  # by value (arrays too), hashed by identity
    __hash__ = identity_hash

    values: np.ndarray
    placement: Placement = Placement()
    source: str = "array"  # the file, for messages
    srgb_decoded: bool = False  # decoded from sRGB code values (so not data such as a normal map)

    @property
    def channels(self) -> int:
        return int(self.values.shape[-1])


MODEL = BitmapTexture


def decoded(values: np.ndarray, encoded: bool, raw: bool) -> np.ndarray:
    """Linear values: sRGB-decoded when the image holds encoded code values and is not raw."""
    from spectrace.spectral import srgb_decode

    return np.asarray(srgb_decode(values) if encoded and not raw else values, np.float64)


def from_spec(spec, resolver, key: str) -> BitmapTexture:
    from spectrace.io.images import read_texture_image

    path = resolver.folder / spec.file
    values, encoded = read_texture_image(path, resolver.where(f"{key}.file"))
    linear = decoded(values, encoded, spec.raw)
    return BitmapTexture(
        _read_only(_luminance(linear) if spec.luminance else linear),
        placement(spec, resolver.where(key)),
        source=str(path),
        srgb_decoded=encoded and not spec.raw,
    )


def make(
    source,
    *,
    srgb: bool | None = None,
    raw: bool = False,
    luminance: bool = False,
    wrap: str = "repeat",
    filter: str = "bilinear",
    uv_scale: float | tuple[float, float] = 1.0,
    uv_offset: tuple[float, float] = (0.0, 0.0),
    mapping: str = "uv",
    transform=(),
    v1=(1.0, 0.0, 0.0),
    v2=(0.0, 1.0, 0.0),
) -> BitmapTexture:
    """An image texture (docs/textures.md), `spectrace.bitmap`: a file path (PNG, JPEG, TIFF, OpenEXR, Radiance .hdr;
    integer-coded files are sRGB-decoded unless raw), a numpy array (H, W), (H, W, 1) or (H, W, 3) of linear values
    (srgb=True: sRGB-encoded values in [0, 1]), or a PIL image (decoded from sRGB unless raw). st = uv · uv_scale +
    uv_offset; wrap "repeat", "mirror" or "clamp"; filter "nearest", "bilinear" or "trilinear"; luminance=True: an RGB
    image as one channel, its luminance; mapping (with transform, v1, v2): where (u, v) come from (docs/textures.md)."""
    from spectrace.io.images import pil_image_values, read_texture_image

    where = "texture"
    if isinstance(source, (str, Path)):
        values, encoded = read_texture_image(Path(source), where)
        name = str(source)
    elif isinstance(source, np.ndarray):
        values = np.asarray(source, np.float64)
        if values.ndim == 2:
            values = values[..., None]
        if values.ndim != 3 or values.shape[-1] not in (1, 3) or values.shape[0] < 1 or values.shape[1] < 1:
            raise SpectraceError(f"a texture array must be (H, W), (H, W, 1) or (H, W, 3), got {source.shape}", where)
        if not np.all(np.isfinite(values)):
            raise SpectraceError("a texture array must be finite", where)
        encoded, name = bool(srgb), "array"
    elif hasattr(source, "mode") and hasattr(source, "size"):  # a PIL image
        values, encoded = pil_image_values(source)
        name = "PIL image"
    else:
        raise SpectraceError(
            f"a texture is a file path, a numpy array or a PIL image, got {type(source).__name__}", where
        )
    linear = decoded(values, encoded, raw)
    return BitmapTexture(
        _read_only(_luminance(linear) if luminance else linear),
        api_mapping(checked_placement(uv_scale, uv_offset, wrap, filter), mapping, transform, v1, v2),
        source=name,
        srgb_decoded=encoded and not raw,
    )


def _luminance(values: np.ndarray) -> np.ndarray:
    """One channel, the luminance of an RGB image's linear values; a grey image as it is."""
    return values if values.shape[-1] == 1 else (values @ _LUMINANCE_WEIGHTS)[..., None]


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array, np.float32)
    array.setflags(write=False)
    return array


def device_texels(texture: BitmapTexture, kind: str) -> tuple[int, int, list[np.ndarray]]:
    """(texel format, channels, levels) for a use of the texture: "spectrum" (a reflectance: each level's linear RGB
    to sigmoid coefficients), "float" (a scalar: one channel as stored), "vector" (a normal map: three channels as
    stored) or "emission" (linear RGB as stored, the weights of a light's three basis spectra; a grey image weights
    all three alike). The pyramid is built in linear RGB, each level then converted: averaging coefficients would not
    average the colours."""
    from spectrace.spectral.rgb_texture import texture_reflectance_coefficients

    values = texture.values.astype(np.float64)
    levels = mip_pyramid(values) if texture.placement.filter == "trilinear" else [values]
    if kind == "vector":
        return TEXEL_VECTOR, 3, levels
    if kind == "float":
        if texture.channels != 1:
            raise SpectraceError(
                f"texture '{texture.source}' has {texture.channels} channels; a scalar texture needs one (grey)"
            )
        return TEXEL_SCALAR, 1, levels
    rgb = [np.repeat(level, 3, axis=-1) if texture.channels == 1 else level for level in levels]
    if kind == "emission":
        return TEXEL_RGB, 3, rgb
    return TEXEL_SIGMOID, 3, [texture_reflectance_coefficients(np.clip(level, 0.0, 1.0)) for level in rgb]


def from_mitsuba(importer, texture, properties) -> dict | None:
    """Mitsuba 3's `bitmap`: filename (relative to the XML), raw, filter_type, wrap_mode, to_uv."""
    table: dict = {"type": NAME, "file": importer.input_file(importer.child(properties, "filename", texture))}
    if "raw" in properties:
        table["raw"] = importer.boolean(properties["raw"])
    for key, options in (("wrap_mode", MITSUBA_WRAPS), ("filter_type", MITSUBA_FILTERS)):
        if key in properties:
            table[key.split("_")[0]] = importer.choice(properties[key], options)  # spectrace's wrap, filter
    for key in properties:
        if key not in ("filename", "raw", "wrap_mode", "filter_type", "to_uv", *_MITSUBA_STORAGE):
            importer.unsupported_plugin(texture, f" with {key}")
    placement = importer.uv_placement(texture, properties)
    return None if placement is None else table | placement


def to_mitsuba(texture: BitmapTexture, exporter) -> dict:
    """A bitmap reading the texture's linear values from a float OpenEXR that the export writes: Mitsuba then reads
    the very texels spectrace decoded (however the source image was encoded) and uplifts them in its spectral
    variants by the same method (its table differs slightly)."""
    if texture.placement.filter not in MITSUBA_FILTERS:
        raise exporter.refuse(
            f"texture '{texture.source}': filter '{texture.placement.filter}' (Mitsuba 3's bitmap has no MIP mapping)"
        )
    values = np.asarray(texture.values, np.float32)
    path = exporter.write_linear_image(np.repeat(values, 3, axis=-1) if texture.channels == 1 else values)
    return {
        "type": "bitmap",
        "filename": str(path),
        "raw": False,
        "filter_type": texture.placement.filter,
        "wrap_mode": texture.placement.wrap,
        "to_uv": exporter.uv_transform(texture.placement.uv_scale, texture.placement.uv_offset),
    }


def from_pbrt(context, texture, uv: tuple[float, float, float, float]) -> dict:
    """pbrt-v4's imagemap; `uv` its (uscale, vscale, udelta, vdelta)."""
    if context.absent(texture, "filename", "the constant 0.5"):
        return {"value": 0.5}
    path = context.file_path(texture, "filename")
    if path is None:
        raise context.error(texture.location, f'{texture.label()} needs "string filename"')
    table: dict = {"texture": "bitmap", "file": context.relative(path)}
    encoding = context.string(texture, "encoding")
    if encoding == "linear":
        table["raw"] = True
    elif encoding not in (None, "sRGB"):
        context.warn(texture.location, f"encoding '{context.shown(encoding)}' not imported (read as sRGB)")
    filter_name = context.string(texture, "filter", "bilinear")
    table["filter"] = PBRT_FILTERS.get(filter_name or "", "bilinear")
    wrap = context.string(texture, "wrap", "repeat")
    if wrap not in ("repeat", "clamp"):
        context.warn(texture.location, f"wrap '{context.shown(wrap or '')}' imported as clamp")
        wrap = "clamp"
    table["wrap"] = wrap
    if context.one(texture, "scale", 1.0) != 1.0 or context.boolean(texture, "invert", False):
        context.warn(texture.location, '"scale" and "invert" of an image texture not imported')
    # pbrt looks images up at (s, 1 - t), t = vs v + vd; this texture at (u', v') = uv_scale (u, 1 - v) + uv_offset.
    us, vs, ud, vd = uv
    return table | {"uv_scale": [us, vs], "uv_offset": [ud, 1.0 - vs - vd]}
