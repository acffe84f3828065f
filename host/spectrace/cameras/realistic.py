"""`realistic`: a camera behind a thick lens system (kernels/camera_realistic.cl; pbrt-v4's `realistic` camera,
Pharr, Jakob & Humphreys, 4th ed., 5.3, after Kolb, Mitchell & Hanrahan 1995).

The lens is a stack of spherical surfaces and one aperture stop, read from a lens file in pbrt's format (four
numbers a surface, scene side first: radius of curvature, thickness to the next surface, index of refraction after
the surface, clear aperture diameter, all lengths in mm; `#` starts a comment; scenes/lenses/ holds published
prescriptions). Lengths in the file are millimetres and scene units metres (as pbrt-v4). `origin` is the centre
of the film, which faces `target`; the film is `film_diagonal` mm across its diagonal with the image's aspect ratio.

A camera ray starts at its film position toward a point drawn uniformly in the bounds of the exit pupil seen from
that film position on the rear vertex's plane (one 2D draw after the film position's, as the thin lens draws its lens
point; the bounds are traced when the lens is focused, per ring of film radius, as pbrt-v4 does), and is refracted
at each surface in turn (Snell's law, the surface's normal; total internal reflection loses the ray) or stopped by
the stop; a ray that
meets a surface outside its clear aperture is lost (vignetting). Its weight is cos⁴θ · A / z², θ the angle of the
film-to-pupil segment to the axis, A the bounds' area and z the film-to-rear-vertex distance (pbrt-v4's weight), so
the image of a uniform radiance L is L times the film's irradiance factor E(x) = ∫ cos⁴θ / z² dA over the points of
the rear plane whose rays pass.

Focus: the lens group moves along the axis (the last surface's thickness changes) until a point at
`focus_distance` in front of the film images on it, by the Gaussian thick-lens relation between the principal planes
and focal points traced with near-axis rays (as pbrt-v4's FocusThickLens). The stop's diameter is
`aperture_diameter` mm, at most the file's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.cameras.shared import frame
from spectrace.core.parameters import REQUIRED, Parameter, Range
from spectrace.errors import SpectraceError

NAME = "realistic"
MITSUBA_PLUGINS: tuple[str, ...] = ()
MITSUBA_NONE = "Mitsuba 3 has no lens-system sensor"
PBRT_CAMERAS = ("realistic",)
# Surfaces a lens may have: RenderParams.lens_elements holds a header row and one row per surface.
MAX_SURFACES = 31
MM = 1e-3  # scene units (metres) per millimetre
LENS_FILE = Parameter(
    "lens_file",
    "string",
    "",
    REQUIRED,
    doc="the lens prescription in pbrt's format, relative to the scene file (or the name of one in "
    "scenes/lenses/, e.g. `dgauss.50mm.dat`)",
)
APERTURE_DIAMETER = Parameter(
    "aperture_diameter", "float", "mm", 1.0, Range(0.0, low_open=True), doc="the stop's opening, at most the file's"
)
FOCUS_DISTANCE = Parameter(
    "focus_distance", "float", "scene units", 10.0, Range(0.0, low_open=True), doc="from the film to the plane in focus"
)
FILM_DIAGONAL = Parameter("film_diagonal", "float", "mm", 35.0, Range(0.0, low_open=True), doc="the film's diagonal")
PARAMETERS = (LENS_FILE, APERTURE_DIAMETER, FOCUS_DISTANCE, FILM_DIAGONAL)


@dataclass(frozen=True)
class LensSystem:
    """A focused lens: surfaces scene side first as (radius, thickness, eta, aperture radius) in scene units (eta 1
    for air, radius 0 for the stop), the last thickness the rear surface's distance to the film."""

    surfaces: tuple[tuple[float, float, float, float], ...]
    film_diagonal: float  # scene units
    # Per ring of film radius (LENS_PUPIL_BINS equal rings out to half the diagonal): the bounds (x0, y0, x1, y1) on
    # the rear vertex's plane of the points a film point on the ring's +x half-axis sees through the lens (all zero
    # where none): camera rays are drawn there, turned to the film point's azimuth (`exit_pupils`).
    pupils: tuple[tuple[float, float, float, float], ...] = ()

    @property
    def rear_distance(self) -> float:
        return self.surfaces[-1][1]

    @property
    def effective_focal_length(self) -> float:
        points = cardinal_points(self.surfaces, 1e-3 * self.film_diagonal)
        assert points is not None  # lens_system made sure near-axis rays pass
        return points[2]

    def film_half_extent(self, aspect_ratio: float) -> tuple[float, float]:
        """Half the film's width and height for width / height = aspect_ratio."""
        width = self.film_diagonal / math.sqrt(1.0 + 1.0 / (aspect_ratio * aspect_ratio))
        return width / 2.0, width / aspect_ratio / 2.0


def read_lens_file(path: Path, where: str) -> np.ndarray:
    """The rows (n × 4, mm) of a lens file in pbrt's format."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise SpectraceError(f"cannot read lens file {path}: {exc.strerror or exc}", where=where) from None
    except UnicodeDecodeError:
        raise SpectraceError(f"cannot read lens file {path}: not text", where=where) from None
    numbers: list[float] = []
    for number, line in enumerate(text.splitlines(), 1):
        for token in line.split("#", 1)[0].split():
            try:
                value = float(token)
            except ValueError:
                raise SpectraceError(f"{path}:{number}: expected a number, got '{token[:40]}'", where=where) from None
            if not math.isfinite(value):
                raise SpectraceError(f"{path}:{number}: {token} is not a finite number", where=where)
            numbers.append(value)
    if not numbers or len(numbers) % 4:
        raise SpectraceError(
            f"{path}: a lens file holds 4 numbers a surface (radius, thickness, eta, aperture), got {len(numbers)}",
            where=where,
        )
    rows = np.asarray(numbers, np.float64).reshape(-1, 4)
    if len(rows) > MAX_SURFACES:
        raise SpectraceError(f"{path}: {len(rows)} surfaces, spectrace takes at most {MAX_SURFACES}", where=where)
    if np.count_nonzero(rows[:, 0] == 0.0) > 1:
        raise SpectraceError(f"{path}: more than one aperture stop (radius 0)", where=where)
    if np.any(rows[:, 1] < 0.0) or np.any(rows[:, 3] <= 0.0) or np.any((rows[:, 2] < 1.0) & (rows[:, 2] != 0.0)):
        raise SpectraceError(
            f"{path}: thicknesses must be >= 0, apertures > 0 and indices 0 (air) or >= 1", where=where
        )
    return rows


PLACEHOLDER_LENS = "dgauss.50mm.dat"  # the bundled lens that stands in for a missing lens file (pbrt import)


def lens_file_path(name: str, folder: Path) -> Path:
    """`name` relative to the scene's folder; a bare name found only among the bundled lenses is that one."""
    from spectrace.resources import scenes_dir

    path = folder / name
    bundled = scenes_dir() / "lenses" / name
    return bundled if not path.exists() and Path(name).name == name and bundled.is_file() else path


def lens_system(
    rows_mm,
    aperture_diameter: float = 1.0,
    focus_distance: float = 10.0,
    film_diagonal: float = 35.0,
    where: str | None = None,
) -> LensSystem:
    """The lens of `rows_mm` (a lens file's rows) with its stop opened to `aperture_diameter` mm (at most the
    file's), focused on `focus_distance` scene units from the film; `film_diagonal` in mm."""
    rows = np.asarray(rows_mm, np.float64).reshape(-1, 4)
    surfaces = []
    for radius, thickness, eta, aperture in rows:
        if radius == 0.0:
            aperture = min(aperture, aperture_diameter)
        surfaces.append((radius * MM, thickness * MM, eta if eta != 0.0 else 1.0, aperture * MM / 2.0))
    diagonal = film_diagonal * MM
    points = cardinal_points(tuple(surfaces), 1e-3 * diagonal)
    if points is None:
        raise SpectraceError("no near-axis ray passes the lens: its stop is too small or it does not focus", where)
    principal, principal_image, focal = points[0], points[1], points[2]
    # Gaussian imaging between the principal planes: object distance s = D − P, image distance s' = P' (from the
    # film, after the move δ); s + s' = L does not change with δ and 1/s + 1/s' = 1/f gives s' (L − s') = f L, whose
    # smaller root is the image nearer the focal point.
    span = focus_distance - principal + principal_image
    discriminant = span * (span - 4.0 * focal)
    if not (focal > 0.0 and span > 0.0 and discriminant > 0.0):
        raise SpectraceError(
            f"the lens (focal length {focal / MM:.4g} mm) cannot focus at {focus_distance:g} scene units: "
            "more than 4 focal lengths are needed",
            where,
        )
    image = (span - math.sqrt(discriminant)) / 2.0
    radius, thickness, eta, aperture = surfaces[-1]
    surfaces[-1] = (radius, thickness + image - principal_image, eta, aperture)
    focused = tuple(surfaces)
    return LensSystem(focused, diagonal, exit_pupils(focused, diagonal))


def exit_pupils(surfaces, film_diagonal: float, side: int = 64) -> tuple[tuple[float, float, float, float], ...]:
    """The exit pupil's bounds for each ring of film radius (LensSystem.pupils): rays from film points spread over
    the ring's +x segment to a side × side grid over 1.5 times the rear element's clear square, those that pass
    bounded, the bounds widened by two grid steps (a pupil's edge may fall between points)."""
    from spectrace.core.contract import LENS_PUPIL_BINS

    rear, rear_radius = surfaces[-1][1], surfaces[-1][3]
    extent = 1.5 * rear_radius
    steps = (np.arange(side) + 0.5) / side * 2.0 - 1.0
    gx, gy = (np.tile(extent * a.ravel(), LENS_PUPIL_BINS) for a in np.meshgrid(steps, steps))
    count = side * side
    ring = np.repeat(np.arange(LENS_PUPIL_BINS), count)
    # Film positions within each ring paired with the grid points by a golden-ratio sequence (no alignment).
    spread = (np.arange(count * LENS_PUPIL_BINS) * 0.6180339887498949) % 1.0
    film_x = (ring + spread) / LENS_PUPIL_BINS * film_diagonal / 2.0
    origins = np.column_stack([film_x, np.zeros_like(film_x), np.zeros_like(film_x)])
    directions = np.column_stack([gx - film_x, gy, np.full_like(film_x, rear)])
    _, _, passed = trace(surfaces, origins, directions, from_film=True)
    margin = 2.0 * (2.0 * extent / side)
    pupils = []
    for index in range(LENS_PUPIL_BINS):
        hits = passed & (ring == index)
        if not hits.any():
            pupils.append((0.0, 0.0, 0.0, 0.0))
            continue
        x, y = gx[hits], gy[hits]
        pupils.append((x.min() - margin, y.min() - margin, x.max() + margin, y.max() + margin))
    return tuple((float(x0), float(y0), float(x1), float(y1)) for x0, y0, x1, y1 in pupils)


def _vertices(surfaces) -> np.ndarray:
    """Each surface's vertex distance from the film (scene side +z)."""
    thickness = np.array([s[1] for s in surfaces])
    return np.cumsum(thickness[::-1])[::-1]


def trace(surfaces, origins, directions, from_film: bool):
    """Rays (n × 3, lens space: film at z = 0, the scene toward +z) through the lens, from the film side or from the
    scene side: (origins, unit directions, passed) where they leave it."""
    z_vertex = _vertices(surfaces)
    o = np.array(origins, np.float64, ndmin=2)
    d = np.array(directions, np.float64, ndmin=2)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    passed = np.ones(len(o), bool)
    order = range(len(surfaces) - 1, -1, -1) if from_film else range(len(surfaces))
    for i in order:
        radius, _, eta, aperture = surfaces[i]
        scene_side = surfaces[i - 1][2] if i > 0 else 1.0
        if radius == 0.0:
            t = (z_vertex[i] - o[:, 2]) / d[:, 2]
            passed &= t >= 0.0
            normal = None
        else:
            centre = np.array([0.0, 0.0, z_vertex[i] - radius])
            oc = o - centre
            b = np.sum(oc * d, axis=1)
            c = np.sum(oc * oc, axis=1) - radius * radius
            disc = b * b - c
            passed &= disc >= 0.0
            root = np.sqrt(np.maximum(disc, 0.0))
            # The cap around the vertex: the far crossing where the centre lies behind the travel, else the near.
            far = (radius > 0.0) == (d[:, 2] > 0.0)
            t = np.where(far, -b + root, -b - root)
            passed &= t > 0.0
            normal = o + t[:, None] * d - centre
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        o = o + t[:, None] * d
        passed &= o[:, 0] ** 2 + o[:, 1] ** 2 <= aperture * aperture
        if normal is not None:
            n_i, n_t = (eta, scene_side) if from_film else (scene_side, eta)
            d, refracted = _refract(d, normal, n_t / n_i)
            passed &= refracted
    return o, d, passed


def _refract(d: np.ndarray, normal: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Directions d refracted at normals into a medium eta times denser; whether each passes (no total internal
    reflection)."""
    cos_i = -np.sum(d * normal, axis=1)
    normal = np.where(cos_i[:, None] < 0.0, -normal, normal)
    cos_i = np.abs(cos_i)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    out = d / eta + (cos_i / eta - cos_t)[:, None] * normal
    return out / np.linalg.norm(out, axis=1, keepdims=True), sin2_t < 1.0


def cardinal_points(surfaces, height: float) -> tuple[float, float, float] | None:
    """(P, P', f): the distances from the film of the object-side principal plane P and the image-side one P', and
    the effective focal length f, from rays parallel to the axis at `height` traced through the lens both ways; None
    where either is blocked."""
    front = float(_vertices(surfaces)[0])
    o, d, passed = trace(surfaces, [[height, 0.0, front + 1.0]], [[0.0, 0.0, -1.0]], from_film=False)
    o_back, d_back, passed_back = trace(surfaces, [[height, 0.0, -1.0]], [[0.0, 0.0, 1.0]], from_film=True)
    if not (passed[0] and passed_back[0]) or d[0, 0] == 0.0 or d_back[0, 0] == 0.0:
        return None
    # The image-side ray crosses the axis at the focal point F' and reaches `height` at P'.
    focal_image = o[0, 2] + (-o[0, 0] / d[0, 0]) * d[0, 2]
    principal_image = o[0, 2] + ((height - o[0, 0]) / d[0, 0]) * d[0, 2]
    principal = o_back[0, 2] + ((height - o_back[0, 0]) / d_back[0, 0]) * d_back[0, 2]
    return float(principal), float(principal_image), float(principal_image - focal_image)


def basis(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The frame, with right and up scaled as the pinhole of the same field (half film extent over the focal
    length), which the ray differentials of texture filtering take."""
    origin, forward, right, up = frame(camera)
    half_width, half_height = camera.lens_system.film_half_extent(aspect_ratio)
    focal = camera.lens_system.effective_focal_length
    return origin, forward, right * (half_width / focal), up * (half_height / focal)


def lens(camera) -> tuple[float, float]:
    return 0.0, 0.0


def device_lens(camera, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """RenderParams.lens_elements: a header (half film width, half film height, surface count, rear aperture
    radius), then each surface from the film side: (radius, vertex distance from the film, n_scene side /
    n_film side, aperture radius), radius 0 for the stop; and RenderParams.lens_pupils, the exit pupil's bounds per
    ring of film radius (LensSystem.pupils)."""
    system: LensSystem = camera.lens_system
    surfaces = system.surfaces
    rows = np.zeros((MAX_SURFACES + 1, 4), np.float32)
    rows[0] = (*system.film_half_extent(aspect_ratio), len(surfaces), surfaces[-1][3])
    z_vertex = _vertices(surfaces)
    for row, i in enumerate(range(len(surfaces) - 1, -1, -1), 1):
        radius, _, eta, aperture = surfaces[i]
        scene_side = surfaces[i - 1][2] if i > 0 else 1.0
        rows[row] = (radius, z_vertex[i], scene_side / eta, aperture)
    return rows, np.asarray(system.pupils, np.float32)


def from_pbrt(context, camera, view) -> dict:
    """pbrt-v4's realistic camera: `lensfile` (relative to the pbrt file), `aperturediameter` (mm, default 1),
    `focusdistance` (default 10) and the film's `diagonal` (mm, default 35); its camera space's origin is the
    film's centre. A diaphragm image (`aperture`) is not imported."""
    if context.absent(camera, "lensfile", f"the bundled lens {PLACEHOLDER_LENS}"):
        lens_file = PLACEHOLDER_LENS  # a bare name: the bundled lens (lens_file_path)
    elif (path := context.file_path(camera, "lensfile")) is not None:
        lens_file = context.relative(path)
    else:
        raise context.error(camera.location, 'the realistic camera needs "string lensfile" (as pbrt-v4)')
    if (shape := camera.find("aperture")) is not None:
        context.warn(shape.location, f'"{shape.label()}" (a diaphragm image) not imported: the stop is round')
    film = context.scene.film
    table = {
        "type": "realistic",
        "origin": view.origin,
        "target": (np.asarray(view.origin) + np.asarray(view.forward)).tolist(),
        "up": view.up,
        "lens_file": lens_file,
        "aperture_diameter": context.one(camera, "aperturediameter", 1.0),
        "focus_distance": context.one(camera, "focusdistance", 10.0),
        "film_diagonal": context.one(film, "diagonal", 35.0) if film is not None else 35.0,
    }
    if view.lens_radius > 0.0:
        context.warn(camera.location, '"lensradius" not imported: the realistic camera\'s lens is its lens file')
    return table
