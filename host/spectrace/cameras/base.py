"""What a camera plugin is: the shape of a camera's module (`CameraPlugin`), which mypy checks every module of
spectrace.cameras.CAMERAS against. The model's `Camera` (spectrace.scene.model) is one dataclass for every type."""

from typing import Any, Protocol

import numpy as np

from spectrace.core.registry import TabledPlugin


class CameraPlugin(TabledPlugin, Protocol):
    """What a camera's module holds. Beside these, where it applies: SPEC_CHECKS (rules spanning several keys, for
    the scene schema)."""

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    def basis(self, camera: Any, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """RenderParams' camera_origin, camera_forward, camera_right and camera_up for an image of width / height =
        aspect_ratio (kernels/camera.cl reads them per type)."""
        ...

    def lens(self, camera: Any) -> tuple[float, float]:
        """RenderParams.lens.xy: the aperture radius and the focus distance (zeros for a camera without a lens)."""
        ...
