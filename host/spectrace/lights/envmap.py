"""`envmap`: an environment from a latitude-longitude image, importance-sampled by luminance
(kernels/light_environment_map.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core import limits
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError
from spectrace.io.images import read_environment_map
from spectrace.lights.base import DeviceLight, Light, LightRows, light_row
from spectrace.lights.distribution import piecewise_constant_2d
from spectrace.spectral.colorimetry import LINEAR_SRGB_TO_XYZ
from spectrace.spectral.illuminants import d65_normalised
from spectrace.spectral.uplift import uplift_illuminant

NAME = "envmap"
MITSUBA_PLUGINS = ("envmap",)
# pbrt-v4's `infinite` is two lights here: this one with an image (`filename`), constant without.
PBRT_LIGHTS = ("infinite",)
IS_ENVIRONMENT = True
# A latitude-longitude RGB image at infinity, scaled: radiance W/(m² sr nm).
ENVIRONMENT_MAP = DeviceLight("environment_map", "infinite")
DEVICE_TYPES = (ENVIRONMENT_MAP,)
# No Python API constructor yet: a map comes from the file a scene names.
API_NAME = None
make = None
DEFAULT_UP = (0.0, 1.0, 0.0)
DEFAULT_FRONT = (0.0, 0.0, -1.0)
PARAMETERS = (
    Parameter("file", "string", "", REQUIRED, doc="latitude-longitude OpenEXR image, linear sRGB"),
    Parameter("scale", "float", "", 1.0, Range(0.0), doc="multiplies every texel's radiance"),
    Parameter("up", "vector", "", list(DEFAULT_UP), doc="the direction the image's top row (its zenith) shows"),
    Parameter(
        "front",
        "vector",
        "",
        list(DEFAULT_FRONT),
        doc="the direction the image's centre shows (made perpendicular to `up`)",
    ),
    Parameter(
        "rows",
        "string",
        "",
        "bands",
        type_doc='`"bands"` or `"poles"`',
        default_doc='`"bands"`',
        doc="where the rows lie: `bands`, H bands of equal angle; `poles` (Mitsuba 3's), samples from the zenith "
        "to the nadir, read as the H − 1 bands between them",
    ),
    Parameter(
        "texel_spectra",
        "string",
        "",
        "primaries",
        type_doc='`"primaries"` or `"smooth"`',
        default_doc='`"primaries"`',
        doc="each texel's spectrum: `primaries`, r·R(λ) + g·G(λ) + b·B(λ) from the emission uplifts of the three "
        "primaries; `smooth` (Mitsuba 3's spectral variants and pbrt-v4's), the emission uplift of the texel's own "
        "colour, a smooth spectrum times D65",
    ),
)
ROWS = ("bands", "poles")
TEXEL_SPECTRA = ("primaries", "smooth")


@dataclass(frozen=True, eq=False)
class EnvironmentMap(Light):
    """Light from a latitude-longitude image at infinity: `rgb` (height, width, 3) linear sRGB, times `scale`;
    each texel's radiance is a D65-based emission uplift of its colour (RGB (1,1,1) = D65 at Y = 1), in
    W/(m² sr nm): the primaries' uplifts weighted by its channels, or with `texel_spectra = "smooth"` the uplift
    of the colour itself. +y is up; the image centre looks along −z (see kernels/light_environment_map.cl)."""

    rgb: np.ndarray
    scale: float = 1.0
    up: tuple[float, float, float] = DEFAULT_UP
    front: tuple[float, float, float] = DEFAULT_FRONT
    texel_spectra: str = "primaries"

    def __post_init__(self) -> None:
        if problem := magnitude_problem(self.rgb, self.scale):
            raise SpectraceError(problem, where="scale")
        if self.texel_spectra not in TEXEL_SPECTRA:
            raise SpectraceError(
                f"texel_spectra must be one of {', '.join(TEXEL_SPECTRA)}, got {self.texel_spectra!r}",
                where="texel_spectra",
            )

    def world_to_map_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The first two rows (x, y) of the rotation from world directions to the map's frame (+y its zenith, −z
        its centre); the kernel makes the third, x × y."""
        y = np.asarray(self.up, float) / np.linalg.norm(self.up)
        front = np.asarray(self.front, float)
        z = -(front - (front @ y) * y)
        z /= np.linalg.norm(z)
        return np.cross(y, z), y


MODEL = EnvironmentMap


def orientation_problem(up, front) -> str | None:
    """Why `up` and `front` do not orient a map (zero, or parallel), or None."""
    up, front = np.asarray(up, float), np.asarray(front, float)
    if not (np.linalg.norm(up) > 0 and np.linalg.norm(front) > 0):
        return "up and front must not be zero"
    if np.linalg.norm(np.cross(up / np.linalg.norm(up), front / np.linalg.norm(front))) < 1e-6:
        return "up and front must not be parallel"
    return None


def magnitude_problem(rgb: np.ndarray, scale: float) -> str | None:
    """Why a map's texels (times `scale`) would overflow on the device, or None. Refused, not rescaled: as for any
    spectrum (limits.MAX_SPECTRUM_VALUE), a texel's radiance reaches the film times the CMFs over the wavelength pdf
    and summed over the samples in 32-bit floats, so a map far beyond 1e20 turns every sample that sees it into
    infinity, dropped (a black sky); rescaling it quietly would change the light the scene asked for. The texels are
    limited alone too, since the kernel weighs the basis spectra by them before it applies `scale`."""
    largest = float(np.max(rgb)) if np.size(rgb) else 0.0
    limit = limits.MAX_SPECTRUM_VALUE
    if largest > limit:
        return (
            f"the map's texels reach {largest:.3g}, beyond {limit:.0e}, where the film's 32-bit sums overflow "
            "(scale the image's values down)"
        )
    with np.errstate(over="ignore"):
        scaled = largest * float(scale)
    if not scaled <= limit:
        return (
            f"the map's texels times scale reach {scaled:.3g}, beyond {limit:.0e}, where the film's 32-bit sums "
            "overflow (scale the scene's radiometric units down)"
        )
    return None


def pole_rows_as_bands(rgb: np.ndarray) -> np.ndarray:
    """A map whose H rows are samples at the angles θᵢ = π i / (H − 1) from the zenith, interpolated linearly in θ
    between them (Mitsuba 3's envmap), as the H − 1 bands of equal angle between neighbouring rows: each band the
    interpolation's mean over the band's solid angle, so that every band sends the light the interpolated map sends
    through it (the map's power and any band's irradiance kept, up to how the light varies within one band).
    Columns are left as they are: both conventions centre column j on the azimuth (j + ½)/W of a turn."""
    height = rgb.shape[0]
    step = np.pi / (height - 1)
    top = np.arange(height - 1) * step  # each band's θ from its upper row to its lower one
    bottom = top + step
    # ∫ sin θ dθ over the band, and ∫ (θ − top)/step sin θ dθ: the weight of the lower row in the band's mean.
    solid = np.cos(top) - np.cos(bottom)
    lower = (np.sin(bottom) - np.sin(top) - step * np.cos(bottom)) / (step * solid)
    lower = lower[:, None, None]
    return ((1.0 - lower) * rgb[:-1] + lower * rgb[1:]).astype(rgb.dtype)


def from_spec(spec, resolver, key: str) -> EnvironmentMap:
    if problem := orientation_problem(spec.up, spec.front):
        raise SpectraceError(problem, where=resolver.where(f"{key}.front"))
    if spec.rows not in ROWS:
        raise SpectraceError(
            f"rows must be one of {', '.join(ROWS)}, got {spec.rows!r}", where=resolver.where(f"{key}.rows")
        )
    if spec.texel_spectra not in TEXEL_SPECTRA:
        raise SpectraceError(
            f"texel_spectra must be one of {', '.join(TEXEL_SPECTRA)}, got {spec.texel_spectra!r}",
            where=resolver.where(f"{key}.texel_spectra"),
        )
    rgb = read_environment_map(resolver.folder / spec.file, resolver.where(f"{key}.file"))
    if spec.rows == "poles":
        if rgb.shape[0] < 2:
            raise SpectraceError(
                f"rows = poles needs a map of 2 rows or more, got {rgb.shape[0]}", where=resolver.where(f"{key}.rows")
            )
        rgb = pole_rows_as_bands(rgb)
    if problem := magnitude_problem(rgb, spec.scale):
        name = "file" if float(np.max(rgb, initial=0.0)) > limits.MAX_SPECTRUM_VALUE else "scale"
        raise SpectraceError(problem, where=resolver.where(f"{key}.{name}"))
    return EnvironmentMap(
        rgb,
        spec.scale,
        tuple(float(v) for v in spec.up),  # type: ignore[arg-type]
        tuple(float(v) for v in spec.front),  # type: ignore[arg-type]
        spec.texel_spectra,
    )


def environment_map_tables(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Texels, sampling CDFs and mean luminance of a latitude-longitude map: the sampling density is ∝ luminance ×
    sin θ of the row's centre, so directions are drawn where light arrives and the poles' small texels are not
    oversampled."""
    height, width = rgb.shape[:2]
    texels = np.zeros((height * width, 4), np.float32)
    texels[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
    luminance = (texels[:, :3] @ LINEAR_SRGB_TO_XYZ[1]).reshape(height, width).astype(np.float64)
    sin_theta = np.sin(np.pi * (np.arange(height) + 0.5) / height)[:, None]
    weights = luminance * sin_theta
    if weights.sum() <= 0:
        weights = np.broadcast_to(sin_theta, (height, width)).copy()
    return texels, piecewise_constant_2d(weights), float(luminance.mean())


def smooth_texels(rgb: np.ndarray) -> np.ndarray:
    """(n, 4) float32 texels of `texel_spectra = "smooth"` from (n, 3) non-negative linear sRGB: each texel's
    emission uplift (pbrt-v4's RGBIlluminantSpectrum, `uplift_illuminant`'s scheme) as the sigmoid coefficients
    of its colour over 2 × its largest channel, in the dimensionless form (t = (λ − centre) / half span, which
    float32 holds far better than powers of λ in nm), then that multiplier; the kernel multiplies by the D65 the
    light's spectrum slot holds."""
    from spectrace.spectral.rgb_texture import texture_illuminant_coefficients
    from spectrace.textures.storage import dimensionless

    coefficients, multiplier = texture_illuminant_coefficients(rgb)
    texels = np.empty((len(rgb), 4), np.float32)
    texels[:, :3] = dimensionless(coefficients)
    texels[:, 3] = multiplier
    return texels


# Light.basis_green_offset of a map whose texels are smooth spectra (kernels/light_environment_map.cl).
SMOOTH_TEXELS = -1


def write_rows(light: EnvironmentMap, out: LightRows) -> None:
    map_texels, out.map_cdf, mean_luminance = environment_map_tables(light.rgb)
    height, width = light.rgb.shape[:2]
    if light.texel_spectra == "smooth":
        # The map's power estimate stays the RGB luminance's: the uplift keeps each texel's colour.
        spectrum = out.table.add(d65_normalised())
        map_fields = (SMOOTH_TEXELS, SMOOTH_TEXELS, width, height)
        texel_offset = out.add_chunk(smooth_texels(map_texels[:, :3]))
    else:
        basis = [out.table.add(uplift_illuminant(primary)) for primary in np.eye(3)]
        spectrum, map_fields = basis[0], (basis[1], basis[2], width, height)
        texel_offset = out.add_texels(map_texels[:, :3].reshape(height, width, 3))
    row_x, row_y = light.world_to_map_rows()
    out.add(
        light_row(
            out.code(ENVIRONMENT_MAP),
            spectrum,
            position=tuple(row_x),
            direction=tuple(row_y),
            map_fields=map_fields,
            texel_offset=texel_offset,
            scale=light.scale,
        ),
        4.0 * np.pi**2 * out.scene_radius**2 * light.scale * mean_luminance,
        environment=True,
    )


def from_mitsuba(importer, emitter, properties, to_world) -> dict | None:
    """Mitsuba 3's `envmap`: filename (a latitude-longitude image), scale, to_world. Mitsuba's map shows its local +z
    at the image's centre and +y at the top row (measured with Mitsuba's own emitter: +x at a quarter of the width,
    +z at half, −x at three quarters); its to_world turns those into world directions, which become `front` and
    `up` (a translation does nothing to light from infinitely far away)."""
    table: dict = {"type": NAME, "file": importer.input_file(importer.child(properties, "filename", emitter), "image")}
    # Mitsuba's first and last rows sit on the poles (its texel rows are π / (height − 1) apart); its spectral
    # variants give each texel the smooth uplift of its own colour times D65.
    table["rows"] = "poles"
    table["texel_spectra"] = "smooth"
    if "scale" in properties:
        scale = importer.number(properties["scale"])
        if not scale >= 0.0:
            raise importer.fail(properties["scale"], f"scale must be >= 0, got {scale:g}", "value")
        table["scale"] = scale
    linear = to_world[:3, :3]
    columns = linear / np.linalg.norm(linear, axis=0)
    if not (np.linalg.det(linear) > 0 and np.allclose(columns.T @ columns, np.eye(3), atol=1e-5)):
        importer.unsupported_plugin(emitter, " with a to_world that mirrors or shears (spectrace turns maps only)")
        return None
    up, front = (columns @ [0.0, 1.0, 0.0]).tolist(), (columns @ [0.0, 0.0, 1.0]).tolist()
    if not np.allclose(up, DEFAULT_UP, atol=0.0) or not np.allclose(front, DEFAULT_FRONT, atol=0.0):
        table |= {"up": up, "front": front}
    importer.notes.append(
        f"{importer.at(emitter)}: envmap: spectrace reads the map as the bands between its rows, each the mean of "
        "Mitsuba's interpolation over it, "
        "looked up at the nearest band (Mitsuba interpolates bilinearly between the rows)"
    )
    return table


def from_pbrt(context, light, matrix) -> dict | None:
    """pbrt-v4's `infinite` light with an image (None without one: constant's), its equal-area square resampled
    into a latitude-longitude map in spectrace's world (context.environment_map). pbrt-v4 reads each texel as an
    RGBIlluminantSpectrum: the smooth uplift of its colour times the colour space's illuminant."""
    if light.find("filename", "string") is None:
        return None
    return context.environment_map(light, matrix, context.one(light, "scale", 1.0)) | {"texel_spectra": "smooth"}
