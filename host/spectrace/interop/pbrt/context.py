"""What every pbrt mapping reads through: the parsed scene, where the TOML goes, what was written and what was
not imported (`Context`), and the readers of pbrt's parameters and spectra.

pbrt-v4 divides every light's spectrum by its photometric integral ∫ȳ(λ)s(λ)dλ (an RGB illuminant by that of the
colour space's D65) and its film sums ∫x̄L, ∫ȳL, ∫z̄L without spectrace's 1/∫ȳ: a light of `scale` k shows as
luminance factor Y = k in both once spectrace's spectrum is s scaled to Y = k (`Context.emission`). RGB stays RGB
(both uplift with Jakob & Hanika's sigmoid), `blackbody` is Planck's law, named spectra map to spectrace's data:
metal-{Ag,Al,Au,Cu}-{eta,k} to spectra/metals, glass-BK7 to N-BK7 and glass-F11 to N-SF11 (SCHOTT Sellmeier),
stdillum-* to the CIE illuminants. Wavelength/value lists are zero outside their range, as in pbrt.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.interop.pbrt.graphics_state import Entity, PbrtScene
from spectrace.interop.pbrt.meshes import MeshData
from spectrace.interop.pbrt.parser import Location, error, shown

_METALS = ("Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2")  # pbrt's metal-X-eta / metal-X-k: spectra/metals/X.csv
# pbrt-v4's named glasses (an index of refraction by name, materials.ior); spectra/glasses/sellmeier.csv notes how
# close each of pbrt's tables is to the formula.
GLASSES = {
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


def unique_name(base: str, taken) -> str:
    """`base` made a TOML key (letters, digits, _ and -), numbered past the names `taken`."""
    name = re.sub(r"[^A-Za-z0-9_-]", "_", base) or "item"
    candidate, number = name, 2
    while candidate in taken:
        candidate, number = f"{name}_{number}", number + 1
    return candidate


def grouped(warnings: list[str]) -> list[str]:
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


class Context:
    """One import: the parsed scene, where the TOML goes, what it holds so far and what was not imported. Every
    mapping (the modules of spectrace.interop.pbrt, and through `Import` each plugin's `from_pbrt`) reads pbrt's
    parameters through it, so that what none read is reported."""

    def __init__(
        self, scene: PbrtScene, source: Path, toml_folder: Path, mesh_folder: str, missing_assets: str = "refuse"
    ):
        self.scene = scene
        self.missing_assets = missing_assets  # "placeholder": missing asset files stood in for (placeholders.py)
        self.placeholders: list[str] = list(scene.skipped)
        self.source = source
        self.toml_folder = toml_folder
        self.mesh_folder = mesh_folder
        self.warnings: list[str] = [*scene.unsupported, *(f"placeholder: {text}" for text in scene.skipped)]
        self.notes: list[str] = []
        self.meshes: dict[str, MeshData] = {}  # file name in mesh_folder -> data
        self.files: dict[str, np.ndarray] = {}  # environment maps (EXR) to write beside the meshes
        # file in `files` -> the equal-area square it was resampled from, spectrace-from-light, the image's path
        self.environment_sources: dict[str, tuple[np.ndarray, np.ndarray, str]] = {}
        self.mesh_of: dict[tuple[int, bool, bool], tuple[str, MeshData]] = {}
        self.materials: dict[str, dict] = {}
        self.material_of: dict[int | str, str | None] = {}
        self.textures: dict[str, dict] = {}
        self.texture_of: dict[tuple[str, str], str] = {}
        self.interior_of: dict[str, dict] = {}
        self.material_interiors: dict[int, dict] = {}  # id of a subsurface material -> its medium (subsurface.py)
        self.world = np.eye(4)  # spectrace world from pbrt world: the handedness mirror, or not
        self.origins: dict[str, Location] = {}  # TOML key path -> where in the pbrt files it came from
        self.read: set[int] = set()  # the entities mapped (their unread parameters are reported)

    @staticmethod
    def error(location: Location, message: str) -> SpectraceError:
        """The one-line error for a problem at file:line (what a mapping raises)."""
        return error(location, message)

    @staticmethod
    def shown(text: str, limit: int = 60) -> str:
        """A name from the file as a message shows it: one line, at most `limit` characters."""
        return shown(text, limit)

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

    def absent(self, entity: Entity, name: str, stand_in: str) -> bool:
        """Whether the file parameter `name` names is missing and stood in for (`missing_assets="placeholder"`,
        reported as a warning); False where it is there, or missing without placeholders (file_path refuses it)."""
        from spectrace.interop.pbrt.placeholders import is_missing

        value = self.string(entity, name)
        if self.missing_assets != "placeholder" or value is None:
            return False
        if not is_missing(value, entity.location.file.parent):
            return False
        parameter = entity.find(name)
        text = f"{parameter.location if parameter else entity.location}: '{shown(value, 200)}' is missing: {stand_in}"
        self.placeholders.append(text)
        self.warnings.append(f"placeholder: {text}")
        return True

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

    def spectrum(self, entity: Entity, name: str, role: str) -> dict | None:
        """A spectrum parameter as a spectrace spectrum table (None when absent). role: "albedo" (an RGB must be in
        [0, 1]), "unbounded" (a conductor's η or k: an RGB >= 0, which the conductor uplifts), "medium" or
        "illuminant"."""
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
        if name in GLASSES:
            return {"glass": GLASSES[name]}
        path = Path(name) if Path(name).is_absolute() else location.file.parent / name
        if self.missing_assets == "placeholder" and not path.is_file() and path.suffix:
            text = f"{location}: '{shown(name, 200)}' is missing: the constant 1"
            self.placeholders.append(text)
            self.warnings.append(f"placeholder: {text}")
            return {"value": 1.0}
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

    def texture_kind(self, value: dict) -> str | None:
        """The kind of texture a TOML value holds (a named one's from the textures table), None for a spectrum."""
        name = value.get("texture")
        return self.textures[name]["type"] if name in self.textures else name
