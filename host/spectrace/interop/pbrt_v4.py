"""pbrt-v4 scenes -> spectrace scene TOML, for the subset spectrace represents (docs/pbrt.md).

spectrace.interop.pbrt_parser reads the file (tokens, directives, graphics state, instances expanded); this module
maps what it read onto spectrace's scene format, with the same writer (spectrace.interop.toml_writer), the same
checks on the output and the same one-line errors as the Mitsuba importer.

Conventions it bridges (each checked by tests/interop/test_pbrt_import.py):
- Handedness: pbrt's camera has image right = up × forward; spectrace's (as Mitsuba's) forward × up. The whole scene
  is mirrored through x = 0 when the camera's own transform does not already mirror (exported scenes often start
  with `Scale -1 1 1`), so the image is pbrt's. spectrace keeps a mirrored mesh's fronts where its winding put them,
  as pbrt does.
- Field of view: pbrt's `fov` spans the shorter image axis; it becomes spectrace's fov on that axis.
- Depth: pbrt's `maxdepth` counts bounces (1 = direct light); spectrace's max_depth counts segments: maxdepth + 1.
- Lights: pbrt-v4 divides every light's spectrum by its photometric integral ∫ȳ(λ)s(λ)dλ (an RGB illuminant by that
  of the colour space's D65) and its film sums ∫x̄L, ∫ȳL, ∫z̄L without spectrace's 1/∫ȳ: a light of `scale` k shows as
  luminance factor Y = k in both once spectrace's spectrum is s scaled to Y = k. `power` (point, spot, area) and
  `illuminance` (distant, infinite) rescale it exactly as pbrt-v4's light constructors do.
- Spectra: RGB stays RGB (both uplift with Jakob & Hanika's sigmoid), `blackbody` is Planck's law, named spectra map
  to spectrace's data: metal-{Ag,Al,Au,Cu}-{eta,k} to spectra/metals, glass-BK7 to N-BK7 and glass-F11 to N-SF11
  (SCHOTT Sellmeier), stdillum-* to the CIE illuminants. Wavelength/value lists are zero outside their range, as in
  pbrt.
- Files: meshes pbrt gives inline (trianglemesh, bilinearmesh) and the shapes spectrace has no exact surface for
  (partial spheres, disks and cylinders) are written as binary PLY files into a folder beside the TOML; PLY files a
  scene names are rewritten there too (pbrt's ReverseOrientation and normal-facing rules applied, gzipped files
  read); environment maps (resampled, spectrace.interop.pbrt_envmap) and scaled image textures go there as OpenEXR.

Anything the file states that is not imported is reported: a parameter no mapping read, or a directive spectrace
has no counterpart for, as a warning naming file:line (an error with strict=True); an entity of a type spectrace
cannot represent (a realistic camera, a `measured` material, a goniometric light, a `curve` shape) as an error
naming file:line.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path

import numpy as np

from spectrace.core.limits import linear_map_problem
from spectrace.errors import SpectraceError
from spectrace.geometry.analytic import similarity_problem
from spectrace.geometry.mesh import winding_against_normals
from spectrace.interop.pbrt_parser import (
    Entity,
    Location,
    PbrtScene,
    Shape,
    error,
    read_scene,
    shown,
)
from spectrace.io.output_files import check_output_file
from spectrace.pixel_filters import PixelFilter
from spectrace.spectral.metals import METALS as SPECTRACE_METALS

SHAPES = ("trianglemesh", "plymesh", "bilinearmesh", "loopsubdiv", "sphere", "disk", "cylinder")
MATERIALS = (
    "diffuse",
    "conductor",
    "dielectric",
    "thindielectric",
    "coateddiffuse",
    "diffusetransmission",
    "interface",
    "mix",
)
LIGHTS = ("point", "spot", "distant", "infinite")
AREA_LIGHTS = ("diffuse",)
TEXTURES = ("imagemap", "checkerboard", "constant")
# Materials spectrace has no counterpart for, refused with this reason.
_NO_EQUIVALENT = {
    "coatedconductor": "spectrace has no coated conductor",
    "measured": "spectrace has no measured BRDFs",
    "hair": "spectrace has no hair model",
    "subsurface": "spectrace's subsurface scattering is a medium inside a shape, not a material",
}
# Unbiased integrators that converge to the path tracer's image.
_SAME_IMAGE_INTEGRATORS = ("bdpt", "mlt", "sppm", "lightpath", "randomwalk")
_METALS = ("Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2")  # pbrt's metal-X-eta / metal-X-k: spectra/metals/X.csv
# pbrt-v4's named glasses; spectra/glasses/sellmeier.csv notes how close each of pbrt's tables is to the formula.
_GLASSES = {
    "glass-BK7": "N-BK7",
    "glass-BAF10": "N-BAF10",
    "glass-FK51A": "N-FK51A",
    "glass-LASF9": "N-LASF9",
    "glass-F5": "N-SF5",
    "glass-F10": "N-SF10",
    "glass-F11": "N-SF11",
}
_ILLUMINANTS = {"stdillum-A": "A", "stdillum-D50": "D50", "stdillum-D65": "D65"} | {
    f"stdillum-F{i}": f"FL{i}" for i in range(1, 13)
}
PBRT_DEFAULT_FILM = (1280, 720)
PBRT_DEFAULT_FOV = 90.0
PBRT_DEFAULT_MAXDEPTH = 5
PBRT_DEFAULT_SPP = 16
TESSELLATION_SEGMENTS = 128  # disk and cylinder: the polygon's area is 0.9996 of the circle's
_MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


@dataclass
class MeshData:
    vertices: np.ndarray  # (n, 3) object space
    faces: np.ndarray  # (m, 3) int, winding = front (pbrt's rules applied)
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None  # pbrt's (u, v) as stored

    def world_area(self, matrix: np.ndarray) -> float:
        points = self.vertices @ matrix[:3, :3].T
        a, b, c = (points[self.faces[:, i]] for i in range(3))
        return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def _name(base: str, taken) -> str:
    name = re.sub(r"[^A-Za-z0-9_-]", "_", base) or "item"
    candidate, number = name, 2
    while candidate in taken:
        candidate, number = f"{name}_{number}", number + 1
    return candidate


def _grouped(warnings: list[str]) -> list[str]:
    """Warnings with the same message at several lines as one line: the first place, and how many more."""
    groups: dict[str, list[str]] = {}
    for warning in warnings:
        match = re.match(r"(.*?:\d+): (.*)", warning)
        place, message = (match.group(1), match.group(2)) if match else ("", warning)
        groups.setdefault(message, []).append(place)
    return [
        f"{places[0]}: {message}" + (f" (and {len(places) - 1} more like it)" if len(places) > 1 else "")
        if places[0]
        else message
        for message, places in groups.items()
    ]


def _luminance_factor(table: dict) -> float:
    """Y (spectrace's film: ∫ȳ L / ∫ȳ) of a spectrum table without its scale."""
    from spectrace.spectral import library_spectrum, parse_inline_spectrum, spectrum_to_xyz
    from spectrace.spectral.blackbody import blackbody

    if "blackbody" in table:
        spectrum = blackbody(float(table["blackbody"]))
    elif "spectrum" in table:
        spectrum = library_spectrum(table["spectrum"])
    elif "values" in table:
        spectrum = parse_inline_spectrum(table["values"], where="spectrum")
    else:  # rgb: an RGB illuminant, whose photometric normalisation in pbrt-v4 is the colour space's D65 (Y = 1)
        return 1.0
    return float(spectrum_to_xyz(spectrum)[1])


class PbrtImporter:
    """One import: the parsed scene, where the TOML goes, and what was not imported."""

    def __init__(self, scene: PbrtScene, source: Path, toml_folder: Path, mesh_folder: str):
        self.scene = scene
        self.source = source
        self.toml_folder = toml_folder
        self.mesh_folder = mesh_folder
        self.warnings: list[str] = list(scene.unsupported)
        self.notes: list[str] = []
        self.meshes: dict[str, MeshData] = {}  # file name in mesh_folder -> data
        self.files: dict[str, np.ndarray] = {}  # environment maps (EXR) to write beside the meshes
        self._mesh_of: dict[tuple[int, bool, bool], tuple[str, MeshData]] = {}
        self.materials: dict[str, dict] = {}
        self._material_of: dict[int | str, str | None] = {}
        self.textures: dict[str, dict] = {}
        self._texture_of: dict[tuple[str, str], str] = {}
        self._interior_of: dict[str, dict] = {}
        self.world = np.eye(4)  # spectrace world from pbrt world: the handedness mirror, or not
        self.origins: dict[str, Location] = {}  # TOML key path -> where in the pbrt files it came from
        self.read: set[int] = set()  # the entities mapped (their unread parameters are reported)

    # -------------------------------------------------- parameters

    def warn(self, location: Location, message: str) -> None:
        self.warnings.append(f"{location}: {message}")

    def floats(self, entity: Entity, name: str, default: list[float] | None = None, *types: str) -> list[float] | None:
        parameter = entity.find(name, *(types or ("float",)))
        if parameter is None:
            return default
        if any(isinstance(v, (str, bool)) for v in parameter.values):
            raise error(parameter.location, f'"{parameter.label()}" takes numbers')
        return [float(v) for v in parameter.values]

    def one(self, entity: Entity, name: str, default: float, *types: str) -> float:
        values = self.floats(entity, name, None, *(types or ("float",)))
        return default if values is None else values[0]

    def integer(self, entity: Entity, name: str, default: int, low: int | None = None) -> int:
        parameter = entity.find(name, "integer")
        if parameter is None:
            return default
        value = parameter.values[0]
        if value != int(value) or (low is not None and value < low):
            limit = f" >= {low}" if low is not None else ""
            raise error(parameter.location, f'"{parameter.label()}" must be an integer{limit}, got {value:g}')
        return int(value)

    def vector(self, entity: Entity, name: str, default: list[float]) -> list[float]:
        values = self.floats(entity, name, None, "point3", "point", "vector3", "vector")
        return default if values is None else values[:3]

    def string(self, entity: Entity, name: str, default: str | None = None) -> str | None:
        parameter = entity.find(name, "string")
        return default if parameter is None else str(parameter.values[0])

    def boolean(self, entity: Entity, name: str, default: bool) -> bool:
        parameter = entity.find(name, "bool")
        return default if parameter is None else bool(parameter.values[0])

    def file_path(self, entity: Entity, name: str) -> Path | None:
        value = self.string(entity, name)
        if value is None:
            return None
        path = Path(value)
        path = path if path.is_absolute() else entity.location.file.parent / path
        if not path.is_file():
            parameter = entity.find(name)
            raise error(parameter.location if parameter else entity.location, f"'{shown(value, 200)}' is not a file")
        return path

    def relative(self, path: Path) -> str:
        try:
            return Path(os.path.relpath(path.resolve(), self.toml_folder.resolve())).as_posix()
        except ValueError:  # another drive on Windows
            return path.resolve().as_posix()

    def point(self, matrix: np.ndarray, xyz: list[float]) -> list[float]:
        return (self.world @ matrix @ np.array([*xyz, 1.0]))[:3].tolist()

    def direction(self, matrix: np.ndarray, xyz) -> list[float]:
        vector = (self.world @ matrix)[:3, :3] @ np.asarray(xyz, dtype=np.float64)
        return (vector / np.linalg.norm(vector)).tolist()

    # -------------------------------------------------- spectra

    def spectrum(self, entity: Entity, name: str, role: str) -> dict | None:
        """A spectrum parameter as a spectrace spectrum table (None when absent). role: "albedo" (an RGB must be in
        [0, 1]), "unbounded" or "illuminant"."""
        parameter = entity.find(name, "rgb", "spectrum", "blackbody", "float")
        if parameter is None:
            return None
        values = parameter.values
        if parameter.type == "float":
            if role == "illuminant":
                raise error(
                    parameter.location, f'"{parameter.label()}": give a light\'s spectrum as rgb, spectrum or blackbody'
                )
            return {"value": float(values[0])}
        if parameter.type == "rgb":
            rgb = [float(v) for v in values[:3]]
            if min(rgb) < 0 or (role == "albedo" and max(rgb) > 1):
                bound = "[0, 1]" if role == "albedo" else ">= 0"
                raise error(parameter.location, f'"{parameter.label()}" components must lie in {bound}, got {rgb}')
            if role == "medium":
                return {"rgb": rgb}
            if role == "unbounded":
                raise error(parameter.location, f'"{parameter.label()}": give an index of refraction as a spectrum')
            return {"rgb": rgb}
        if parameter.type == "blackbody":
            if not values[0] > 0:
                raise error(parameter.location, f'"{parameter.label()}" needs a temperature > 0 K')
            return {"blackbody": float(values[0])}
        if isinstance(values[0], str):
            return self.named_spectrum(values[0], parameter.location, role, parameter.label())
        return {"values": self.pairs([float(v) for v in values], parameter.location, parameter.label(), role)}

    def pairs(self, numbers: list[float], location: Location, label: str, role: str = "") -> list[list[float]]:
        """Wavelength/value pairs as pbrt reads them: zero outside their range (spectrace holds the end values, so
        zeros are added at the ends), except for an index of refraction (role "unbounded"), where pbrt's zero (a
        metal of η = k = 0, a perfect mirror) is no index: the end values are held instead, with a note."""
        if len(numbers) % 2 or len(numbers) < 4:
            raise error(location, f'"{label}" needs wavelength/value pairs, at least two')
        pairs = [[numbers[i], numbers[i + 1]] for i in range(0, len(numbers), 2)]
        if any(b[0] <= a[0] for a, b in zip(pairs, pairs[1:], strict=False)):
            raise error(location, f'"{label}": wavelengths must increase')
        if role == "unbounded":
            if pairs[0][0] > 360.0 or pairs[-1][0] < 830.0:
                self.notes.append(
                    f'{location}: "{label}" covers {pairs[0][0]:g}-{pairs[-1][0]:g} nm: its end values are held to '
                    "360-830 nm (pbrt has 0 there)"
                )
            return pairs
        if pairs[0][0] > 360.0:
            pairs.insert(0, [pairs[0][0] - 1e-3, 0.0])
        if pairs[-1][0] < 830.0:
            pairs.append([pairs[-1][0] + 1e-3, 0.0])
        return pairs

    def named_spectrum(self, name: str, location: Location, role: str, label: str) -> dict | None:
        metal = re.fullmatch(r"metal-(\w+)-(eta|k)", name)
        if metal and metal.group(1) in _METALS:
            return {"spectrum": f"metals/{metal.group(1)}:{metal.group(2)}"}
        if name in _ILLUMINANTS:
            return {"spectrum": f"cie:{_ILLUMINANTS[name]}"}
        if name in _GLASSES:
            return {"glass": _GLASSES[name]}
        path = Path(name) if Path(name).is_absolute() else location.file.parent / name
        if path.is_file():
            try:
                numbers = [float(x) for x in re.sub(r"#[^\n]*", " ", path.read_text()).split()]
            except (OSError, ValueError, UnicodeError):
                raise error(
                    location, f"\"{label}\": '{shown(name, 200)}' is not a file of wavelength/value pairs"
                ) from None
            return {"values": self.pairs(numbers, location, label, role)}
        known = (
            "metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k}, glass-{BK7,BAF10,FK51A,LASF9,F5,F10,F11}, "
            "stdillum-{A,D50,D65,F1..F12}"
        )
        raise error(
            location, f"\"{label}\": named spectrum '{shown(name)}' has no spectrace data (spectrace maps {known})"
        )

    def emission(self, entity: Entity, name: str, scale: float) -> dict:
        """pbrt-v4's light spectrum `name` (default: the colour space's D65) and `scale`, as a spectrace table whose
        luminance factor Y is pbrt's scale (see the module's notes)."""
        table = self.spectrum(entity, name, "illuminant") or {"spectrum": "cie:D65"}
        if "glass" in table:
            raise error(entity.location, f"{entity.label()}: a glass's index is no light spectrum")
        factor = _luminance_factor(table)
        if not factor > 0:
            raise error(entity.location, f"{entity.label()}: the light's spectrum has no luminance")
        return table | {"scale": scale / factor}

    # -------------------------------------------------- camera, film, sampler, integrator

    def camera(self, data: dict) -> None:
        scene = self.scene
        camera = scene.camera or Entity("Camera", "perspective", [], Location(self.source, 1))
        if camera.kind not in ("perspective", "orthographic", "spherical"):
            raise error(
                camera.location,
                f"camera '{shown(camera.kind)}': spectrace imports pbrt's perspective, orthographic and spherical "
                '(mapping "equirect") cameras',
            )
        if camera.kind == "spherical" and (mapping := self.string(camera, "mapping") or "equalarea") != "equirect":
            raise error(
                camera.location,
                f"spherical camera mapping '{shown(mapping)}' (pbrt-v4's default is equalarea): spectrace imports "
                'only "equirect", as its equirectangular camera',
            )
        width, height = PBRT_DEFAULT_FILM
        film = scene.film
        if film is not None:
            if film.kind not in ("rgb", "gbuffer", "spectral"):
                raise error(film.location, f"film '{shown(film.kind)}' (pbrt-v4 has rgb, gbuffer and spectral)")
            width = self.integer(film, "xresolution", width, low=1)
            height = self.integer(film, "yresolution", height, low=1)
            if (filename := self.string(film, "filename")) is not None:
                self.notes.append(f"{film.location}: the output file name '{shown(filename)}' is not imported")
        world_from_camera = np.linalg.inv(scene.camera_from_world)
        linear = world_from_camera[:3, :3]
        # pbrt's image right is the camera's +x = up × forward for a proper rotation; spectrace's is forward × up.
        # pbrt's spherical camera turns the other way: its longitude runs from +x toward +z, i.e. from right to
        # left as seen from inside, where spectrace's equirectangular runs left to right (see spherical_camera).
        mirrors = np.linalg.det(linear) > 0
        if camera.kind == "spherical":
            mirrors = not mirrors
        self.world = _MIRROR if mirrors else np.eye(4)
        gram = linear.T @ linear
        if not np.allclose(gram, np.eye(3) * gram[0, 0], rtol=1e-4, atol=1e-6 * gram[0, 0]):
            self.warn(
                camera.location,
                "the camera transform scales or shears unevenly: only its position and axes are imported",
            )
        if scene.camera_medium:
            self.warn(camera.location, f"the camera's medium '{shown(scene.camera_medium)}' not imported")
        origin = self.point(world_from_camera, [0.0, 0.0, 0.0])
        forward = self.direction(world_from_camera, [0.0, 0.0, 1.0])
        up = self.direction(world_from_camera, [0.0, 1.0, 0.0])
        aspect = self.one(camera, "frameaspectratio", width / height)
        # pbrt's default screen window spans [-1, 1] along the frame's shorter side.
        default_window = [-aspect, aspect, -1.0, 1.0] if aspect > 1.0 else [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect]
        window = camera.find("screenwindow")
        lens_radius = self.one(camera, "lensradius", 0.0)
        focus = self.one(camera, "focaldistance", 1e6)  # pbrt-v4's default
        if camera.kind == "spherical":
            data["camera"] = self.spherical_camera(camera, world_from_camera, origin, up)
        elif camera.kind == "orthographic":
            x0, x1, y0, y1 = self.floats(camera, "screenwindow", default_window) or default_window
            if not (x1 > x0 and y1 > y0):
                raise error(camera.location, "screenwindow must have x0 < x1 and y0 < y1")
            if not math.isclose((x1 - x0) / (y1 - y0), width / height, rel_tol=1e-4):
                self.warn(
                    camera.location,
                    "the screen window's aspect ratio differs from the film's: the window's width is kept",
                )
            # An off-centre window moves the view's centre in the camera's plane (pbrt's camera x is image right).
            centre = self.point(world_from_camera, [(x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0])
            data["camera"] = {
                "type": "orthographic",
                "origin": centre,
                "target": (np.asarray(centre) + np.asarray(forward)).tolist(),
                "up": up,
                "view_width": x1 - x0,
            }
            if lens_radius > 0.0:
                self.warn(camera.location, '"lensradius" not imported: spectrace\'s orthographic camera is sharp')
        else:
            if window is not None:
                self.warn(window.location, '"screenwindow" not imported (the image spans pbrt\'s default window)')
            fov = self.one(camera, "fov", PBRT_DEFAULT_FOV)
            if not 0.0 < fov < 180.0:
                raise error(camera.location, f"fov must lie in (0, 180) degrees, got {fov:g}")
            data["camera"] = {
                "origin": origin,
                "target": (np.asarray(origin) + np.asarray(forward)).tolist(),
                "up": up,
                "fov": fov,
                # pbrt's fov spans the shorter side of the frame.
                "fov_axis": "y" if aspect > 1.0 else "x",
            }
            if lens_radius > 0.0:
                if not focus > 0.0:
                    raise error(camera.location, f"focaldistance must be > 0, got {focus:g}")
                data["camera"] = {
                    "type": "thinlens",
                    **data["camera"],
                    "aperture_radius": lens_radius,
                    "focus_distance": focus,
                }
        data["film"] = {"width": width, "height": height, "filter": self.pixel_filter()}
        # pbrt-v4's sensor scales the image by ISO/100 times the shutter's open time; spectrace's film exposure
        # (stops) scales its RGB the same way.
        iso = self.one(film, "iso", 100.0) if film is not None else 100.0
        ratio = iso / 100.0 * (self.one(camera, "shutterclose", 1.0) - self.one(camera, "shutteropen", 0.0))
        if not ratio > 0:
            raise error(camera.location, "iso and the shutter times give no exposure")
        if ratio != 1.0:
            data["film"]["exposure"] = math.log2(ratio)

    def spherical_camera(self, camera: Entity, world_from_camera: np.ndarray, origin, up) -> dict:
        """pbrt-v4's spherical camera with mapping "equirect" as spectrace's equirectangular camera. pbrt-v4
        (cameras.cpp, SphericalCamera::GenerateRay) sends film position (u, v) in [0, 1]² along θ = π v, φ = 2π u,
        camera direction (sin θ cos φ, cos θ, sin θ sin φ): row 0 toward the camera's +y, the image's centre
        (φ = π) along its −x, φ growing from +x toward +z. spectrace's (kernels/camera.cl) sends (u, v) along
        θ = π v, φ' = 2π u − π, sin θ sin φ' right + cos θ up + sin θ cos φ' forward. The two agree with up = the
        camera's +y, forward = its −x and right = forward × up = its −z, which holds when the world is mirrored
        exactly when the perspective camera's is not (camera())."""
        if self.one(camera, "lensradius", 0.0) > 0.0:
            self.warn(camera.location, '"lensradius" not imported: the spherical camera is a pinhole')
        if camera.find("screenwindow") is not None:
            self.warn(camera.location, '"screenwindow" not imported: the spherical camera covers the whole sphere')
        forward = (-np.asarray(self.direction(world_from_camera, [1.0, 0.0, 0.0]))).tolist()
        return {
            "type": "equirectangular",
            "origin": origin,
            "target": (np.asarray(origin) + np.asarray(forward)).tolist(),
            "up": up,
        }

    def pixel_filter(self) -> dict:
        """pbrt-v4's PixelFilter; its default, as pbrt-v4's, is the Gaussian of σ = 0.5 and radius 1.5."""
        entity = self.scene.pixel_filter
        kind = entity.kind if entity is not None else "gaussian"
        defaults = {"box": 0.5, "gaussian": 1.5, "mitchell": 2.0, "triangle": 2.0}
        if kind not in defaults:
            assert entity is not None
            self.warn(entity.location, f"pixel filter '{shown(kind)}' not imported: a Gaussian filter used")
            kind = "gaussian"
        radius = defaults[kind]
        if entity is not None and kind == entity.kind:
            radius = self.one(entity, "xradius", radius)
            if self.one(entity, "yradius", radius) != radius:
                self.warn(entity.location, "yradius differs from xradius: spectrace's filters take one radius (x's)")
        if kind == "box":
            if radius != 0.5:
                assert entity is not None
                self.warn(entity.location, "a box filter's radius other than 0.5 is not imported")
            return {"type": "box"}
        if kind == "triangle":
            table: dict = {"type": "tent", "radius": radius}
        elif kind == "gaussian":
            sigma = self.one(entity, "sigma", 0.5) if entity is not None else 0.5
            table = {"type": "gaussian", "stddev": sigma, "radius": radius}
        else:
            b = self.one(entity, "B", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
            c = self.one(entity, "C", 1.0 / 3.0) if entity is not None else 1.0 / 3.0
            table = {"type": "mitchell", "radius": radius, "b": b, "c": c}
        try:  # the filters' own ranges and rules (spectrace.pixel_filters), at the file's line
            PixelFilter(**table)
        except SpectraceError as exc:
            assert entity is not None  # pbrt's default filter is valid
            raise error(entity.location, f"{exc.message} ({exc.where}, imported from PixelFilter)") from None
        return table

    def sampler(self, data: dict) -> None:
        sampler = self.scene.sampler
        spp, settings = PBRT_DEFAULT_SPP, dict[str, object]()
        if sampler is not None:
            spp = self.integer(sampler, "pixelsamples", spp, low=1)
            if (seed := sampler.find("seed", "integer")) is not None:
                settings["seed"] = int(seed.values[0])
            if sampler.kind == "independent":
                settings["type"] = "independent"
            else:
                settings["type"] = "sobol"
                self.notes.append(
                    f"{sampler.location}: sampler '{shown(sampler.kind)}' imported as spectrace's Owen-scrambled Sobol"
                )
        data["sampler"] = {**settings, "spp": spp}

    def integrator(self, data: dict) -> None:
        integrator = self.scene.integrator
        depth = PBRT_DEFAULT_MAXDEPTH
        if integrator is not None:
            depth = self.integer(integrator, "maxdepth", depth, low=0)
            kind = shown(integrator.kind)
            if integrator.kind in _SAME_IMAGE_INTEGRATORS:
                self.notes.append(f"{integrator.location}: integrator '{kind}' imported as path tracing (same image)")
            elif integrator.kind not in ("volpath", "path", "simplepath", "simplevolpath"):
                self.warn(integrator.location, f"integrator '{kind}' renders another quantity; path tracing imported")
        # pbrt's maxdepth counts bounces (0: emitters only), spectrace's max_depth path segments (1: emitters only).
        data["integrator"] = {"type": "path", "max_depth": depth + 1}

    # -------------------------------------------------- textures and materials

    def texture_reference(self, entity: Entity, name: str) -> dict | None:
        """A `"texture name" "tex"` parameter as {"texture": key} (spectrum textures), or None."""
        parameter = entity.find(name, "texture")
        if parameter is None:
            return None
        key = ("spectrum", str(parameter.values[0]))
        if key not in self.scene.textures:
            if ("float", key[1]) in self.scene.textures:
                self.warn(
                    parameter.location,
                    f'"{parameter.label()}": a float texture where spectrace takes a spectrum; not imported',
                )
                return None
            raise error(
                parameter.location, f"\"{parameter.label()}\" names '{shown(key[1])}', which no Texture defined"
            )
        if key not in self._texture_of:
            texture = self.scene.textures[key].entity
            table = self.texture_table(texture)
            if "texture" not in table:
                return table
            self._texture_of[key] = _name(texture.name, self.textures)
            self.textures[self._texture_of[key]] = {"type": table.pop("texture"), **table}
        return {"texture": self._texture_of[key]}

    def texture_table(self, texture: Entity) -> dict:
        self.read.add(id(texture))
        kind = texture.kind
        if kind == "scale":
            return self.scaled_texture(texture)
        if kind == "constant":
            return self.spectrum(texture, "value", "albedo") or {"value": 1.0}
        if kind not in TEXTURES:
            raise error(texture.location, f"texture '{shown(kind)}': spectrace imports {', '.join(TEXTURES)}")
        mapping = self.string(texture, "mapping", "uv")
        if mapping != "uv":
            raise error(texture.location, f"{texture.label()}: mapping '{shown(str(mapping))}' (spectrace takes uv)")
        us, vs = self.one(texture, "uscale", 1.0), self.one(texture, "vscale", 1.0)
        ud, vd = self.one(texture, "udelta", 0.0), self.one(texture, "vdelta", 0.0)
        if kind == "checkerboard":
            if self.integer(texture, "dimension", 2) != 2:
                raise error(texture.location, f"{texture.label()}: a 3D checkerboard (spectrace's is 2D)")
            sides = []
            for side, default in (("tex1", 1.0), ("tex2", 0.0)):
                value = self.spectrum(texture, side, "albedo") or self.texture_reference(texture, side)
                sides.append(value or {"value": default})
            # spectrace's texture v is 1 - the file's v (mesh files store v up): s = us u + ud, t = vs v + vd.
            return {
                "texture": "checkerboard",
                "color0": sides[0],
                "color1": sides[1],
                "uv_scale": [us, -vs],
                "uv_offset": [ud, vs + vd],
            }
        path = self.file_path(texture, "filename")
        if path is None:
            raise error(texture.location, f'{texture.label()} needs "string filename"')
        table: dict = {"texture": "bitmap", "file": self.relative(path)}
        encoding = self.string(texture, "encoding")
        if encoding == "linear":
            table["raw"] = True
        elif encoding not in (None, "sRGB"):
            self.warn(texture.location, f"encoding '{shown(encoding)}' not imported (read as sRGB)")
        filter_name = self.string(texture, "filter", "bilinear")
        table["filter"] = {
            "point": "nearest",
            "bilinear": "bilinear",
            "trilinear": "trilinear",
            "ewa": "trilinear",
        }.get(filter_name or "", "bilinear")
        wrap = self.string(texture, "wrap", "repeat")
        if wrap not in ("repeat", "clamp"):
            self.warn(texture.location, f"wrap '{shown(wrap or '')}' imported as clamp")
            wrap = "clamp"
        table["wrap"] = wrap
        if self.one(texture, "scale", 1.0) != 1.0 or self.boolean(texture, "invert", False):
            self.warn(texture.location, '"scale" and "invert" of an image texture not imported')
        # pbrt looks images up at (s, 1 - t), t = vs v + vd; spectrace at (u', v') = uv_scale (u, 1 - v) + uv_offset.
        table |= {"uv_scale": [us, vs], "uv_offset": [ud, 1.0 - vs - vd]}
        return table

    def scaled_texture(self, texture: Entity) -> dict:
        """pbrt's `scale` texture: `tex` times a number. A scaled spectrum stays a spectrum; a scaled image becomes a
        linear OpenEXR copy of it, multiplied, beside the TOML (pbrt scales the uplifted spectrum, spectrace uplifts
        the scaled colour: the same colour under D65, docs/pbrt.md)."""
        value_type = next(t.value_type for t in self.scene.textures.values() if t.entity is texture)
        factor = self.one(texture, "scale", 1.0)
        if (factor_texture := texture.find("scale", "texture")) is not None:
            # A constant float texture as the factor is its number (pbrt-v4's scenes write scales so).
            key = ("float", str(factor_texture.values[0]))
            constant = self.scene.textures.get(key)
            if constant is None or constant.entity.kind != "constant":
                raise error(
                    factor_texture.location,
                    f'{texture.label()}: a texture as "scale" other than a constant one (spectrace takes a number)',
                )
            self.read.add(id(constant.entity))
            factor = self.one(constant.entity, "value", 1.0)
        if factor < 0:
            raise error(texture.location, f"{texture.label()}: a negative scale")
        inner = self.spectrum(texture, "tex", "albedo")
        if inner is None:
            reference = texture.find("tex", "texture")
            if reference is None:
                inner = {"value": 1.0}
            else:
                key = (value_type, str(reference.values[0]))
                if key not in self.scene.textures:
                    raise error(
                        reference.location, f"\"texture tex\" names '{shown(key[1])}', which no Texture defined"
                    )
                inner = self.texture_table(self.scene.textures[key].entity)
        if inner.get("texture") == "bitmap":
            return inner | {"file": self.scaled_image(inner, factor, texture), "raw": True}
        if "texture" in inner:
            raise error(texture.location, f"{texture.label()}: spectrace scales spectra and image textures only")
        return inner | {"scale": inner.get("scale", 1.0) * factor}

    def scaled_image(self, table: dict, factor: float, texture: Entity) -> str:
        from spectrace.io.images import read_texture_image
        from spectrace.textures.bitmap import decoded

        source = (self.toml_folder / table["file"]).resolve()
        values, encoded = read_texture_image(source, str(texture.location))
        linear = decoded(values, encoded, bool(table.get("raw", False))) * factor
        if linear.shape[-1] == 1:
            linear = np.repeat(linear, 3, axis=-1)
        if linear.max(initial=0.0) > 1.0:
            self.warn(texture.location, f"{texture.label()}: texels above 1 after scaling clamped to 1 (a reflectance)")
            linear = np.minimum(linear, 1.0)
        file = _name(f"{source.stem}_x{factor:g}", {Path(n).stem for n in self.files}) + ".exr"
        self.files[file] = linear.astype(np.float32)
        return f"{self.mesh_folder}/{file}"

    def reflectance(self, entity: Entity, name: str, default: float) -> dict:
        return self.spectrum(entity, name, "albedo") or self.texture_reference(entity, name) or {"value": default}

    def roughness(self, material: Entity) -> float | dict:
        """The GGX α: a number, or for a `"texture roughness"` a one-channel texture of α per point."""
        if (texture := material.find("roughness", "texture")) is not None and not any(
            material.find(key, "texture", "float") for key in ("uroughness", "vroughness")
        ):
            return self.roughness_texture(material, texture)
        values = [self.one(material, key, -1.0) for key in ("roughness", "uroughness", "vroughness")]
        for key in ("roughness", "uroughness", "vroughness"):
            if (parameter := material.find(key, "texture")) is not None:
                self.warn(parameter.location, f'"{parameter.label()}": a roughness texture is not imported (0 used)')
        u = values[1] if values[1] >= 0 else max(values[0], 0.0)
        v = values[2] if values[2] >= 0 else max(values[0], 0.0)
        if u != v:
            self.warn(
                material.location, f"{material.label()}: anisotropic roughness ({u:g}, {v:g}) imported as their mean"
            )
        roughness = (u + v) / 2.0
        # pbrt-v4 remaps a roughness to the Trowbridge-Reitz (GGX) alpha as sqrt(roughness) unless told not to.
        alpha = math.sqrt(roughness) if self.boolean(material, "remaproughness", True) else roughness
        return min(alpha, 1.0)

    def roughness_texture(self, material: Entity, parameter) -> float | dict:
        """A float texture as the roughness: a `constant` one is its number; an `imagemap` becomes a one-channel
        float TIFF of α beside the TOML: pbrt's float lookup averages an image's channels, and its remapping
        (`remaproughness`, default true: α = √roughness) is applied to each texel, as pbrt applies it to the value
        it looks up (exact for nearest lookups; a filtered lookup differs by √ of a blend against a blend of √)."""
        from spectrace.io.images import read_texture_image
        from spectrace.textures.bitmap import decoded

        key = ("float", str(parameter.values[0]))
        if key not in self.scene.textures:
            raise error(
                parameter.location, f"\"{parameter.label()}\" names '{shown(key[1])}', which no Texture defined"
            )
        texture = self.scene.textures[key].entity
        table = self.texture_table(texture)
        remap = self.boolean(material, "remaproughness", True)
        if "texture" not in table:
            value = max(float(table.get("value", 0.0)) * float(table.get("scale", 1.0)), 0.0)
            return min(math.sqrt(value) if remap else value, 1.0)
        if table["texture"] != "bitmap":
            raise error(parameter.location, f'"{parameter.label()}": spectrace takes an imagemap or a constant here')
        source = (self.toml_folder / table["file"]).resolve()
        written = str(table["file"]).removeprefix(f"{self.mesh_folder}/")
        if written in self.files:  # a scaled image this import made (a `scale` texture): not on disk yet
            linear = np.asarray(self.files[written], np.float64)
        else:
            values, encoded = read_texture_image(source, str(texture.location))
            linear = decoded(values, encoded, bool(table.get("raw", False)))
        roughness = np.clip(linear.mean(axis=-1), 0.0, None)
        alpha = np.minimum(np.sqrt(roughness) if remap else roughness, 1.0)
        file = _name(f"{source.stem}_alpha", {Path(n).stem for n in self.files}) + ".tif"
        self.files[file] = alpha.astype(np.float32)
        return table | {"file": f"{self.mesh_folder}/{file}", "raw": True}

    def material(self, reference: Entity | str | None, location: Location) -> str | None:
        """The TOML material name for a shape's material (None for pbrt's `interface`)."""
        if reference is None:
            key: int | str = "default"
            entity = Entity("Material", "diffuse", [], location)
        elif isinstance(reference, str):
            key = reference
            if reference not in self.scene.named_materials:
                raise error(location, f"NamedMaterial '{shown(reference)}', which no MakeNamedMaterial defined")
            entity = self.scene.named_materials[reference]
        else:
            key, entity = id(reference), reference
        if key in self._material_of:
            return self._material_of[key]
        table = self.material_table(entity)
        name = None if table is None else _name(entity.name or entity.kind, self.materials)
        if name is not None and table is not None:
            self.materials[name] = table
        self._material_of[key] = name
        return name

    def material_table(self, material: Entity) -> dict | None:
        self.read.add(id(material))
        kind = material.kind
        if material.directive == "MakeNamedMaterial":
            kind = self.string(material, "type") or ""
            if not kind:
                raise error(material.location, f"named material '{shown(material.name)}' needs \"string type\"")
        if kind in _NO_EQUIVALENT:
            raise error(
                material.location,
                f"material '{kind}': {_NO_EQUIVALENT[kind]} (spectrace imports {', '.join(MATERIALS)})",
            )
        if kind not in MATERIALS:
            raise error(
                material.location, f"unknown material '{shown(kind)}' (spectrace imports {', '.join(MATERIALS)})"
            )
        for key in ("normalmap", "displacement"):
            if (parameter := material.find(key)) is not None:
                self.warn(parameter.location, f'"{parameter.label()}" not imported')
        if kind == "interface":
            return None
        if kind == "mix":
            return self.mix_table(material)
        if kind == "diffuse":
            return {"type": "diffuse", "reflectance": self.reflectance(material, "reflectance", 0.5)}
        if kind == "conductor":
            if (reflectance := material.find("reflectance")) is not None:
                raise error(
                    reflectance.location, 'a conductor given by "reflectance": spectrace\'s conductor takes eta and k'
                )
            eta_table = self.spectrum(material, "eta", "unbounded") or {"spectrum": "metals/Cu:eta"}
            k = self.spectrum(material, "k", "unbounded") or {"spectrum": "metals/Cu:k"}
            table: dict[str, object] = {"type": "conductor"}
            metals = {s.get("spectrum", "").split(":")[0] for s in (eta_table, k)}
            metal = next(iter(metals)).removeprefix("metals/") if len(metals) == 1 else ""
            if metal in SPECTRACE_METALS:
                table["metal"] = metal
            else:
                table |= {"eta": eta_table, "k": k}
            if "glass" in eta_table or "glass" in k:
                raise error(material.location, "a glass's index given as a conductor's eta or k")
            return table | self._rough(material)
        if kind == "diffusetransmission":
            return self.diffuse_transmission(material)
        eta: float | str = self.ior(material)
        if kind == "dielectric":
            return {"type": "dielectric", "ior": eta} | self._rough(material)
        if kind == "thindielectric":  # pbrt-v4's ThinDielectricBxDF: R' = R + T²R/(1 − R²), straight through
            if not isinstance(eta, (int, float)):
                raise error(material.location, "a thindielectric's eta must be a number for spectrace")
            return {"type": "thindielectric", "ior": eta}
        # coateddiffuse: pbrt-v4 simulates a dielectric coat over a Lambertian base (random walk between the
        # layers); spectrace's plastic is the same two layers in closed form (docs/pbrt.md). The walk meets the
        # base's albedo at every return to it, which is the plastic's nonlinear series, and crosses a rough coat
        # by its own microfacet transmission, which is coat_transmission "rough".
        if not isinstance(eta, (int, float)):
            eta = 1.5
            self.warn(material.location, "coateddiffuse with a spectral eta imported with 1.5")
        albedo = self.spectrum(material, "albedo", "albedo")
        if albedo is not None and albedo != {"value": 0.0}:
            self.warn(material.location, 'coateddiffuse "albedo" (an absorbing coat) not imported')
        for key in ("thickness", "g", "maxdepth", "nsamples"):
            material.find(key)
        table = {
            "type": "plastic",
            "reflectance": self.reflectance(material, "reflectance", 0.5),
            "ior": eta,
            "nonlinear": True,
        } | self._rough(material)
        if "roughness" in table:
            table["coat_transmission"] = "rough"
        return table

    def diffuse_transmission(self, material: Entity) -> dict:
        """pbrt-v4's DiffuseTransmissionMaterial: Lambertian reflection and transmission, `reflectance` and
        `transmittance` (defaults 0.25 each) both multiplied by `scale` (default 1), as spectrace's
        `diffusetransmission`."""
        factor = self.one(material, "scale", 1.0)
        table: dict = {"type": "diffusetransmission"}
        for key in ("reflectance", "transmittance"):
            value = self.reflectance(material, key, 0.25)
            if factor != 1.0:
                if "value" in value:
                    value = {"value": value["value"] * factor}
                elif "rgb" in value:
                    value = {"rgb": [c * factor for c in value["rgb"]]}
                else:
                    raise error(
                        material.location,
                        f'diffusetransmission "scale" {factor:g} on a {key} that is not a number or rgb: spectrace '
                        "scales only those",
                    )
            table[key] = value
        return table

    def mix_table(self, material: Entity) -> dict | None:
        """pbrt-v4's `mix`: at each intersection one of `materials` is chosen by a hash of the point and direction,
        the second with probability `amount` (its MixMaterial::ChooseMaterial): spectrace's `mix` material, which
        chooses the same way. Two diffuse materials with a number or image amount become instead one diffuse
        material of the blended reflectance, (1 - amount) R1 + amount R2 (spectrace's `mix` texture): the same
        average without the choice's noise. An amount of 0 or 1, or the same material twice, is that material."""
        names = material.find("materials", "string")
        if names is None or len(names.values) != 2:
            raise error(material.location, f'{material.label()} needs "string materials" naming two materials')
        tables = []
        for name in names.values:
            if str(name) not in self.scene.named_materials:
                raise error(names.location, f"mix names '{shown(str(name))}', which no MakeNamedMaterial defined")
            tables.append(self.material_table(self.scene.named_materials[str(name)]))
        amount_texture = material.find("amount", "texture")
        number = self.one(material, "amount", 0.5)
        amount: float | dict = number
        if amount_texture is not None:
            key = ("float", str(amount_texture.values[0]))
            if key not in self.scene.textures:
                raise error(
                    amount_texture.location,
                    f"\"{amount_texture.label()}\" names '{shown(key[1])}', which no Texture defined",
                )
            amount = self.texture_table(self.scene.textures[key].entity)
            if amount.get("texture") not in ("bitmap", "checkerboard"):
                raise error(amount_texture.location, "a mix's amount texture must be an imagemap or a checkerboard")
        elif number <= 0.0 or number >= 1.0:
            return tables[number >= 1.0]
        if tables[0] == tables[1]:
            return tables[0]
        if any(table is None for table in tables):
            raise error(material.location, "material 'mix' with an interface: spectrace mixes two materials")
        pair = [table for table in tables if table is not None]
        if (
            all(table["type"] == "diffuse" for table in pair)
            and (not isinstance(amount, dict) or amount.get("texture") == "bitmap")
            and not any(self._texture_kind(table["reflectance"]) in ("checkerboard", "scale", "mix") for table in pair)
        ):
            return {
                "type": "diffuse",
                "reflectance": {
                    "texture": "mix",
                    "tex1": pair[0]["reflectance"],
                    "tex2": pair[1]["reflectance"],
                    "amount": amount,
                },
            }
        materials = [self.material(str(name), names.location) for name in names.values]
        return {"type": "mix", "materials": materials, "amount": amount}

    def _texture_kind(self, value: dict) -> str | None:
        """The kind of texture a TOML value holds (a named one's from the textures table), None for a spectrum."""
        name = value.get("texture")
        return self.textures[name]["type"] if name in self.textures else name

    def _rough(self, material: Entity) -> dict:
        alpha = self.roughness(material)
        return {"roughness": alpha} if isinstance(alpha, dict) or alpha > 0 else {}

    def ior(self, material: Entity) -> float | str:
        parameter = material.find("eta", "float", "spectrum", "rgb")
        if parameter is None:
            return 1.5
        if parameter.type == "float":
            return float(parameter.values[0])
        if parameter.type == "spectrum" and isinstance(parameter.values[0], str) and parameter.values[0] in _GLASSES:
            return _GLASSES[parameter.values[0]]
        raise error(
            parameter.location,
            f'"{parameter.label()}": spectrace takes a number or a named glass ({", ".join(_GLASSES)}) as eta',
        )

    # -------------------------------------------------- shapes

    def shape_geometry(self, shape: Shape, needs_uv: bool = False) -> tuple[dict, MeshData | None]:
        """The spectrace geometry keys (type, file, transform) for a pbrt shape, and its mesh when one is written.
        The one place that decides how each pbrt shape becomes spectrace geometry (analytic shapes change it)."""
        entity = shape.entity
        matrix = self.world @ shape.world_from_object
        if (analytic := self.analytic_geometry(shape, matrix, needs_uv)) is not None:
            return analytic, None
        key = id(entity), shape.reverse_orientation, needs_uv
        if key not in self._mesh_of:
            mesh = self.mesh(shape)
            if needs_uv and mesh.uvs is None:
                mesh = with_default_uvs(mesh, entity.kind)
            if shape.reverse_orientation:
                mesh.faces = mesh.faces[:, ::-1].copy()
                mesh.normals = None if mesh.normals is None else -mesh.normals
            file = _name(f"{entity.kind}_{entity.location.line}", {Path(n).stem for n in self.meshes}) + ".ply"
            self.meshes[file] = mesh
            self._mesh_of[key] = (file, mesh)
        file, mesh = self._mesh_of[key]
        table = {"type": "mesh", "file": f"{self.mesh_folder}/{file}", "transform": [{"matrix": matrix.tolist()}]}
        return table, mesh

    def analytic_geometry(self, shape: Shape, matrix: np.ndarray, needs_uv: bool) -> dict | None:
        """The spectrace analytic sphere, disk or cylinder for a whole pbrt one (exact surface, smooth normals,
        pbrt's texture coordinates and front side), or None when it needs triangles: partial shapes (phimax < 360,
        a disk's innerradius > 0, a sphere's zmin/zmax cuts), degenerate ones, and a sphere under a map that is no
        similarity (an ellipsoid: the built-in tessellation when nothing depends on its orientation or uv)."""
        entity = shape.entity
        kind = entity.kind
        if kind not in ("sphere", "disk", "cylinder"):
            return None
        radius = self.one(entity, "radius", 1.0)
        if kind == "sphere" and not radius > 0:
            raise error(entity.location, f"a sphere's radius must be > 0, got {radius:g}")
        if not radius > 0 or self.one(entity, "phimax", 360.0) < 360.0:
            return None
        # pbrt's front: the object-space normal (outward; the disk's +z), flipped when ReverseOrientation is set
        # or the shape's own placement swaps handedness (Disk/Cylinder/Sphere InteractionFromIntersection), then
        # carried to the world by the inverse transpose, which is what spectrace's flip_normals does. The mirror
        # into spectrace's world (self.world) is not pbrt's and does not count.
        flip = shape.reverse_orientation != bool(np.linalg.det(shape.world_from_object[:3, :3]) < 0)
        if kind == "sphere":
            zmin, zmax = self.one(entity, "zmin", -radius), self.one(entity, "zmax", radius)
            if zmin > -radius or zmax < radius:
                return None
            steps: list[dict] = [{"scale": radius}, {"matrix": matrix.tolist()}]
            if similarity_problem(matrix) is not None:
                if needs_uv or flip:
                    return None
                return {"type": "sphere", "transform": steps, "tessellated": True}
        elif kind == "disk":
            if self.one(entity, "innerradius", 0.0) > 0.0:
                return None
            # Spectrace's unit disk (z = 0, facing +z) scaled to the radius and lifted to z = height.
            height = self.one(entity, "height", 0.0)
            steps = [{"scale": [radius, radius, 1.0]}, {"translate": [0.0, 0.0, height]}, {"matrix": matrix.tolist()}]
        else:
            # Spectrace's cylinder (radius 1, z from 0 to 1) stretched over [zmin, zmax]; pbrt orders them itself.
            z0, z1 = sorted((self.one(entity, "zmin", -1.0), self.one(entity, "zmax", 1.0)))
            if not z1 > z0:
                return None
            steps = [{"scale": [radius, radius, z1 - z0]}, {"translate": [0.0, 0.0, z0]}, {"matrix": matrix.tolist()}]
        table: dict = {"type": kind, "transform": steps}
        if flip:
            table["flip_normals"] = True
        if needs_uv and kind != "cylinder":  # the cylinders' (u, v) already agree
            table["uv_convention"] = "pbrt"
        return table

    def analytic_area(self, entity: Entity) -> float:
        """pbrt-v4's Area() of a whole sphere, disk or cylinder: object-space, whatever the transform scales."""
        radius = self.one(entity, "radius", 1.0)
        if entity.kind == "sphere":
            return 4.0 * math.pi * radius**2
        if entity.kind == "disk":
            return math.pi * radius**2
        return 2.0 * math.pi * radius * abs(self.one(entity, "zmax", 1.0) - self.one(entity, "zmin", -1.0))

    def mesh(self, shape: Shape) -> MeshData:
        entity = shape.entity
        kind = entity.kind
        if kind in ("trianglemesh", "bilinearmesh"):
            points = self.floats(entity, "P", None, "point3", "point")
            if points is None:
                raise error(entity.location, f'{entity.label()} needs "point3 P"')
            vertices = np.array(points).reshape(-1, 3)
            per_face = 3 if kind == "trianglemesh" else 4
            indices_parameter = entity.find("indices", "integer")
            if indices_parameter is None:
                if len(vertices) != per_face:
                    raise error(
                        entity.location,
                        f'{entity.label()} needs "integer indices" unless it has exactly {per_face} points',
                    )
                indices = np.arange(per_face, dtype=np.float64)
            else:
                indices = np.array(indices_parameter.values, dtype=np.float64)
                if len(indices) % per_face or np.any(indices != np.round(indices)):
                    raise error(
                        indices_parameter.location, f'"integer indices" must be whole numbers, {per_face} per face'
                    )
                if indices.size and (indices.min() < 0 or indices.max() >= len(vertices)):
                    raise error(indices_parameter.location, f"an index lies outside the {len(vertices)} points")
            faces = indices.astype(np.int64).reshape(-1, per_face)
            if kind == "bilinearmesh":
                # A patch (p00, p10, p01, p11) faces (p10 - p00) × (p01 - p00): split along p00-p11, same winding.
                faces = np.concatenate([faces[:, [0, 1, 3]], faces[:, [0, 3, 2]]])
            normals = self.floats(entity, "N", None, "normal3", "normal")
            uvs = self.floats(entity, "uv", None, "point2")
            mesh = MeshData(
                vertices,
                faces,
                None if normals is None else np.array(normals).reshape(-1, 3),
                None if uvs is None else np.array(uvs).reshape(-1, 2),
            )
            for name, array in (("N", mesh.normals), ("uv", mesh.uvs)):
                if array is not None and len(array) != len(vertices):
                    raise error(entity.location, f'"{name}" has {len(array)} values, "P" {len(vertices)}')
        elif kind == "plymesh":
            mesh = self.ply_mesh(entity)
        elif kind == "loopsubdiv":
            mesh = self.subdivided_mesh(entity)
        elif kind == "sphere":
            radius = self.one(entity, "radius", 1.0)
            mesh = sphere_mesh(
                radius,
                max(self.one(entity, "zmin", -radius), -radius),
                min(self.one(entity, "zmax", radius), radius),
                self.one(entity, "phimax", 360.0),
            )
        elif kind == "disk":
            mesh = disk_mesh(
                self.one(entity, "height", 0.0),
                self.one(entity, "radius", 1.0),
                self.one(entity, "innerradius", 0.0),
                self.one(entity, "phimax", 360.0),
            )
        elif kind == "cylinder":
            mesh = cylinder_mesh(
                self.one(entity, "radius", 1.0),
                self.one(entity, "zmin", -1.0),
                self.one(entity, "zmax", 1.0),
                self.one(entity, "phimax", 360.0),
            )
        else:
            raise error(entity.location, f"shape '{shown(kind)}': spectrace imports {', '.join(SHAPES)}")
        if mesh.normals is not None:
            # pbrt turns a triangle's geometric normal toward its shading normals: the normals, not the winding,
            # say which side is the front (spectrace's renderer reads it so too); the file written keeps a winding
            # that agrees, for any other reader.
            a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
            back = winding_against_normals(a, b, c, mesh.normals[mesh.faces])
            mesh.faces = np.where(back[:, None], mesh.faces[:, ::-1], mesh.faces)
        return mesh

    def subdivided_mesh(self, entity: Entity) -> MeshData:
        """pbrt's `loopsubdiv`: the control mesh refined `levels` times by Loop's scheme (trimesh's), shaded with
        vertex normals; pbrt then moves the vertices onto the limit surface, which this leaves out (a note)."""
        from trimesh.remesh import subdivide_loop

        points = self.floats(entity, "P", None, "point3", "point")
        indices = entity.find("indices", "integer")
        if points is None or indices is None:
            raise error(entity.location, 'loopsubdiv needs "point3 P" and "integer indices"')
        vertices = np.array(points).reshape(-1, 3)
        faces = np.array(indices.values, dtype=np.float64)
        if len(faces) % 3 or np.any(faces != np.round(faces)) or faces.min() < 0 or faces.max() >= len(vertices):
            raise error(indices.location, f'"integer indices" must be whole numbers below {len(vertices)}, 3 a face')
        levels = self.integer(entity, "levels", 3, low=0)
        if levels > 6:
            raise error(entity.location, f"loopsubdiv levels {levels}: spectrace refines at most 6 times")
        entity.find("scheme", "string")  # pbrt-v4 reads it and uses Loop's scheme whatever it says
        faces_int = faces.astype(np.int64).reshape(-1, 3)
        if levels:
            vertices, faces_int = subdivide_loop(vertices, faces_int, iterations=levels)
        self.notes.append(
            f"{entity.location}: loopsubdiv refined {levels} times without pbrt's last step onto the limit surface"
        )
        return MeshData(np.asarray(vertices), np.asarray(faces_int), _vertex_normals(vertices, faces_int), None)

    def ply_mesh(self, entity: Entity) -> MeshData:
        from spectrace.geometry.mesh import load_mesh

        path = self.file_path(entity, "filename")
        if path is None:
            raise error(entity.location, 'plymesh needs "string filename"')
        # A .ply.gz is inflated within the size its header declares (spectrace.io.compressed).
        loaded = load_mesh(path, str(entity.location))
        entity.find("edgelength")  # a displacement's dicing rate: nothing to do without the displacement
        if (displacement := entity.find("displacement")) is not None:
            self.warn(displacement.location, "plymesh displacement not imported")
        uvs = None if loaded.uvs is None else np.column_stack([loaded.uvs[:, 0], 1.0 - loaded.uvs[:, 1]])
        return MeshData(np.asarray(loaded.vertices), np.asarray(loaded.faces), loaded.normals, uvs)

    def shape(self, shape: Shape, index: int) -> dict | None:
        entity = shape.entity
        self.read.add(id(entity))
        if entity.kind not in SHAPES:
            raise error(entity.location, f"shape '{shown(entity.kind)}': spectrace imports {', '.join(SHAPES)}")
        material = self.material(shape.material, entity.location)
        interior = self.interior(shape)
        if material is None and shape.area_light is None and interior is None:
            self.notes.append(f"{entity.location}: a shape with the interface material (no surface) left out")
            return None
        if material is None and shape.area_light is not None:
            material = self.material(None, entity.location)
        geometry, mesh = self.shape_geometry(shape, needs_uv=self.reads_uv(material))
        table: dict = {"name": f"{entity.kind}{index}", **geometry}
        if material is not None:  # an interface around a medium: an index-matched boundary in spectrace
            table["material"] = material
        if interior is not None:
            table["interior"] = interior
        alpha = entity.find("alpha", "float")
        if alpha is not None and float(alpha.values[0]) < 1.0 and shape.area_light is not None:
            self.warn(alpha.location, '"alpha" on an area light not imported (spectrace\'s emitters are opaque)')
        elif material is not None and alpha is not None and float(alpha.values[0]) < 1.0:
            table["material"] = self._with_opacity(material, float(alpha.values[0]))
        if shape.area_light is not None:
            table["emitter"] = self.area_light(shape.area_light, mesh, self.world @ shape.world_from_object, entity)
        return table

    def instanced_object(self, name: str, objects: dict[str, dict]) -> str:
        """The spectrace object (its name in `objects`, added there) for pbrt object `name`, its shapes in the
        object's own space and stored once however often it is placed. As in pbrt-v4, whose instances carry no area
        lights, an area light on an object's shape is left out, with pbrt's warning."""
        shapes = self.scene.objects[name]
        for shape in shapes:
            if shape.area_light is not None:
                self.warn(
                    shape.entity.location,
                    f"area light on a shape of object '{shown(name)}' not imported (pbrt-v4: \"Area lights not "
                    'supported with object instancing"; its instances do not emit)',
                )
        shapes = [replace(shape, area_light=None) for shape in shapes]
        object_name = _name(name, objects)
        tables: list[dict] = []
        world, self.world = self.world, np.eye(4)  # the object's own space; each instance carries the mirror
        try:
            for index, shape in enumerate(shapes):
                if (table := self.shape(shape, index)) is not None:
                    self.origins[f"objects.{object_name}.shapes[{len(tables)}]"] = shape.entity.location
                    tables.append(table)
        finally:
            self.world = world
        objects[object_name] = {"shapes": tables}
        return object_name

    def interior(self, shape: Shape) -> dict | None:
        """The spectrace `interior` for the named medium inside a shape (MediumInterface's first name)."""
        if shape.outside_medium:
            self.warn(
                shape.entity.location,
                f"outside medium '{shown(shape.outside_medium)}' not imported (spectrace's media fill closed shapes)",
            )
        name = shape.inside_medium
        if not name:
            return None
        if name not in self.scene.media:
            raise error(
                shape.entity.location, f"MediumInterface names '{shown(name)}', which no MakeNamedMedium defined"
            )
        if name not in self._interior_of:
            self._interior_of[name] = self.medium_table(self.scene.media[name])
        return self._interior_of[name]

    def medium_table(self, medium: Entity) -> dict:
        from spectrace.spectral.media_presets import medium_presets

        self.read.add(id(medium))
        kind = self.string(medium, "type", "")
        if kind != "homogeneous":
            raise error(medium.location, f"medium '{shown(kind or '')}': spectrace imports homogeneous media")
        table: dict = {}
        if (preset := self.string(medium, "preset")) is not None:
            # pbrt's Jensen et al. presets are the same measurements as spectrace's, in 1/mm (pbrt: per scene unit
            # times scale; spectrace: per mm times scale, its millimetres per scene unit: the same numbers).
            if preset.lower() not in medium_presets():
                raise error(
                    medium.location, f"medium preset '{shown(preset)}' (spectrace has {', '.join(medium_presets())})"
                )
            table["preset"] = preset.lower()
        else:
            # pbrt's coefficients default to 1 per scene unit, spectrace's to 0.
            table["sigma_a"] = self.spectrum(medium, "sigma_a", "medium") or {"value": 1.0}
            table["sigma_s"] = self.spectrum(medium, "sigma_s", "medium") or {"value": 1.0}
        scale = self.one(medium, "scale", 1.0)
        if not scale > 0:
            raise error(medium.location, f"a medium's scale must be > 0, got {scale:g}")
        if scale != 1.0:
            table["scale"] = scale
        if (g := self.one(medium, "g", 0.0)) != 0.0:
            table["g"] = g
        emission = self.spectrum(medium, "Le", "medium")
        medium.find("Lescale")
        if emission is not None and emission not in ({"value": 0.0}, {"rgb": [0.0, 0.0, 0.0]}):
            self.warn(medium.location, "a medium's emission (Le) not imported")
        return table

    def reads_uv(self, material: str | None) -> bool:
        """Whether rendering the TOML material `material` reads texture coordinates: a parameter of it holds a
        texture, or one of a mix's materials reads them, at any depth (as the scene loader decides, through
        spectrace.materials.material_textures). A mesh without uv then gets pbrt's default ones."""
        table = self.materials.get(material or "", {})
        if any(isinstance(value, dict) and "texture" in value for value in table.values()):
            return True
        return table.get("type") == "mix" and any(self.reads_uv(part) for part in table.get("materials", []))

    def _with_opacity(self, material: str, opacity: float) -> str:
        name = _name(f"{material}_alpha", self.materials)
        self.materials[name] = self.materials[material] | {"opacity": max(opacity, 0.0)}
        return name

    # -------------------------------------------------- lights

    def area_light(self, light: Entity, mesh: MeshData | None, matrix: np.ndarray, shape: Entity) -> dict:
        self.read.add(id(light))
        if light.kind not in AREA_LIGHTS:
            raise error(light.location, f"area light '{shown(light.kind)}' (pbrt-v4's only one is diffuse)")
        if light.find("filename") is not None:
            raise error(light.location, "an area light showing an image file is not imported")
        two_sided = self.boolean(light, "twosided", False)
        scale = self.one(light, "scale", 1.0)
        power = self.one(light, "power", -1.0)
        if power > 0:
            if mesh is not None:
                area = mesh.world_area(matrix)
            else:  # an analytic shape: pbrt's Shape::Area(), in the shape's object space (unscaled)
                area = self.analytic_area(shape)
            # Radiance = power / (sides · area · π): a shape without area would need infinite radiance.
            if not (area > 0.0 and math.isfinite(area)):
                raise error(light.location, f'"power" needs a shape with a positive finite area, got area {area:g}')
            scale *= power / ((2.0 if two_sided else 1.0) * area * math.pi)
        table: dict[str, object] = {"radiance": self.emission(light, "L", scale)}
        if two_sided:
            table["two_sided"] = True
        return table

    def light(self, light) -> dict:
        entity, matrix = light.entity, light.world_from_light
        self.read.add(id(entity))
        kind = entity.kind
        # Every light but a point takes a direction through its transform: a singular one maps it to zero (or NaN).
        if kind != "point" and (problem := linear_map_problem(matrix[:3, :3])):
            raise error(entity.location, f"the light's transform {problem}")
        scale = self.one(entity, "scale", 1.0)
        if kind == "point":
            power = self.one(entity, "power", -1.0)
            if power > 0:
                scale *= power / (4.0 * math.pi)
            return {
                "type": "point",
                "position": self.point(matrix, self.vector(entity, "from", [0.0, 0.0, 0.0])),
                "intensity": self.emission(entity, "I", scale),
            }
        if kind == "spot":
            start = self.vector(entity, "from", [0.0, 0.0, 0.0])
            end = self.vector(entity, "to", [0.0, 0.0, 1.0])
            cone = self.one(entity, "coneangle", 30.0)
            delta = self.one(entity, "conedeltaangle", 5.0)
            power = self.one(entity, "power", -1.0)
            if power > 0:
                cos_end, cos_start = math.cos(math.radians(cone)), math.cos(math.radians(cone - delta))
                solid_angle = 2.0 * math.pi * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0)
                if not solid_angle > 0.0:  # intensity = power / solid angle: a closed cone would need infinite
                    raise error(entity.location, f'"power" needs a cone of positive solid angle (coneangle {cone:g})')
                scale *= power / solid_angle
            return {
                "type": "spot",
                "position": self.point(matrix, start),
                "target": self.point(matrix, end),
                "cutoff_angle": cone,
                "falloff_start": max(cone - delta, 0.0),
                "intensity": self.emission(entity, "I", scale),
            }
        if kind == "distant":
            start = self.vector(entity, "from", [0.0, 0.0, 0.0])
            end = self.vector(entity, "to", [0.0, 0.0, 1.0])
            illuminance = self.one(entity, "illuminance", -1.0)
            if illuminance > 0:
                scale *= illuminance
            return {
                "type": "distant",
                "direction": self.direction(matrix, np.subtract(end, start)),
                "irradiance": self.emission(entity, "L", scale),
            }
        if kind == "infinite":
            if entity.find("filename", "string") is not None:
                return self.environment_map(entity, matrix, scale)
            if entity.find("portal") is not None:
                self.warn(entity.location, '"portal" not imported')
            illuminance = self.one(entity, "illuminance", -1.0)
            if illuminance > 0:
                scale *= illuminance / math.pi
            return {"type": "constant", "radiance": self.emission(entity, "L", scale)}
        raise error(
            entity.location, f"light '{shown(kind)}': spectrace imports {', '.join(LIGHTS)} and diffuse area lights"
        )

    def environment_map(self, entity: Entity, matrix: np.ndarray, scale: float) -> dict:
        """An image infinite light: its equal-area square resampled to a latitude-longitude EXR (pbrt_envmap)."""
        from spectrace.interop.pbrt_envmap import to_latitude_longitude, upper_illuminance
        from spectrace.io.images import read_environment_map

        path = self.file_path(entity, "filename")
        assert path is not None
        if path.suffix.lower() not in (".exr", ".hdr", ".rgbe"):
            raise error(
                entity.location,
                f"infinite light image '{shown(path.name)}': spectrace reads OpenEXR and Radiance HDR maps",
            )
        square = read_environment_map(path, str(entity.location))
        height, width = square.shape[:2]
        if height != width:
            raise error(entity.location, f"'{shown(path.name)}' is {width} x {height}: pbrt-v4's maps are square")
        if entity.find("L") is not None:
            raise error(entity.location, 'both "L" and "filename" given (pbrt-v4 refuses them too)')
        if entity.find("portal") is not None:
            self.warn(entity.location, '"portal" not imported')
        illuminance = self.one(entity, "illuminance", -1.0)
        if illuminance > 0:
            reference = upper_illuminance(square)
            if not (reference > 0.0 and math.isfinite(reference)):
                raise error(
                    entity.location,
                    f'"illuminance" rescales the map\'s upper hemisphere, whose illuminance is {reference:g}',
                )
            scale *= illuminance / reference
        # RGB texels are illuminants of the colour space's D65, normalised as an RGB light's L: spectrace's envmap
        # texels are D65-based with RGB (1, 1, 1) at Y = 1, so pbrt's scale carries over.
        linear = (self.world @ matrix)[:3, :3]
        image = to_latitude_longitude(square, linear / np.cbrt(abs(np.linalg.det(linear))), min(height, 2048))
        file = _name(path.stem, {Path(n).stem for n in self.files}) + ".exr"
        self.files[file] = image
        return {"type": "envmap", "file": f"{self.mesh_folder}/{file}", "scale": scale}

    # -------------------------------------------------- the scene

    def run(self) -> dict:
        if not self.scene.has_world:
            raise SpectraceError("the file has no WorldBegin: is it a pbrt-v4 scene?", where=str(self.source))
        data: dict = {}
        self.camera(data)
        self.integrator(data)
        self.sampler(data)
        shapes: list[dict] = []
        lights: list[dict] = []
        for index, shape in enumerate(self.scene.shapes):
            if (table := self.shape(shape, index)) is not None:
                self.origins[f"shapes[{len(shapes)}]"] = shape.entity.location
                shapes.append(table)
        objects: dict[str, dict] = {}
        instances: list[dict] = []
        placed: dict[str, str] = {}  # pbrt object -> its spectrace object
        for use in self.scene.object_uses:
            if use.name not in placed:
                placed[use.name] = self.instanced_object(use.name, objects)
            if objects[placed[use.name]]["shapes"]:
                self.origins[f"instances[{len(instances)}]"] = use.location
                transform = [{"matrix": (self.world @ use.world_from_instance).tolist()}]
                instances.append({"object": placed[use.name], "transform": transform})
        objects = {name: table for name, table in objects.items() if table["shapes"]}
        for light in self.scene.lights:
            self.origins[f"lights[{len(lights)}]"] = light.entity.location
            lights.append(self.light(light))
        if sum(light["type"] in ("constant", "envmap") for light in lights) > 1:
            extra = [light.entity for light in self.scene.lights if light.entity.kind == "infinite"][1]
            raise error(extra.location, "a second infinite light; spectrace takes one environment light")
        if not shapes and not lights and not instances:
            raise SpectraceError("the scene has no shapes or lights spectrace imports", where=str(self.source))
        for entity in (
            self.scene.camera,
            self.scene.film,
            self.scene.pixel_filter,
            self.scene.sampler,
            self.scene.integrator,
        ):
            if entity is not None:
                self.read.add(id(entity))
        for entity in self.scene.entities:
            if id(entity) in self.read:
                for parameter in entity.parameters:
                    if not parameter.used:
                        self.warn(parameter.location, f'{entity.label()}: parameter "{parameter.label()}" not imported')
        self.warnings, self.notes = _grouped(self.warnings), _grouped(self.notes)
        if self.textures:
            data["textures"] = self.textures
        data["materials"] = self.materials
        data["shapes"] = shapes
        data["lights"] = lights
        data["objects"] = objects
        data["instances"] = instances
        order = (
            "camera",
            "film",
            "integrator",
            "sampler",
            "textures",
            "materials",
            "shapes",
            "lights",
            "objects",
            "instances",
        )
        # materials stays even when empty: the scene format asks for the table.
        return {key: data[key] for key in order if key in data and (key == "materials" or data[key] not in ([], {}))}

    def imported_error(self, failure: SpectraceError, toml_path: Path) -> SpectraceError:
        """The loader's complaint about the written TOML, told at the pbrt line the value came from."""
        where = failure.where or ""
        key = where.split(": ", 1)[1] if where.startswith(f"{toml_path}: ") else ""
        matches = [p for p in self.origins if key == p or key.startswith((p + ".", p + "["))]
        detail = f" (imported as {key})" if key else ""
        if not matches:
            return SpectraceError(
                f"the imported scene does not load: {failure.message}{detail}", where=str(self.source)
            )
        return error(self.origins[max(matches, key=len)], f"{failure.message}{detail}")


# ---------------------------------------------------------------- tessellation (until spectrace has analytic shapes)


def disk_mesh(height: float, radius: float, inner: float, phimax_degrees: float) -> MeshData:
    """pbrt's disk (the z = height plane, facing +z) as a ring of triangles, uv = (φ/φmax, (r - ri)/(r_max... ))."""
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * min(phimax_degrees, 360.0) / 360.0)))
    phi = np.linspace(0.0, math.radians(min(phimax_degrees, 360.0)), segments + 1)
    rings = np.array([radius, inner])
    xy = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    vertices = np.concatenate([np.column_stack([r * xy, np.full(len(phi), height)]) for r in rings])
    n = len(phi)
    i = np.arange(segments)
    outer, inner_ring = i, i + n
    # pbrt's v runs from the outer edge (0) to the inner one (1).
    faces = np.concatenate(
        [np.stack([outer, outer + 1, inner_ring + 1], 1), np.stack([outer, inner_ring + 1, inner_ring], 1)]
    )
    uvs = np.column_stack([np.tile(phi / phi[-1], 2), np.repeat([0.0, 1.0], n)])
    if inner <= 0.0:  # the inner ring collapses to the centre: keep its fan, drop the degenerate triangles
        faces = faces[:segments]
    normals = np.tile([0.0, 0.0, 1.0], (len(vertices), 1))
    return MeshData(vertices, faces, normals, uvs)


def sphere_mesh(radius: float, zmin: float, zmax: float, phimax_degrees: float) -> MeshData:
    """pbrt's (partial) sphere about z as a grid of triangles facing outward, with radial normals and pbrt's uv:
    u = φ/φmax, v = (θ − θ(zmin)) / (θ(zmax) − θ(zmin)), θ = acos(z/r)."""
    phimax = math.radians(min(max(phimax_degrees, 0.0), 360.0))
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * phimax / (2 * math.pi))))
    theta_start, theta_end = (
        math.acos(max(-1.0, min(1.0, zmin / radius))),
        math.acos(max(-1.0, min(1.0, zmax / radius))),
    )
    rings = max(2, int(math.ceil(TESSELLATION_SEGMENTS / 2 * abs(theta_start - theta_end) / math.pi)))
    u = np.linspace(0.0, 1.0, segments + 1)
    v = np.linspace(0.0, 1.0, rings + 1)
    uu, vv = np.meshgrid(u, v)  # rows: v, from zmin up to zmax
    phi, theta = uu * phimax, theta_start + vv * (theta_end - theta_start)
    normals = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1).reshape(-1, 3)
    columns = segments + 1
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = (i * columns + j).ravel()
    b, c, d = a + 1, a + columns + 1, a + columns
    # (a, b, c) winds with dp/dφ × dp/dz, outward, as pbrt's sphere faces.
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    vertices = radius * normals
    area = 0.5 * np.linalg.norm(
        np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]), axis=1
    )
    faces = faces[area > 1e-12 * radius * radius]  # the poles' degenerate triangles
    return MeshData(vertices, faces, normals, np.stack([uu.ravel(), vv.ravel()], 1))


def cylinder_mesh(radius: float, zmin: float, zmax: float, phimax_degrees: float) -> MeshData:
    """pbrt's cylinder (about z, open, facing outward) as a band of triangles with radial normals."""
    zmin, zmax = min(zmin, zmax), max(zmin, zmax)
    segments = max(3, int(math.ceil(TESSELLATION_SEGMENTS * min(phimax_degrees, 360.0) / 360.0)))
    phi = np.linspace(0.0, math.radians(min(phimax_degrees, 360.0)), segments + 1)
    xy = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    n = len(phi)
    vertices = np.concatenate([np.column_stack([radius * xy, np.full(n, z)]) for z in (zmin, zmax)])
    i = np.arange(segments)
    bottom, top = i, i + n
    faces = np.concatenate([np.stack([bottom, bottom + 1, top + 1], 1), np.stack([bottom, top + 1, top], 1)])
    normals = np.concatenate([np.column_stack([xy, np.zeros(n)])] * 2)
    uvs = np.column_stack([np.tile(phi / phi[-1], 2), np.repeat([0.0, 1.0], n)])
    return MeshData(vertices, faces, normals, uvs)


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals: the sum of the area-weighted normals of the faces around each vertex."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    face_normals = np.cross(b - a, c - a)
    normals = np.zeros_like(vertices, dtype=np.float64)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_normals)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)


def with_default_uvs(mesh: MeshData, kind: str) -> MeshData:
    """The mesh with pbrt's texture coordinates for meshes without any: (0, 0), (1, 0), (1, 1) at each triangle's
    corners; a bilinear patch's (0, 0)..(1, 1) at its corners (its second triangle p00, p11, p01). Each corner gets a
    vertex of its own."""
    count = len(mesh.faces)
    corners = np.tile([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], (count, 1, 1))
    if kind == "bilinearmesh":  # faces: the patches' first triangles, then their second ones
        corners[count // 2 :] = [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    return MeshData(
        mesh.vertices[mesh.faces.ravel()],
        np.arange(3 * count).reshape(count, 3),
        None if mesh.normals is None else mesh.normals[mesh.faces.ravel()],
        corners.reshape(-1, 2),
    )


def write_ply(path: Path, mesh: MeshData) -> None:
    """A binary PLY spectrace's mesh reader takes: positions, optional normals and texture coordinates (v as pbrt
    stores it, up the image; the reader turns it into spectrace's)."""
    columns = [mesh.vertices]
    names = ["x", "y", "z"]
    if mesh.normals is not None:
        columns.append(mesh.normals)
        names += ["nx", "ny", "nz"]
    if mesh.uvs is not None:
        columns.append(mesh.uvs)
        names += ["u", "v"]
    vertex_data = np.ascontiguousarray(np.column_stack(columns), dtype="<f4")
    face_data = np.zeros(len(mesh.faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face_data["n"] = 3
    face_data["i"] = mesh.faces
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment written by spectrace import-pbrt",
        f"element vertex {len(mesh.vertices)}",
        *(f"property float {name}" for name in names),
        f"element face {len(mesh.faces)}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    with open(path, "wb") as handle:
        handle.write(("\n".join(header) + "\n").encode("ascii"))
        handle.write(vertex_data.tobytes())
        handle.write(face_data.tobytes())


# ---------------------------------------------------------------- public API


def mesh_folder_name(toml_path: Path) -> str:
    """The folder beside the TOML that holds the meshes and environment maps an import writes."""
    return f"{toml_path.stem}_assets"


def pbrt_scene_data(pbrt_path: str | Path, toml_path: str | Path | None = None) -> tuple[dict, PbrtImporter]:
    """(scene data in the TOML format's structure, the importer with its warnings, notes and meshes to write)."""
    pbrt_path = Path(pbrt_path)
    toml_path = Path(toml_path) if toml_path is not None else pbrt_path.with_suffix(".toml")
    importer = PbrtImporter(read_scene(pbrt_path), pbrt_path, toml_path.parent, mesh_folder_name(toml_path))
    return importer.run(), importer


def _write_image_file(path: Path, image: np.ndarray) -> None:
    """An image the import made: a one-channel float TIFF for a `.tif` (a roughness: one number per texel), else
    an OpenEXR."""
    if path.suffix == ".tif":
        from PIL import Image

        Image.fromarray(image, mode="F").save(path)
    else:
        from spectrace.io.exr import write_exr

        write_exr(path, image, None, {})


def import_pbrt(
    pbrt_path: str | Path, toml_path: str | Path, strict: bool = False, option: str = "the TOML file"
) -> tuple[list[str], list[str]]:
    """Write the spectrace TOML scene (and its folder of meshes) for a pbrt-v4 scene and check that it loads;
    returns (warnings, notes). strict: every warning (something in the file not imported) is an error instead.
    option: what errors about the output call it (the command line's --output).

    The output is checked and locked first (spectrace.io.output_lock: a second import writing it is refused); the
    TOML and its folder of meshes are replaced together, and only by a complete import whose TOML loads: a failed
    import leaves an earlier one, TOML and folder, as it was."""
    from spectrace.interop.toml_writer import lock_import

    pbrt_path, toml_path = Path(pbrt_path), Path(toml_path)
    check_output_file(toml_path, option, create_folders=True)
    if toml_path.exists() and pbrt_path.exists() and toml_path.samefile(pbrt_path):
        raise SpectraceError(
            "is the pbrt scene being imported; writing it would destroy the input", where=str(toml_path)
        )
    with lock_import(toml_path, option, "spectrace import-pbrt"):
        return _import_pbrt(pbrt_path, toml_path, strict, option)


def _import_pbrt(pbrt_path: Path, toml_path: Path, strict: bool, option: str) -> tuple[list[str], list[str]]:
    from spectrace.interop.toml_writer import non_finite_key, write_scene
    from spectrace.scene import load_scene

    data, importer = pbrt_scene_data(pbrt_path, toml_path)
    if strict and importer.warnings:
        raise SpectraceError(
            f"{len(importer.warnings)} things not imported (--strict): " + "; ".join(importer.warnings),
            where=str(pbrt_path),
        )
    header = "\n".join(
        [
            f"Imported from the pbrt-v4 scene {shown(pbrt_path.name, 200)} by `spectrace import-pbrt`.",
            *(f"warning: {text}" for text in importer.warnings),
            *(f"note: {text}" for text in importer.notes),
        ]
    )
    if (key := non_finite_key(data)) is not None:
        failure = SpectraceError(
            "is NaN or infinite: a number of the file overflows or divides by zero", f"{toml_path}: {key}"
        )
        raise importer.imported_error(failure, toml_path)
    files: dict[str, Callable[[Path], object]] = {}
    for name, mesh in importer.meshes.items():
        files[f"{importer.mesh_folder}/{name}"] = partial(write_ply, mesh=mesh)
    for name, image in importer.files.items():
        files[f"{importer.mesh_folder}/{name}"] = partial(_write_image_file, image=image)

    def check(temp: Path) -> None:
        try:
            load_scene(temp)
        except SpectraceError as failure:
            raise importer.imported_error(failure, temp) from None

    try:
        write_scene(toml_path, data, header, files, check, option, "spectrace import-pbrt")
    except OSError as failure:
        raise SpectraceError(
            f"cannot write the TOML or its files ({failure.strerror or failure})", where=str(toml_path)
        ) from None
    return importer.warnings, importer.notes


def load_pbrt_scene(pbrt_path: str | Path, strict: bool = False):
    """A `Scene` from a pbrt-v4 file (through a temporary TOML file and mesh folder)."""
    from spectrace.scene import load_scene

    with tempfile.TemporaryDirectory(prefix="spectrace-pbrt-") as folder:
        toml_path = Path(folder) / (Path(pbrt_path).stem + ".toml")
        import_pbrt(pbrt_path, toml_path, strict=strict)
        return load_scene(toml_path).with_overrides(source=Path(pbrt_path))
