"""What a camera plugin is: the shape of a camera's module (`CameraPlugin`), which mypy checks every module of
spectrace.cameras.CAMERAS against. The model's `Camera` (spectrace.scene.model) is one dataclass for every type."""

from typing import Any, Protocol

import numpy as np

from spectrace.core.registry import TabledPlugin


class CameraPlugin(TabledPlugin, Protocol):
    """What a camera's module holds, with its importer mappings: MITSUBA_PLUGINS with `from_mitsuba(importer,
    sensor, properties, camera, linear, aspect)` (the Mitsuba 3 sensors it imports; `camera` the placement read
    already) and `to_mitsuba(camera, exporter)` (the export), or MITSUBA_NONE saying why it has none; PBRT_CAMERAS
    with `from_pbrt` (pbrt-v4's cameras it maps). Beside these, where they apply: SPEC_CHECKS (rules spanning
    several keys, for the scene schema); PBRT_MIRRORED (its image runs the other way round from pbrt's, so the
    import mirrors the world the other way), pbrt_maps(context, camera) (whether it maps this camera of a pbrt type
    that several modules share, before the world's mirror is chosen) and PBRT_CONDITION (what the refusal of
    another pbrt camera says it takes of the type)."""

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    @property
    def PBRT_CAMERAS(self) -> tuple[str, ...]: ...  # noqa: N802

    def from_pbrt(self, context: Any, camera: Any, view: Any) -> dict | None:
        """The [camera] table of a pbrt-v4 Camera of PBRT_CAMERAS (`view`: what pbrt's cameras share,
        spectrace.interop.pbrt.cameras.View), or None where another module of the same pbrt type maps it."""
        ...

    def basis(self, camera: Any, aspect_ratio: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """RenderParams' camera_origin, camera_forward, camera_right and camera_up for an image of width / height =
        aspect_ratio (kernels/camera.cl reads them per type)."""
        ...

    def lens(self, camera: Any) -> tuple[float, float]:
        """RenderParams.lens.xy: the aperture radius and the focus distance (zeros for a camera without a lens)."""
        ...
