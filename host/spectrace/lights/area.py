"""Area lights: a shape's `emitter`, emitting from each of its triangles (or from the whole of an analytic shape: a
sphere sampled by the cone it subtends, a disk or cylinder by area), optionally showing an image: an emission
texture, or a display's picture, which is one (kernels/light_area.cl and the kernel file of each shape's device
type).

Not a LightPlugin (spectrace.lights.base): an area light is no `[[lights]]` table but a shape's `emitter`, so it has
no from_spec of its own (the loader reads it with the shape, `emitter` below), its rows come with the scene's
triangles and analytic shapes (write_rows, write_shape_rows) and its Mitsuba mapping has no to_world (it is the
shape's). It is a LightSource: it declares the device light types its rows have."""

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from spectrace.core.contract import NO_TEXTURE
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.lights.base import DeviceLight, LightRows, light_row
from spectrace.spectral.spectrum import Spectrum

if TYPE_CHECKING:
    from spectrace.geometry.analytic import AnalyticSurface

NAME = "area"
MITSUBA_PLUGINS = ("area",)  # on a shape only
PBRT_LIGHTS = ("diffuse",)  # AreaLightSource, on a shape

# Radiance W/(m² sr nm) from each emitting triangle; from an analytic sphere (sampled by the solid angle it
# subtends); from another analytic shape, a disk or cylinder (sampled by area).
TRIANGLE = DeviceLight("triangle", "area")
SPHERE = DeviceLight("sphere", "area")
SHAPE = DeviceLight("shape", "area")
DEVICE_TYPES = (TRIANGLE, SPHERE, SHAPE)
PARAMETERS = (
    Parameter(
        "radiance",
        "spectrum",
        "W/(m² sr nm)",
        REQUIRED,
        doc="times scale; a texture: an RGB image (each texel the D65-based emission of its colour, as an `envmap`'s) "
        "or a spectral one (each texel its radiance)",
        textured=True,
    ),
    Parameter(
        "two_sided",
        "bool",
        "",
        False,
        doc="emit on both faces; by default only on the side the triangles' winding faces",
    ),
    Parameter("scale", "float", "", 1.0, Range(0.0), doc="multiplies the radiance"),
    Parameter(
        "polarization",
        "string",
        "",
        None,
        doc="the Stokes state of its light: `linear <degrees>` (counter-clockwise from the surface's u direction "
        "as seen facing its emitting side: a picture's right toward its up), `circular`, `unpolarized`, or `display` "
        "(the record of the radiance's display); makes the scene polarised ([polarization.md](polarization.md))",
    ),
)


@dataclass(frozen=True, eq=False)
class EmitterImage:
    """An image shown by an area light, placed by the surface's texture coordinates (u right, v down): a texture
    (spectrace.textures) looked up at its finest level, times `scale`. A bitmap's texel (r, g, b) emits
    r·R(λ) + g·G(λ) + b·B(λ) of `primaries` (the D65-based emission uplifts of the sRGB primaries for an emission
    texture, as an environment map's; a display's measured primaries for the picture it shows, its linear drive the
    texels); a spectral texture's texel is its radiance, and `primaries` is None."""

    texture: Any  # a BitmapTexture or SpectralTexture (spectrace.textures is imported lazily here)
    primaries: tuple[Spectrum, Spectrum, Spectrum] | None  # W/(m² sr nm) at full drive
    scale: float = 1.0

    def mean_radiance(self) -> Spectrum:
        """The radiance averaged over the image's texels, W/(m² sr nm), scale applied: what the light's power
        estimate uses."""
        from spectrace.spectral.grid import GRID_NM
        from spectrace.textures import SpectralTexture

        values = np.asarray(self.texture.values, np.float64)
        mean = values.reshape(-1, values.shape[-1]).mean(axis=0)
        if isinstance(self.texture, SpectralTexture):
            # The kernel interpolates linearly between band centres and holds the end bands, as np.interp does.
            radiance = np.interp(GRID_NM, self.texture.wavelengths_nm, mean)
        else:
            assert self.primaries is not None  # a bitmap weights its primaries
            rgb = np.repeat(mean, 3) if len(mean) == 1 else mean
            radiance = sum(c * p.values for c, p in zip(rgb, self.primaries))
        return Spectrum(self.scale * radiance, name="image mean")


@dataclass(frozen=True)
class AreaEmitter:
    radiance: Spectrum  # W/(m² sr nm), scale applied; with an image, its mean emission
    two_sided: bool = False
    image: EmitterImage | None = None
    stokes: tuple[float, float, float] | None = None  # (S1, S2, S3) / S0 of its light, or None: unpolarised


MODEL = AreaEmitter


def emitter_stokes(text: str, display, where: str | None) -> tuple[float, float, float] | None:
    """The normalised (S1, S2, S3) of an emitter's `polarization` (None for unpolarised light): a display's
    catalogue text, or `display` for the record of `display` (None when the radiance names no display)."""
    from spectrace.errors import SpectraceError
    from spectrace.spectral.display_polarization import parse_polarization

    if text.strip().lower() == "display":
        if display is None:
            raise SpectraceError("polarization = 'display' needs a radiance that names a display", where=where)
        polarization = display.polarization
        if not polarization.known:
            raise SpectraceError(
                "the display's catalogue record leaves its polarisation unknown; give it here (linear <axis>, "
                "circular, unpolarized)",
                where=where,
            )
    else:
        polarization = parse_polarization(text, where=where)
        if not polarization.known:
            raise SpectraceError(
                "polarization = 'unknown' renders nothing: give linear <axis>, circular or unpolarized", where=where
            )
    s = polarization.stokes()
    return None if not np.any(s[1:]) else (float(s[1]), float(s[2]), float(s[3]))


def _polarization_fields(e: AreaEmitter) -> dict:
    """Light.direction of an area light: its normalised Stokes vector and w = 1 when it emits polarised light
    (kernels/polarized_path.cl); otherwise light_row's default, so unpolarised rows keep their bytes."""
    return {} if e.stokes is None else {"direction": e.stokes, "direction_w": 1.0}


def peak_radiance(e: AreaEmitter) -> float:
    """The largest radiance the emitter sends anywhere, W/(m² sr nm), scale applied: its spectrum's peak, or for an
    image the brightest texel times its brightest primary (an upper bound)."""
    with np.errstate(over="ignore"):
        if e.image is None:
            return float(np.max(np.abs(e.radiance.values))) if np.size(e.radiance.values) else 0.0
        texels = float(np.max(np.abs(np.asarray(e.image.texture.values, np.float64))))
        primary = (
            max((float(np.max(np.abs(p.values))) for p in e.image.primaries), default=1.0)
            if (e.image.primaries)
            else 1.0
        )
        return texels * primary * abs(float(e.image.scale))


def emission_image(texture, scale: float = 1.0) -> EmitterImage:
    """An emission texture (a bitmap of linear sRGB, or a spectral texture) as the image of an area light."""
    from spectrace.spectral.uplift import uplift_illuminant
    from spectrace.textures import BitmapTexture

    if not isinstance(texture, BitmapTexture):
        return EmitterImage(texture, None, float(scale))
    red, green, blue = (uplift_illuminant(primary) for primary in np.eye(3))
    return EmitterImage(texture, (red, green, blue), float(scale))


def emitter(radiance, two_sided: bool = False, scale: float = 1.0) -> AreaEmitter:
    """An area emitter of a checked radiance: a Spectrum (scale applied here) or an emission texture."""
    from spectrace.textures import is_texture

    if is_texture(radiance):
        image = emission_image(radiance, scale)
        return AreaEmitter(radiance=image.mean_radiance(), two_sided=bool(two_sided), image=image)
    return AreaEmitter(radiance=radiance.scaled(scale) if scale != 1.0 else radiance, two_sided=bool(two_sided))


def write_rows(
    emitters: list[AreaEmitter], triangle_emitter: np.ndarray, areas: np.ndarray, out: LightRows
) -> np.ndarray:
    """One row per emitting triangle of non-zero area (triangle_emitter: each triangle's index into `emitters`,
    or -1); returns those triangles' indices, in row order. A light showing an image refers to its texture row
    (Light.texture); its power estimate uses the image's mean radiance."""
    emitting = np.flatnonzero((triangle_emitter >= 0) & (areas > 0))
    emitter_rows: list[tuple[int, int, float]] = []  # spectrum offset, texture, scale
    for e in emitters:
        if e.image is None:
            emitter_rows.append((out.table.add(e.radiance), NO_TEXTURE, 1.0))
        else:
            basis = None if e.image.primaries is None else [out.table.add(p) for p in e.image.primaries]
            texture = out.textures.add(e.image.texture, "emission", basis=basis)
            emitter_rows.append((basis[0] if basis else 0, texture, e.image.scale))
    for t in emitting:
        e = emitters[triangle_emitter[t]]
        spectrum_offset, texture, scale = emitter_rows[triangle_emitter[t]]
        out.add(
            light_row(
                out.code(TRIANGLE),
                spectrum_offset,
                triangle=int(t),
                area=areas[t],
                two_sided=e.two_sided,
                scale=scale,
                texture=texture,
                **_polarization_fields(e),
            ),
            np.pi * areas[t] * e.radiance.mean() * (2.0 if e.two_sided else 1.0),
        )
    return emitting


def write_shape_rows(emitters: list[tuple[AreaEmitter, int, "AnalyticSurface"]], out: LightRows) -> list[int]:
    """One row per emitting analytic shape (its emitter, its index among the scene's analytic shapes, its surface):
    SPHERE for a whole sphere (sampled by the cone it subtends), SHAPE for a disk, a cylinder or a partial sphere
    (sampled by area); returns the row indices, in order."""
    indices = []
    for e, shape_index, surface in emitters:
        if e.image is None:
            spectrum_offset, texture, scale = out.table.add(e.radiance), NO_TEXTURE, 1.0
        else:
            basis = None if e.image.primaries is None else [out.table.add(p) for p in e.image.primaries]
            texture = out.textures.add(e.image.texture, "emission", basis=basis)
            spectrum_offset, scale = (basis[0] if basis else 0), e.image.scale
        area = surface.area()
        row = light_row(
            out.code(SPHERE if surface.kind == "sphere" and not surface.partial else SHAPE),
            spectrum_offset,
            triangle=shape_index,
            area=area,
            two_sided=e.two_sided,
            scale=scale,
            texture=texture,
            **_polarization_fields(e),
        )
        if surface.kind == "sphere" and not surface.partial:  # Light.position: the centre, with the radius in w
            centre, radius = surface.sphere_centre_radius()
            row = ((*centre, radius), *row[1:])
        indices.append(len(out.rows))
        out.add(row, np.pi * area * e.radiance.mean() * (2.0 if e.two_sided else 1.0))
    return indices


def from_mitsuba(importer, emitter, properties) -> dict | None:
    """A shape's emitter table (one-sided toward the face normal, as Mitsuba's area light)."""
    radiance = importer.child(properties, "radiance", emitter)
    spectrum = importer.spectrum(radiance, "radiance")
    return None if spectrum is None else {"radiance": spectrum}


def from_pbrt(context, light, area) -> dict:
    """pbrt-v4's diffuse area light; `area()` is the shape's area, which `power` is spread over (each side's)."""
    if light.find("filename") is not None:
        raise context.error(light.location, "an area light showing an image file is not imported")
    two_sided = context.boolean(light, "twosided", False)
    scale = context.one(light, "scale", 1.0)
    power = context.one(light, "power", -1.0)
    if power > 0:
        shape_area = area()
        # Radiance = power / (sides · area · π): a shape without area would need infinite radiance.
        if not (shape_area > 0.0 and math.isfinite(shape_area)):
            raise context.error(
                light.location, f'"power" needs a shape with a positive finite area, got area {shape_area:g}'
            )
        scale *= power / ((2.0 if two_sided else 1.0) * shape_area * math.pi)
    table: dict[str, object] = {"radiance": context.emission(light, "L", scale)}
    if two_sided:
        table["two_sided"] = True
    return table


def to_mitsuba(emitter: AreaEmitter, exporter, owner: str) -> dict:
    """Mitsuba's area light has one spectrum and emits on the front face only; `owner` names the shape."""
    if emitter.image is not None:
        raise exporter.refuse(f"{owner} shows an image; Mitsuba's area light has one spectrum")
    if emitter.two_sided:
        raise exporter.refuse(f"{owner} emits on both faces; Mitsuba's area light is one-sided")
    if emitter.stokes is not None:
        raise exporter.refuse(f"{owner} emits polarised light; Mitsuba's area light is unpolarised")
    return {"type": "area", "radiance": exporter.spectrum(emitter.radiance)}
