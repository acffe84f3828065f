"""One Blender import's state: the files it writes beside the TOML (meshes and images, in a folder named after
the TOML), the names taken, and what it reports: warnings (what the scene holds that is not imported, each kind
once; `strict` makes them one error) and notes."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path

import numpy as np

from spectrace.interop.mitsuba.context import unique_name


class BlendImport:
    def __init__(self, blend_path: Path, assets: str):
        self.blend_path = blend_path
        self.assets = assets  # folder beside the TOML, named as the TOML names it
        self.files: dict[str, Callable[[Path], object]] = {}  # name relative to the TOML -> writer
        self.warnings: list[str] = []
        self.notes: list[str] = []
        self._warned: set[str] = set()
        self.materials: dict[str, dict] = {}
        self.material_names: dict[str, str] = {}  # Blender material name -> TOML name
        self.emitters: dict[str, dict | None] = {}  # TOML material name -> its emitter table, if it emits
        self.images: dict[tuple, str] = {}  # (image name, role) -> file name

    def warn(self, where: str, message: str) -> None:
        """Something in the scene that is not imported: each message once, with the first place it was met."""
        if message in self._warned:
            return
        self._warned.add(message)
        self.warnings.append(f"{where}: {message}")

    def note(self, message: str) -> None:
        if message not in self.notes:
            self.notes.append(message)

    def file_name(self, base: str, suffix: str) -> str:
        taken = {Path(name).stem: None for name in self.files}
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in base)[:64] or "item"
        return f"{self.assets}/{unique_name(safe, taken)}{suffix}"

    def add_png(self, base: str, pixels: np.ndarray) -> str:
        """An 8-bit PNG of (h, w) or (h, w, 3) code values in [0, 255]."""
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8)).save(buffer, format="PNG")
        content = buffer.getvalue()
        name = self.file_name(base, ".png")

        def write(path: Path) -> None:
            path.write_bytes(content)

        self.files[name] = write
        return name
