"""`goniometric`: a point light whose radiant intensity over directions is an image in Clarberg's equal-area
octahedral mapping (pbrt-v4's `goniometric` light; kernels/light_goniometric.cl).

I(ω) = intensity(λ)·image(uv(ω)), W/(sr nm), the texel nearest to uv; an RGB image counts by the mean of its three
channels, as pbrt-v4 reads it. The map's frame: its centre (the octahedron's +z pole) along `up`, its u axis
along front × up and its v axis along `front` (made perpendicular to `up`); `mirrored` turns the v axis round (the
frame of a left-handed scene, as pbrt-v4's import needs). Every texel covers the same solid angle 4π / texel count,
so the light's flux is intensity·4π·mean(image); `power` sets it so.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.core.parameters import Parameter
from spectrace.errors import SpectraceError
from spectrace.lights import point, spot
from spectrace.lights.base import DeviceLight, Light, LightRows, check_position, light_row, vector3
from spectrace.lights.distribution import add_distribution
from spectrace.lights.envmap import magnitude_problem, orientation_problem
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike

NAME = "goniometric"
API_NAME = "goniometric_light"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no goniometric emitter"
PBRT_LIGHTS = ("goniometric",)
IS_ENVIRONMENT = False
GONIOMETRIC = DeviceLight("goniometric", "position")
DEVICE_TYPES = (GONIOMETRIC,)
DEFAULT_UP = (0.0, 1.0, 0.0)
DEFAULT_FRONT = (0.0, 0.0, 1.0)
PARAMETERS = (
    *point.PARAMETERS,
    Parameter(
        "file",
        "string",
        "",
        None,
        default_doc="none (isotropic)",
        doc="a square equal-area image of the intensity over directions (OpenEXR or Radiance HDR; RGB averaged)",
        api_name="image",  # the API takes the image's values
    ),
    Parameter("up", "vector", "", DEFAULT_UP, default_doc="[0, 1, 0]", doc="the direction the image's centre shows"),
    Parameter(
        "front",
        "vector",
        "",
        DEFAULT_FRONT,
        default_doc="[0, 0, 1]",
        doc="the image's v axis (made perpendicular to `up`)",
    ),
    Parameter("mirrored", "bool", "", False, doc="the map's v axis turned round (a left-handed frame)"),
)


@dataclass(frozen=True, eq=False)
class GoniometricLight(Light):
    """A point light at `position` with I(ω) = intensity·image(uv(ω)): see the module."""

    position: tuple[float, float, float]
    intensity: Spectrum
    image: np.ndarray | None = None  # (n, n) grey, ≥ 0
    up: tuple[float, float, float] = DEFAULT_UP
    front: tuple[float, float, float] = DEFAULT_FRONT
    mirrored: bool = False

    def mean_image(self) -> float:
        return 1.0 if self.image is None else float(np.mean(self.image))

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, z) of the map: z = up, y = front across it (negated when mirrored), x = y × z (right-handed
        before the mirror)."""
        z = np.asarray(self.up, float) / np.linalg.norm(self.up)
        front = np.asarray(self.front, float)
        y = front - (front @ z) * z
        y /= np.linalg.norm(y)
        x = np.cross(y, z)
        return x, (-y if self.mirrored else y), z


MODEL = GoniometricLight


def grey_image(values, where: str | None) -> np.ndarray:
    """A square grey image from (n, n), (n, n, 1) or (n, n, 3) values (RGB averaged, as pbrt-v4 does)."""
    array = np.asarray(values, np.float64)
    if array.ndim == 3 and array.shape[2] in (1, 3):
        array = array.mean(axis=2)
    if array.ndim != 2 or array.shape[0] != array.shape[1] or array.shape[0] == 0:
        raise SpectraceError(f"a goniometric image must be square (equal-area), got shape {array.shape}", where=where)
    if not np.all(np.isfinite(array)) or np.any(array < 0):
        raise SpectraceError("a goniometric image's values must be finite and ≥ 0", where=where)
    if problem := magnitude_problem(array, 1.0):
        raise SpectraceError(problem, where=where)
    return array


def _light(position, intensity_of, image, up, front, mirrored, where_front) -> GoniometricLight:
    if problem := orientation_problem(up, front):
        raise SpectraceError(problem, where=where_front)
    mean = 1.0 if image is None else float(np.mean(image))
    if not mean > 0:
        raise SpectraceError("a goniometric image must not be all black", where=where_front)
    return GoniometricLight(
        tuple(float(v) for v in position),  # type: ignore[arg-type]
        intensity_of(4.0 * np.pi * mean),
        image,
        tuple(float(v) for v in up),  # type: ignore[arg-type]
        tuple(float(v) for v in front),  # type: ignore[arg-type]
        bool(mirrored),
    )


def from_spec(spec, resolver, key: str) -> GoniometricLight:
    from spectrace.io.images import read_environment_map

    check_position(spec.position, resolver.where(f"{key}.position"))
    image = None
    if spec.file is not None:
        where = resolver.where(f"{key}.file")
        image = grey_image(read_environment_map(resolver.folder / spec.file, where, "goniometric image"), where)
    return _light(
        spec.position,
        lambda solid_angle: point.spec_intensity(spec, resolver, key, solid_angle),
        image,
        spec.up,
        spec.front,
        spec.mirrored,
        resolver.where(f"{key}.front"),
    )


def write_rows(light: GoniometricLight, out: LightRows) -> None:
    # The map's frame rides in the direction (its pole and the angle of its x axis, as a spot's slide), the mirror in
    # the projector's falloff switch, the image in the environment map's fields, its sampling table's texel in the
    # triangle's (kernels/types.h).
    x, _, z = light.frame()
    fields: dict = {}
    if light.image is not None:
        n = light.image.shape[0]
        texels = np.repeat(light.image[..., None], 3, axis=2).astype(np.float32)
        fields = {
            "map_fields": (0, 0, n, n),
            "texel_offset": out.add_texels(texels),
            # Light paths are drawn by the image: every texel covers the same solid angle, so its value is its weight.
            "triangle": add_distribution(light.image, out),
        }
    out.add(
        light_row(
            out.code(GONIOMETRIC),
            out.table.add(light.intensity),
            position=light.position,
            direction=tuple(z),
            direction_w=spot.slide_angle(z, x),
            linear_falloff=light.mirrored,
            **fields,
        ),
        4.0 * np.pi * light.mean_image() * light.intensity.mean(),
    )


def make(
    position: Sequence[float],
    intensity: SpectrumLike | None = None,
    power_w: float | None = None,
    spectrum: SpectrumLike | None = None,
    image=None,
    up: Sequence[float] = DEFAULT_UP,
    front: Sequence[float] = DEFAULT_FRONT,
    mirrored: bool = False,
) -> GoniometricLight:
    """A goniometric light at `position`: I(ω) = intensity·image(uv(ω)) W/(sr nm), `image` a square (n, n) or
    (n, n, 3) array in Clarberg's equal-area mapping (RGB averaged), or the path of such an OpenEXR or Radiance HDR
    file, centred on `up`, its v axis along `front`; or `power_w` W in all."""
    if isinstance(image, (str, Path)):
        from spectrace.io.images import read_environment_map

        image = read_environment_map(Path(image), "image", "goniometric image")
    grey = None if image is None else grey_image(image, "image")
    return _light(
        vector3(position, "position"),
        lambda solid_angle: point.make_intensity(intensity, power_w, spectrum, solid_angle),
        grey,
        vector3(up, "up"),
        vector3(front, "front"),
        mirrored,
        "front",
    )


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's goniometric light (lights.cpp, GoniometricLight): at its frame's origin, I(w) =
    scale·I(λ)·image(EqualAreaSphereToSquare(w')), w' the light-space direction with y and z swapped: the map's
    pole is the frame's +y, its u axis +x, its v axis +z; I normalised to luminance 1 (as every pbrt light), `power`
    setting the flux over 4π·mean(image). The frame's handedness in spectrace's world (context.world's mirror and
    the CTM's) decides `mirrored`, with `front` turned so that front × up stays the u axis."""
    from spectrace.io.images import read_environment_map

    x_axis, pole, v_axis = (np.asarray(context.direction(matrix, axis)) for axis in np.eye(3))
    mirrored = bool(np.dot(np.cross(v_axis, pole), x_axis) < 0.0)
    table: dict = {
        "type": NAME,
        "position": context.point(matrix, [0.0, 0.0, 0.0]),
        "up": pole.tolist(),
        "front": (-v_axis if mirrored else v_axis).tolist(),
        "mirrored": mirrored,
    }
    mean = 1.0
    absent = context.absent(light, "filename", "none (an isotropic light)")
    path = None if absent else context.file_path(light, "filename")
    if path is not None:
        table["file"] = context.relative(path)
        where = f"{light.location}"
        mean = float(np.mean(grey_image(read_environment_map(path, where, "goniometric image"), where)))
    scale = context.one(light, "scale", 1.0)
    power = context.one(light, "power", -1.0)
    if power > 0 and mean > 0:
        scale *= power / (4.0 * np.pi * mean)
    table["intensity"] = context.emission(light, "I", scale)
    return table
