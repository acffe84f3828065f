"""`projector`: an image projected from a point through a rectangular field of view (Mitsuba 3's `projector`,
pbrt-v4's `projection`; kernels/light_projector.cl).

The light's frame looks down its axis z (position → target) with y toward `up` across it; the image spans the
rectangle |x/z| ≤ tan(fov/2), |y/z| ≤ tan(fov/2)/aspect of the plane z = 1, its top row toward `up`. A direction ω
meets that plane at (x, y)/z, which names the image's texture coordinates uv. Two profiles of the radiant intensity
I(ω), W/(sr nm):
- `irradiance` (Mitsuba 3's): I(ω) = intensity·image(uv)/cos³θ, θ from the axis, so the plane z = 1 receives the
  irradiance intensity·image(uv) in W/(m² nm) at every point (a constant image lights it evenly);
- `intensity` (pbrt-v4's): I(ω) = intensity·image(uv), the image read as an intensity pattern.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.core.contract import NO_TEXTURE
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.lights import point, spot
from spectrace.lights.base import DeviceLight, Light, LightRows, check_position, light_row, unit_direction, vector3
from spectrace.lights.distribution import add_distribution
from spectrace.spectral.colorimetry import LINEAR_SRGB_TO_XYZ
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike

NAME = "projector"
API_NAME = "projector_light"
MITSUBA_PLUGINS = ("projector",)
PBRT_LIGHTS = ("projection",)
IS_ENVIRONMENT = False
PROJECTOR = DeviceLight("projector", "position")
DEVICE_TYPES = (PROJECTOR,)
PROFILES = ("irradiance", "intensity")
FOV = Parameter(
    "fov", "float", "degrees", 45.0, Range(0.0, 180.0, low_open=True, high_open=True), doc="across the image's width"
)
IMAGE = Parameter(
    "image",
    "spectrum",
    "",
    None,
    default_doc="none (white)",
    doc="a reflectance texture the intensity passes through, spanning the field of view",
    textured=True,
)
UP = Parameter("up", "vector", "", (0.0, 1.0, 0.0), default_doc="[0, 1, 0]", doc="the direction the image's top faces")
ASPECT = Parameter(
    "aspect",
    "float",
    "",
    None,
    Range(0.0, low_open=True),
    default_doc="the image's width/height (1 without one)",
    doc="width/height of the field of view",
)
PROFILE = Parameter(
    "profile",
    "string",
    "",
    "irradiance",
    doc="`irradiance`: I = intensity·image/cos³θ, the plane at unit distance lit by intensity·image (Mitsuba 3); "
    "`intensity`: I = intensity·image (pbrt-v4)",
)
FOV_AXES = ("width", "shorter")
FOV_AXIS = Parameter(
    "fov_axis",
    "string",
    "",
    "width",
    doc="the side `fov` spans: `width` (Mitsuba 3's default) or `shorter` (pbrt-v4's)",
)
PARAMETERS = (
    *point.PARAMETERS,
    Parameter("target", "vector", "scene units", REQUIRED, doc="the point the axis goes through"),
    FOV,
    FOV_AXIS,
    IMAGE,
    UP,
    ASPECT,
    PROFILE,
)


@dataclass(frozen=True)
class ProjectorLight(Light):
    """A projector at `position` looking along unit `direction`, image x along unit `image_x`: see the module."""

    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    intensity: Spectrum
    tan_x: float  # tan of half the field of view across the width
    tan_y: float  # and across the height
    image: Any = None  # a reflectance texture (spectrace.textures) or None
    image_x: tuple[float, float, float] = (1.0, 0.0, 0.0)
    profile: str = "irradiance"

    def effective_solid_angle(self) -> float:
        return effective_solid_angle(self.tan_x, self.tan_y, self.profile)


MODEL = ProjectorLight


def effective_solid_angle(tan_x: float, tan_y: float, profile: str) -> float:
    """∫ I(ω)/intensity dω for a white image, sr: the flux per unit intensity. With the irradiance profile the
    1/cos³θ cancels the plane's dω = cos³θ dA, leaving the image's area on z = 1; with the intensity profile the
    solid angle of the rectangular pyramid, 4 asin(sin α sin β)."""
    if profile == "irradiance":
        return 4.0 * tan_x * tan_y
    return 4.0 * math.asin(math.sin(math.atan(tan_x)) * math.sin(math.atan(tan_y)))


def _aspect(image, aspect: float | None) -> float:
    if aspect is not None:
        return float(aspect)
    values = getattr(image, "values", None)
    if values is not None and np.ndim(values) >= 2:
        return float(np.shape(values)[1]) / float(np.shape(values)[0])
    return 1.0


def _profile(profile: str, where: str | None) -> str:
    if profile not in PROFILES:
        raise SpectraceError(f"profile must be one of {', '.join(PROFILES)}, got {profile!r}", where=where)
    return profile


def _half_fields(fov: float, fov_axis: str, aspect: float, where: str | None, axis_where: str | None):
    """(tan_x, tan_y): the tangents of the half-fields across the width and the height."""
    if fov_axis not in FOV_AXES:
        raise SpectraceError(f"fov_axis must be one of {', '.join(FOV_AXES)}, got {fov_axis!r}", where=axis_where)
    tan_half = math.tan(math.radians(FOV.check(fov, where)) / 2.0)
    if fov_axis == "shorter" and aspect > 1.0:
        return tan_half * aspect, tan_half
    return tan_half, tan_half / aspect


def _image_x(direction, up, where: str | None) -> tuple[float, float, float]:
    """The image's u direction across the axis, as a spot's slide has it (spot.slide_x), `up` its top."""
    up_vector = np.asarray(up, float)
    if not float(np.linalg.norm(np.cross(up_vector, direction))) > 1e-6 * float(np.linalg.norm(up_vector)):
        raise SpectraceError("up must not lie along the axis", where=where)
    return spot.slide_x(direction, up, where)


def from_spec(spec, resolver, key: str) -> ProjectorLight:
    check_position(spec.position, resolver.where(f"{key}.position"))
    direction = unit_direction(np.subtract(spec.target, spec.position), resolver.where(f"{key}.target"))
    profile = _profile(spec.profile, resolver.where(f"{key}.profile"))
    image = None
    if spec.image is not None:
        image = resolver.spectrum_or_texture(spec.image, f"{key}.image", "spectrum")
        if isinstance(image, Spectrum):
            where = resolver.where(f"{key}.image")
            raise SpectraceError("an image is a texture (a constant one is a factor of the intensity)", where=where)
    tan_x, tan_y = _half_fields(
        spec.fov,
        spec.fov_axis,
        _aspect(image, spec.aspect),
        resolver.where(f"{key}.fov"),
        resolver.where(f"{key}.fov_axis"),
    )
    intensity = point.spec_intensity(spec, resolver, key, effective_solid_angle(tan_x, tan_y, profile))
    x = _image_x(direction, spec.up, resolver.where(f"{key}.up"))
    return ProjectorLight(tuple(spec.position), direction, intensity, tan_x, tan_y, image, x, profile)


def write_rows(light: ProjectorLight, out: LightRows) -> None:
    # The half-field tangents ride in the spot's cone fields, the profile in its falloff switch, the image's sampling
    # table in the triangle's texel and the environment map's size fields (kernels/types.h).
    table = image_weights(light.image) if light.image is not None else None
    table_fields: dict = {}
    if table is not None:
        if light.profile == "intensity":
            # I = intensity·image here, and dω = cos³θ dA on the plane: the cells' weights take the Jacobian (the
            # irradiance profile's 1/cos³θ cancels it).
            table = table * _cos_cubed(table.shape, light.tan_x, light.tan_y)
        table_fields = {
            "triangle": add_distribution(table, out),
            "map_fields": (0, 0, table.shape[1], table.shape[0]),
        }
    out.add(
        light_row(
            out.code(PROJECTOR),
            out.table.add(light.intensity),
            position=light.position,
            direction=light.direction,
            direction_w=spot.slide_angle(light.direction, light.image_x),
            cos_falloff_start=light.tan_x,
            cos_cutoff=light.tan_y,
            linear_falloff=light.profile == "irradiance",
            texture=out.textures.add(light.image, "spectrum") if light.image is not None else NO_TEXTURE,
            **table_fields,
        ),
        # An image only dims (a reflectance): the white image's power bounds the light's for its pick probability.
        light.effective_solid_angle() * light.intensity.mean(),
    )


def image_weights(image) -> np.ndarray | None:
    """Weights (height, width) over the image's uv square for drawing light paths, one cell per texel of a bitmap:
    the largest luminance of the reflectance any lookup in the cell can read (its texels and, filtered, their
    neighbours, through uv_scale, uv_offset and wrap), with a floor of 1e-3 of their mean so that no lit direction
    goes undrawn (a black texel's smooth spectrum is small, not zero). None for other textures: uniform."""
    from spectrace.textures.bitmap import BitmapTexture

    if not isinstance(image, BitmapTexture):
        return None
    values = np.clip(np.asarray(image.values, np.float64), 0.0, 1.0)
    luminance = values[..., 0] if values.shape[-1] == 1 else values @ LINEAR_SRGB_TO_XYZ[1]
    placement = image.placement
    reach = 0.0 if placement.filter == "nearest" else 0.5
    for axis, scale, offset in zip((1, 0), placement.uv_scale, placement.uv_offset, strict=True):
        size = luminance.shape[axis]
        edges = (np.arange(size + 1) / size * scale + offset) * size
        low = np.floor(np.minimum(edges[:-1], edges[1:]) - reach).astype(np.int64)
        high = np.ceil(np.maximum(edges[:-1], edges[1:]) + reach).astype(np.int64) - 1
        cells = []
        for a, b in zip(low, high, strict=True):
            taps = _wrapped(np.arange(a, b + 1), size, placement.wrap)
            cells.append(np.take(luminance, taps, axis=axis).max(axis=axis))
        luminance = np.stack(cells, axis=axis)
    if not luminance.max(initial=0.0) > 0:
        return None
    return np.maximum(luminance, 1e-3 * luminance.mean())


def _cos_cubed(shape: tuple[int, ...], tan_x: float, tan_y: float) -> np.ndarray:
    """cos³θ at the centres of the (height, width) cells of the image's rectangle on the plane z = 1."""
    height, width = shape
    x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * tan_x
    y = (2.0 * (np.arange(height) + 0.5) / height - 1.0) * tan_y
    return (1.0 + x[None, :] ** 2 + y[:, None] ** 2) ** -1.5


def _wrapped(index: np.ndarray, size: int, wrap: str) -> np.ndarray:
    if wrap == "clamp":
        return np.clip(index, 0, size - 1)
    if wrap == "mirror":
        period = np.mod(index, 2 * size)
        return np.where(period < size, period, 2 * size - 1 - period)
    return np.mod(index, size)


def make(
    position: Sequence[float],
    target: Sequence[float],
    fov: float = FOV.number_default,
    intensity: SpectrumLike | None = None,
    power_w: float | None = None,
    spectrum: SpectrumLike | None = None,
    image=None,
    up: Sequence[float] = (0.0, 1.0, 0.0),
    aspect: float | None = None,
    profile: str = "irradiance",
    fov_axis: str = "width",
) -> ProjectorLight:
    """Projector at `position` aimed at `target`, `fov` degrees across the image's width (its shorter side with
    `fov_axis="shorter"`), the image's top toward
    `up`: I(ω) = intensity·image(uv)/cos³θ (profile `irradiance`, Mitsuba 3's) or intensity·image(uv) (`intensity`,
    pbrt-v4's), W/(sr nm); or `power_w` W, that of a white image."""
    origin = np.asarray(vector3(position, "position"))
    direction = unit_direction(
        np.asarray(vector3(target, "target")) - origin, None, "projector target equals its position"
    )
    profile = _profile(profile, "profile")
    if aspect is not None:
        aspect = ASPECT.check(aspect, "aspect")
    tan_x, tan_y = _half_fields(fov, fov_axis, _aspect(image, aspect), "fov", "fov_axis")
    emitted = point.make_intensity(intensity, power_w, spectrum, effective_solid_angle(tan_x, tan_y, profile))
    x = _image_x(direction, vector3(up, "up"), "up")
    origin_t = (float(origin[0]), float(origin[1]), float(origin[2]))
    return ProjectorLight(origin_t, direction, emitted, tan_x, tan_y, image, x, profile)


def _mitsuba_focal_length_fov(focal_length: str, aspect: float = 1.0) -> float | None:
    """The field across the width Mitsuba 3 gives a focal length (default 50mm) on a 36 × 24 mm film's diagonal, for
    an image `aspect` (width / height) wide: tan(fov/2) = (d/2f)·a/√(1+a²) (a = 1 for a constant irradiance's
    square). None: not in mm."""
    text = focal_length.strip()
    if not text.endswith("mm"):
        return None
    try:
        millimetres = float(text[:-2])
    except ValueError:
        return None
    if not millimetres > 0.0:
        return None
    diagonal = math.hypot(36.0, 24.0)
    return math.degrees(2.0 * math.atan(diagonal / (2.0 * millimetres) * aspect / math.sqrt(1.0 + aspect * aspect)))


def _mitsuba_image_aspect(importer, reference: dict) -> float | None:
    """Width / height of the bitmap an imported irradiance texture reads; None for another texture."""
    table = importer.textures.get(reference["texture"], {})
    if table.get("type") != "bitmap" or "file" not in table:
        return None
    from spectrace.io.images import read_texture_image

    values, _ = read_texture_image(importer.toml_folder / table["file"], f"{importer.xml_path}: irradiance")
    return values.shape[1] / values.shape[0]


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    """Mitsuba 3's projector: the perspective camera's frame (to_world's lookat: local x to the image's left, y up
    it, z the axis) and its `fov` across the image's width (fov_axis x, its default); its intensity
    π·scale·irradiance(uv)/cos³θ is the irradiance profile, the image its `irradiance` texture, whose texels are
    reflectance spectra under a flat scale (no illuminant), or a constant folded into the intensity (an <rgb> in an
    emitter being an illuminant's colour)."""
    if "fov_axis" in properties and importer.text(properties["fov_axis"]) != "x":
        importer.unsupported_plugin(emitter, " with fov_axis other than x")
        return None
    scale = importer.number(properties["scale"]) if "scale" in properties else 1.0
    irradiance = importer.spectrum(properties["irradiance"], "irradiance") if "irradiance" in properties else None
    if "irradiance" in properties and irradiance is None:
        return None
    factor = math.pi * scale
    table: dict = {}
    if irradiance is None:
        intensity: dict = {"rgb": [factor] * 3}
    elif "texture" in irradiance:
        # A bitmap's texels are reflectance spectra and the scale is flat (no illuminant): an equal-energy intensity.
        intensity = {"value": factor}
        table["image"] = irradiance
    elif "rgb" in irradiance:
        intensity = {"rgb": [factor * v for v in irradiance["rgb"]]}
    elif "value" in irradiance:
        intensity = {"value": factor * irradiance["value"]}
    else:
        importer.unsupported_plugin(emitter, " with a spectral irradiance")
        return None
    if "fov" in properties:
        fov = importer.number(properties["fov"])
    else:
        aspect = _mitsuba_image_aspect(importer, table["image"]) if "image" in table else 1.0
        if aspect is None:
            importer.unsupported_plugin(emitter, " with an image that is not a bitmap and a focal_length")
            return None
        focal_length = properties.get("focal_length")
        fov = _mitsuba_focal_length_fov(importer.text(focal_length) if focal_length is not None else "50mm", aspect)
        if fov is None:
            importer.unsupported_plugin(emitter, " with a focal_length not in mm")
            return None
    matrix = np.asarray(to_world, dtype=float)
    position = matrix[:3, 3]
    return {
        "type": NAME,
        "position": position.tolist(),
        "target": (position + matrix[:3, 2]).tolist(),
        "up": matrix[:3, 1].tolist(),
        "fov": fov,
        "intensity": intensity,
        **table,
    }


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's projection light: its own frame looks down +z, the image's u along +x and v (rows, top first) along
    +y, so its top faces −y; `fov` spans the image's shorter side; I = scale·image(uv) (the intensity profile), the
    texels RGB illuminants of the colour space (its D65 under a reflectance image, read nearest as pbrt reads it)."""
    from spectrace.interop.pbrt.context import error, unique_name

    if context.one(light, "power", -1.0) > 0:
        raise error(light.location, 'a projection light\'s "power" is not imported: give "scale"')
    path = context.file_path(light, "filename")
    if path is None:
        raise error(light.location, 'a projection light needs "filename"')
    name = unique_name(f"projection_{path.stem}", set(context.textures))
    texture: dict = {"type": "bitmap", "file": context.relative(path), "filter": "nearest"}
    if np.linalg.det((context.world @ matrix)[:3, :3]) < 0.0:
        # A mirroring frame (pbrt's handedness turned into spectrace's) turns the image's u the other way.
        texture |= {"uv_scale": [-1.0, 1.0], "uv_offset": [1.0, 0.0]}
    context.textures[name] = texture
    return {
        "type": NAME,
        "position": context.point(matrix, [0.0, 0.0, 0.0]),
        "target": context.point(matrix, [0.0, 0.0, 1.0]),
        "up": [-c for c in context.direction(matrix, [0.0, 1.0, 0.0])],
        "fov": context.one(light, "fov", 90.0),
        "fov_axis": "shorter",
        "profile": "intensity",
        "intensity": context.emission(light, "I", context.one(light, "scale", 1.0)),
        "image": {"texture": name},
    }
