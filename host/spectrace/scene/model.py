"""A scene resolved for rendering: world-space meshes, spectra on the wavelength grid, validated settings.

These are the objects the Python API builds directly and the TOML loader produces; the renderer consumes only
these, never the file format.
"""

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from spectrace.geometry.mesh import TriangleMesh
from spectrace.spectral.spectrum import Spectrum


@dataclass(frozen=True)
class Camera:
    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov_degrees: float = 45.0
    fov_axis: Literal["x", "y"] = "x"

    def basis(self, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """origin, forward, right·tan(fov_x/2), up·tan(fov_y/2) for an image of width/height = aspect_ratio.

        right = forward × up, so with +y up and +z forward the image's right is world -x (as in the Cornell box
        data, whose red wall at x ≈ 550 mm appears on the left).
        """
        origin = np.asarray(self.origin, float)
        forward = np.asarray(self.target, float) - origin
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(self.up, float))
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        tan_half = np.tan(np.radians(self.fov_degrees) / 2.0)
        if self.fov_axis == "x":
            tan_x, tan_y = tan_half, tan_half / aspect_ratio
        else:
            tan_x, tan_y = tan_half * aspect_ratio, tan_half
        return origin, forward, right * tan_x, up * tan_y


@dataclass(frozen=True)
class DiffuseMaterial:
    reflectance: Spectrum


Material = DiffuseMaterial


@dataclass(frozen=True)
class AreaEmitter:
    radiance: Spectrum  # W/(m² sr nm), scale already applied
    two_sided: bool = False


@dataclass(frozen=True)
class Shape:
    mesh: TriangleMesh  # world space
    material: Material
    emitter: AreaEmitter | None = None
    name: str = ""


@dataclass(frozen=True)
class Scene:
    camera: Camera
    width: int
    height: int
    shapes: list[Shape]
    max_depth: int = 8
    rr_depth: int = 5
    spp: int = 16
    seed: int = 0
    source: Path | None = None
    notes: dict = field(default_factory=dict)

    def with_overrides(self, **changes) -> "Scene":
        """A copy with some settings replaced (spp, width, height, seed, max_depth, ...); None keeps a value."""
        from dataclasses import replace

        return replace(self, **{k: v for k, v in changes.items() if v is not None})
