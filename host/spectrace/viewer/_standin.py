"""A stand-in for `spectrace.session.Session` with the same constructor and methods, used while that module is
absent: it rebuilds the renderer on each `update` (no edit in place), which is all the viewer needs of it."""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from spectrace.errors import SpectraceError
from spectrace.scene.model import Scene


@dataclass(frozen=True)
class UpdateReport:
    """What an update did: each key path and how it was applied, and the seconds it took."""

    applied: dict[str, str] = field(default_factory=dict)
    seconds: float = 0.0


def _vector(key: str, value: object) -> tuple[float, float, float]:
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    ):
        raise SpectraceError("must be 3 finite numbers", where=key)
    return (float(value[0]), float(value[1]), float(value[2]))


def _number(key: str, value: object, low: float, high: float) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not low <= value <= high:
        raise SpectraceError(f"must be a number from {low:g} to {high:g}, got {value!r}", where=key)
    return float(value)


def _check_camera(scene: Scene) -> None:
    """The camera checks of spectrace.render, wherever the tree keeps them."""
    import spectrace.api
    import spectrace.engine.job

    check = vars(spectrace.api).get("_check_camera") or vars(spectrace.engine.job)["check_camera"]
    check(scene)


class Session:
    def __init__(self, scene: Scene, *, device=None, spectral_bins: int = 0, pass_spp: int = 1, **_: object):
        from spectrace.engine.job import RenderJob

        _check_camera(scene)
        self._spectral_bins = spectral_bins
        self._pass_spp = pass_spp
        self._scales: dict[str, float] = {}
        self._loaded = RenderJob.make(scene, spectral_bins=spectral_bins, device=device).scene
        self._scene = self._loaded
        self._renderer = self._build(self._scene, device)

    def _build(self, scene: Scene, device):
        from spectrace.engine.job import RenderJob

        return RenderJob.make(scene, spectral_bins=self._spectral_bins, device=device).renderer()

    @property
    def scene(self) -> Scene:
        return self._scene

    @property
    def samples_done(self) -> int:
        return self._renderer.samples_done

    def step(self, spp: int | None = None) -> None:
        self._renderer.run_pass(spp or self._pass_spp)

    def image(self):
        return self._renderer.image()

    def parameters(self) -> dict[str, object]:
        camera = self._scene.camera
        found: dict[str, object] = {
            "camera.origin": tuple(map(float, camera.origin)),
            "camera.target": tuple(map(float, camera.target)),
            "camera.up": tuple(map(float, camera.up)),
            "camera.fov": float(camera.fov_degrees),
            "film.exposure": float(self._scene.exposure),
        }
        for shape in self._loaded.shapes:
            if shape.emitter is not None and shape.name:
                found[f"shapes.{shape.name}.emitter.scale"] = self._scales.get(shape.name, 1.0)
        return found

    def update(self, changes: Mapping[str, object]) -> UpdateReport:
        start = time.perf_counter()
        known = self.parameters()
        camera: dict[str, Any] = {}
        scales = dict(self._scales)
        exposure = self._scene.exposure
        for key, value in changes.items():
            if key not in known:
                raise SpectraceError("is no editable parameter of this scene", where=key)
            if key in ("camera.origin", "camera.target", "camera.up"):
                camera[key.split(".")[1]] = _vector(key, value)
            elif key == "camera.fov":
                camera["fov_degrees"] = _number(key, value, 1e-3, 179.0)
            elif key == "film.exposure":
                exposure = _number(key, value, -100.0, 100.0)
            else:
                scales[key.split(".")[1]] = _number(key, value, 0.0, 1e30)
        shapes = [
            dataclasses.replace(s, emitter=dataclasses.replace(s.emitter, radiance=s.emitter.radiance * scales[s.name]))
            if s.emitter is not None and s.name in scales
            else s
            for s in self._loaded.shapes
        ]
        scene = dataclasses.replace(
            self._scene, camera=dataclasses.replace(self._scene.camera, **camera), shapes=shapes, exposure=exposure
        )
        _check_camera(scene)
        self._renderer = self._build(scene, self._renderer.device)
        self._scene, self._scales = scene, scales
        return UpdateReport({key: "rebuild" for key in changes}, time.perf_counter() - start)

    def close(self) -> None:
        self._renderer = None

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()
