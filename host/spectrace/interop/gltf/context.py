"""One glTF import's state: the document, the files it writes beside the TOML (meshes and images, in a folder
named after the TOML), the names taken, and what it reports: warnings (what the file holds that is not imported;
`strict` makes them one error) and notes (what spectrace does its own way)."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path

import numpy as np

from spectrace.interop.gltf.document import GltfDocument
from spectrace.interop.mitsuba.context import unique_name
from spectrace.interop.pbrt.meshes import MeshData

# The photometric factor of the glTF units: a spectrum of luminance factor Y (film Y: ∫ S ȳ dλ / ∫ ȳ dλ) has the
# photometric value 683 lm/W · ∫ȳ dλ · Y (spectrace.engine.meters), so candela, lux and nits divide by it to give
# the `scale` of a D65-shaped `{ rgb = ... }` spectrum in W/(sr nm), W/(m² nm) and W/(m² sr nm).
LUMINOUS_EFFICACY_LM_PER_W = 683.0


def photometric_scale() -> float:
    """683 lm/W · ∫ȳ dλ (CIE 1931, on spectrace's wavelength grid): lumens of the spectrum `{ rgb = [1, 1, 1] }`."""
    from spectrace.spectral.colorimetry import CIE_Y_INTEGRAL

    return LUMINOUS_EFFICACY_LM_PER_W * CIE_Y_INTEGRAL


class GltfImport:
    def __init__(self, doc: GltfDocument, assets: str, material_model: str = "principled"):
        self.doc = doc
        self.assets = assets  # folder beside the TOML, named as the TOML names it
        self.material_model = material_model  # "principled", or "diffuse": the base colour only
        self.files: dict[str, Callable[[Path], object]] = {}  # name relative to the TOML -> writer
        self.warnings: list[str] = []
        self.notes: list[str] = []
        self._warned: set[str] = set()
        self.materials: dict[str, dict] = {}
        self.material_names: dict[int | None, str] = {}
        self.emitters: dict[int | None, dict | None] = {}
        self.interiors: dict[int | None, dict | None] = {}  # material -> the medium filling the meshes using it
        self.images: dict[tuple, str] = {}  # (image index, role, factor) -> file name
        self.decoded: dict[int, np.ndarray] = {}
        self.meshes: dict[str, MeshData] = {}  # PLY file name -> its MeshData
        self.origins: dict[str, str] = {}  # TOML key path -> the JSON pointer it was imported from
        self.unrendered_modes: set[str] = set()  # kinds of primitive left out (points, lines), for a file of only them

    def warn(self, pointer: str, message: str) -> None:
        """Something in the file that is not imported; each (pointer-free) message once, with its first place."""
        if message in self._warned:
            return
        self._warned.add(message)
        self.warnings.append(f"{pointer or '/'}: {message}")

    def note(self, message: str) -> None:
        if message not in self.notes:
            self.notes.append(message)

    def file_name(self, base: str, suffix: str) -> str:
        taken = {Path(name).stem: None for name in self.files}
        # names come from the file's meshes: kept short enough for any file system with the number a clash adds
        return f"{self.assets}/{unique_name(base[:64], taken)}{suffix}"

    def add_file(self, base: str, suffix: str, content: bytes) -> str:
        name = self.file_name(base, suffix)

        def write(path: Path) -> None:
            path.write_bytes(content)

        self.files[name] = write
        return name

    def add_png(self, base: str, pixels: np.ndarray) -> str:
        """An 8-bit PNG of (h, w) or (h, w, 3) code values in [0, 255]."""
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8)).save(buffer, format="PNG")
        return self.add_file(base, ".png", buffer.getvalue())
