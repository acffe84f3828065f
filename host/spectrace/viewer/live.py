"""The viewer's render loop and what the page asks of it, apart from HTTP: a thread runs the session's passes up
to the scene's spp; display transforms (exposure, colour space, white balance, channel, false colour) are applied
to the accumulated XYZ without a new pass; camera moves and parameter edits go through `Session.update`, which
restarts the accumulation; a pixel's spectrum comes from the session's spectral bins.

Every value a request sends is checked here with the scene format's own checks and refused as a SpectraceError
naming the value, before anything changes."""

from __future__ import annotations

import importlib
import importlib.util
import io
import math
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.film.response import OBSERVERS

DISPLAY_SPACES = ("srgb", "display-p3", "rec2020")  # xyz has no display encoding
SPECTRAL_BINS = 47  # 10 nm bands over the default 360-830 nm film: a pixel's spectrum in the page
MAX_ORBIT_DEGREES = 360.0
ZOOM_LIMITS = (0.01, 100.0)
AVERAGE_SIZES = (1, 3, 5)  # the pixel windows a spectrum may be averaged over


def _number(value: object, where: str, low: float, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SpectraceError(f"must be a finite number, got {value!r}", where=where)
    if not low <= value <= high:
        raise SpectraceError(f"must be from {low:g} to {high:g}, got {value:g}", where=where)
    return float(value)


def _whole(value: object, where: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise SpectraceError(f"must be a whole number from {low} to {high}, got {value!r}", where=where)
    return value


@dataclass(frozen=True)
class Display:
    """How the accumulated film is shown: none of it needs a new pass."""

    exposure: float = 0.0
    colour_space: str = "srgb"
    white_balance: str = ""  # "" none, else what parse_white_balance reads
    false_colour: bool = False  # luminance on a log scale (spectrace.plots.false_colour)
    channel: str = ""  # "" the film's XYZ; an observer's label; a sensor channel's name

    def changed(self, data: Mapping[str, object], channels: tuple[str, ...]) -> Display:
        """This display with `data`'s values, each checked as the scene file and command line check it."""
        from spectrace.core import limits
        from spectrace.film.colour_output import parse_white_balance

        known = {"exposure", "colour_space", "white_balance", "false_colour", "channel"}
        for key in data:
            if key not in known:
                raise SpectraceError(f"unknown display setting (use {', '.join(sorted(known))})", where=str(key))
        new = self
        if "exposure" in data:
            value = data["exposure"]
            if problem := limits.exposure_problem(value):  # type: ignore[arg-type]
                raise SpectraceError(problem, where="exposure")
            new = replace(new, exposure=float(value))  # type: ignore[arg-type]
        if "colour_space" in data:
            space = data["colour_space"]
            if space not in DISPLAY_SPACES:
                raise SpectraceError(
                    f"unknown colour space {space!r} (use {', '.join(DISPLAY_SPACES)})", "colour_space"
                )
            new = replace(new, colour_space=str(space))
        if "white_balance" in data:
            white = data["white_balance"]
            if not isinstance(white, str) or len(white) > 200:
                raise SpectraceError("must be a short text (A, D50, 3200K, 'x,y')", where="white_balance")
            if white.strip():
                parse_white_balance(white, where="white_balance")
            new = replace(new, white_balance=white.strip())
        if "false_colour" in data:
            if not isinstance(data["false_colour"], bool):
                raise SpectraceError("must be true or false", where="false_colour")
            if data["false_colour"] and importlib.util.find_spec("matplotlib") is None:
                raise SpectraceError("needs matplotlib's colour maps (pip install matplotlib)", where="false_colour")
            new = replace(new, false_colour=data["false_colour"])
        if "channel" in data:
            if data["channel"] != "" and data["channel"] not in channels:
                raise SpectraceError(f"unknown channel {data['channel']!r}", where="channel")
            new = replace(new, channel=str(data["channel"]))
        return new


def image_channels(image) -> tuple[str, ...]:
    """The film's other responses shown in place of its XYZ: observers (as XYZ) and single sensor channels."""
    from spectrace.film.response import OBSERVERS

    names = [label for label, (prefix, _) in OBSERVERS.items() if f"{prefix}.X" in image.channels]
    names += [name for name in image.channels if name.startswith("sensor.")]
    return tuple(names)


def display_rgb(image, display: Display) -> np.ndarray:
    """(H, W, 3) display-encoded values in [0, 1] of `image` under `display`."""
    from spectrace.film.colour_output import ColourSpace, encode_for_display, parse_white_balance, xyz_to_output
    from spectrace.film.response import OBSERVERS, observer_xyz_image

    if display.channel in OBSERVERS:
        xyz = observer_xyz_image(image.channels, display.channel)
    elif display.channel:
        plane = image.channels[display.channel]
        xyz = np.repeat(plane[..., None] / max(float(np.percentile(plane, 99.9)), 1e-30), 3, axis=-1)
        xyz = xyz * np.array([0.9505, 1.0, 1.089])  # grey: D65 white
    else:
        xyz = image.xyz
    if display.false_colour:
        from spectrace.plots import default_limits, false_colour
        from spectrace.spectral.observers import LUMINOUS_EFFICACY_LM_PER_W

        luminance = xyz[..., 1] * LUMINOUS_EFFICACY_LM_PER_W
        return false_colour(luminance, default_limits(luminance, "log"), "log")[..., :3]
    white = parse_white_balance(display.white_balance, where="white_balance") if display.white_balance else None
    space = ColourSpace(display.colour_space)
    return encode_for_display(xyz_to_output(xyz, space, white, display.exposure), space)


def shown_space(display: Display) -> str:
    """The colour space of the values `display_rgb` gives: false colour's map is sRGB."""
    return "srgb" if display.false_colour else display.colour_space


def png_bytes(rgb: np.ndarray, space: str = "srgb") -> bytes:
    """8-bit PNG of display-encoded `rgb` in colour space `space`. A space other than sRGB is tagged with its ICC
    profile, which browsers apply to an <img> (and to a canvas it is drawn into), so Display P3 and Rec.2020 values
    are shown as those colours rather than taken for sRGB ones; an untagged PNG is sRGB."""
    from PIL import Image as PILImage

    from spectrace.film.colour_output import ColourSpace
    from spectrace.film.icc_profile import icc_profile

    colour_space = ColourSpace(space)
    options = {} if colour_space is ColourSpace.SRGB else {"icc_profile": icc_profile(colour_space)}
    buffer = io.BytesIO()
    pixels = np.rint(np.clip(rgb, 0, 1) * 255).astype(np.uint8)
    PILImage.fromarray(pixels, "RGB").save(buffer, format="PNG", **options)
    return buffer.getvalue()


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _rotate(v: np.ndarray, axis: np.ndarray, degrees: float) -> np.ndarray:
    """Rodrigues' rotation of `v` about the unit `axis`."""
    a = math.radians(degrees)
    return v * math.cos(a) + np.cross(axis, v) * math.sin(a) + axis * np.dot(axis, v) * (1 - math.cos(a))


def camera_move(parameters: Mapping[str, Any], action: str, dx: float, dy: float) -> dict[str, object]:
    """The camera keys after an orbit (degrees about the target), a pan (fractions of the distance to the target) or
    a zoom (dy: the factor on that distance), from the session's camera.origin, camera.target and camera.up."""
    origin = np.asarray(parameters["camera.origin"], np.float64)
    target = np.asarray(parameters["camera.target"], np.float64)
    up = _unit(np.asarray(parameters.get("camera.up", (0.0, 1.0, 0.0)), np.float64))  # the scene format's default
    offset = origin - target
    right = _unit(np.cross(-offset, up))
    if action == "orbit":
        offset = _rotate(offset, up, -dx)
        turned = _rotate(offset, _unit(np.cross(offset, up)), dy)
        # Stop short of the poles, where the view would flip about `up`.
        if abs(np.dot(_unit(turned), up)) < 0.995:
            offset = turned
        origin = target + offset
    elif action == "pan":
        shift = (right * -dx + np.cross(right, _unit(-offset)) * dy) * np.linalg.norm(offset)
        origin, target = origin + shift, target + shift
    else:
        origin = target + offset * dy
    return {"camera.origin": [float(v) for v in origin], "camera.target": [float(v) for v in target]}


def _json_value(value: object) -> object | None:
    """A parameter's value as JSON, or None for a value the page cannot edit (a spectrum, a texture)."""
    if isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, float, np.floating, np.integer)):
        return float(value) if math.isfinite(float(value)) else None
    if isinstance(value, (list, tuple, np.ndarray)):
        items = [_json_value(v) for v in value]
        return items if all(isinstance(v, float) for v in items) else None
    return None


EMITTER = ".emitter."


def light_controls(parameters: Mapping[str, object]) -> dict[str, float]:
    """The page's light switches, key path -> value: each emitting shape's `emitter.scale` (a key every area
    emitter takes, 1 where the file leaves it out) and each number of a light's own (`lights.<name>.scale`)."""
    found: dict[str, float] = {}
    for key, value in parameters.items():
        if EMITTER in key:
            scale = key[: key.index(EMITTER) + len(EMITTER)] + "scale"
            given = parameters.get(scale, 1.0)
            found[scale] = float(given) if isinstance(_json_value(given), float) else 1.0  # type: ignore[arg-type]
        elif key.startswith("lights.") and isinstance(_json_value(value), float):
            found[key] = float(value)  # type: ignore[arg-type]
    return found


class LiveView:
    """A session rendered pass by pass on a thread of its own, up to `spp` samples per pixel, then idle until an
    edit restarts it. `session_lock` serialises every call into the session; `changed` (a condition) guards the
    cached state and wakes whoever waits for a new pass."""

    def __init__(self, session: Any, spp: int, pass_spp: int = 1, scene_exposure: float = 0.0):
        self.session = session
        self.spp = spp
        self.pass_spp = pass_spp
        self.session_lock = threading.RLock()
        self.changed = threading.Condition()
        self.scene_exposure = scene_exposure
        self.display = Display(exposure=scene_exposure)
        self.version = 0  # counts passes and restarts: the page's image and state follow it
        self.display_version = 0
        self.paused = False
        self.closed = False
        self.edits: dict[str, object] = {}  # every key path edited, its last value (for the saved TOML)
        self.error = ""  # the last problem of the render thread, shown in the page
        self.reference: tuple[int, int, np.ndarray] | None = None
        self._image: Any = None
        self._seconds = 0.0
        self._read_seconds = 0.0  # what reading the film back took last time
        self._last_read = 0.0  # render seconds at that read
        self._generation = 0  # counts updates: a pass of the scene before one is not shown after it
        self._stale = False  # passes were added since the film was last read
        self._parameters: dict[str, object] = session.parameters()  # read again after each update only
        self._observer: str = session.scene.film_response.observer  # of the film's XYZ; ΔE uses its D65 white
        self._png: tuple[tuple[int, int], bytes] | None = None
        self._thread = threading.Thread(target=self._run, name="spectrace-view-render", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _wanted(self) -> bool:
        return not self.closed and not self.paused and self.session.samples_done < self.spp

    def _run(self) -> None:
        while True:
            with self.changed:
                while not self.closed and not self._wanted() and not self._stale:
                    self.changed.wait()
                if self.closed:
                    return
            with self.session_lock:
                generation, elapsed, image = self._generation, 0.0, None
                try:
                    if self._wanted():
                        start = time.perf_counter()
                        self.session.step(min(self.pass_spp, self.spp - self.session.samples_done))
                        elapsed = time.perf_counter() - start
                    # The film is read back after a pass when that costs at most a fifth of the time since the
                    # last read (a large film's spectral bands take long to read), and whenever the render rests.
                    since = self._seconds + elapsed - self._last_read
                    if since >= 4 * self._read_seconds or not self._wanted():
                        read = time.perf_counter()
                        image = self.session.image()
                        self._read_seconds = time.perf_counter() - read
                        self._last_read = self._seconds + elapsed
                except Exception as error:  # the page says why and waits; the server goes on
                    problem = str(error) if isinstance(error, SpectraceError) else f"{type(error).__name__}: {error}"
                    with self.changed:
                        self.error, self.paused, self._stale = problem, True, False
                        self.version += 1
                        self.changed.notify_all()
                    continue
            with self.changed:
                if generation != self._generation:
                    continue
                self._seconds += elapsed
                self._stale = image is None
                if image is not None:
                    self._image = image
                    self.version += 1
                    self.changed.notify_all()

    def close(self) -> None:
        with self.changed:
            self.closed = True
            self.changed.notify_all()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join()

    # ---------------------------------------------------------------- what the page asks

    def image(self):
        with self.changed:
            return self._image

    def _stamp(self) -> tuple[int, int]:
        return self.version, self.display_version

    def wait_for_change(self, seen: tuple[int, int] | None, timeout: float) -> tuple[int, int]:
        """Wait until a pass, a restart or a display change makes the state differ from stamp `seen`, or `timeout`
        seconds; the stamp now."""
        with self.changed:
            self.changed.wait_for(lambda: self._stamp() != seen or self.closed, timeout)
            return self._stamp()

    def state(self) -> dict[str, object]:
        with self.changed:
            parameters = self._parameters
            image, done = self._image, (self._image.spp if self._image is not None else 0)
            rate = self._seconds / done if done else None
            return {
                "version": self.version,
                "spp": done,
                "target_spp": self.spp,
                "seconds": round(self._seconds, 3),
                "eta": round(rate * (self.spp - done), 3) if rate is not None else None,
                "paused": self.paused,
                "width": image.width if image is not None else None,
                "height": image.height if image is not None else None,
                "display": self.display.__dict__,
                "channels": list(image_channels(image)) if image is not None else [],
                "spaces": list(DISPLAY_SPACES),
                "observer": self._observer,
                "observers": list(OBSERVERS),
                "lights": light_controls(parameters),
                "parameters": {k: j for k, v in parameters.items() if (j := _json_value(v)) is not None},
                "error": self.error,
                "reference": list(self.reference[:2]) if self.reference is not None else None,
            }

    def png(self) -> bytes | None:
        with self.changed:
            image, key, display = self._image, (self.version, self.display_version), self.display
            if self._png is not None and self._png[0] == key:
                return self._png[1]
        if image is None:
            return None
        data = png_bytes(display_rgb(image, display), shown_space(display))
        with self.changed:
            self._png = (key, data)
        return data

    def set_display(self, data: Mapping[str, object]) -> None:
        with self.changed:
            image = self._image
            channels = image_channels(image) if image is not None else ()
            self.display = self.display.changed(data, channels)
            self.display_version += 1
            self.changed.notify_all()

    def set_paused(self, paused: object) -> None:
        if not isinstance(paused, bool):
            raise SpectraceError("must be true or false", where="paused")
        with self.changed:
            self.paused = paused
            if not paused:
                self.error = ""
            self.version += 1
            self.changed.notify_all()

    def update(self, changes: Mapping[str, object]) -> None:
        """Edit the scene through the session (checked there; nothing applied on a refusal); the accumulation
        restarts."""
        if not isinstance(changes, Mapping) or not changes:
            raise SpectraceError("must be a table of key paths and values", where="changes")
        with self.session_lock:
            self.session.update(dict(changes))
            parameters = self.session.parameters()
            observer = self.session.scene.film_response.observer
            self._generation += 1
        with self.changed:
            self.edits.update(changes)
            self._parameters, self._observer = parameters, observer
            self._image, self._seconds, self._last_read, self.error = None, 0.0, 0.0, ""
            self._stale = False
            self.version += 1
            self.changed.notify_all()

    def move_camera(self, action: object, dx: object, dy: object) -> None:
        if action not in ("orbit", "pan", "zoom"):
            raise SpectraceError(f"unknown camera action {action!r} (use orbit, pan or zoom)", where="action")
        if action == "zoom":
            x, y = 0.0, _number(dy, "dy", *ZOOM_LIMITS)
        else:
            limit = MAX_ORBIT_DEGREES if action == "orbit" else 10.0
            x, y = _number(dx, "dx", -limit, limit), _number(dy, "dy", -limit, limit)
        with self.session_lock:  # the pose moved from is the one the update replaces
            changes = camera_move(self.session.parameters(), str(action), x, y)
            self.update(changes)

    def _pixel_at(self, x: object, y: object, size: object = 1):
        """The image, the pixel's column and row, and the window of `size` x `size` pixels about it (clipped to
        the image) as row and column slices."""
        image = self.image()
        if image is None:
            raise SpectraceError("no pass has finished yet", where="pixel")
        column = _whole(x, "x", 0, image.width - 1)
        row = _whole(y, "y", 0, image.height - 1)
        if size not in AVERAGE_SIZES or isinstance(size, bool):
            raise SpectraceError(f"must be {', '.join(map(str, AVERAGE_SIZES))}, got {size!r}", where="size")
        half = int(size) // 2
        window = (slice(max(row - half, 0), row + half + 1), slice(max(column - half, 0), column + half + 1))
        return image, column, row, window

    def set_reference(self, x: object, y: object, size: object = 1) -> None:
        image, column, row, window = self._pixel_at(x, y, size)
        xyz = image.xyz[window].reshape(-1, 3).astype(np.float64).mean(axis=0)
        with self.changed:
            self.reference = (column, row, xyz)

    def pixel(self, x: object, y: object, size: object = 1) -> dict[str, object]:
        """A pixel's XYZ, xy, spectrum (band-averaged radiance, W/(m² sr nm)) with the observer's curves on the
        same bands, and its CIEDE2000 to the reference pixel in CIELAB of the displayed white (Y = 2^-exposure).
        With `size` 3 or 5, each is the mean over the size x size pixels about it (those inside the image), and
        `radiance_error` the standard error of the spectrum's mean, from the spread between those pixels: one
        pixel's estimate is as noisy as its samples are few, and the mean of n neighbours on an even surface is
        √n times less so."""
        from spectrace.film.response import delta_e_2000_map, observer_cmfs
        from spectrace.spectral.grid import GRID_NM

        image, column, row, window = self._pixel_at(x, y, size)
        pixels = image.xyz[window].reshape(-1, 3).astype(np.float64)
        xyz = pixels.mean(axis=0)
        total = float(xyz.sum())
        result: dict[str, object] = {
            "x": column,
            "y": row,
            "size": size,
            "pixels": len(pixels),
            "xyz": [float(v) for v in xyz],
            "xy": [float(xyz[0] / total), float(xyz[1] / total)] if total > 0 else None,
        }
        if image.spectral is not None:
            centres = image.spectral.centres_nm
            with self.changed:
                observer = self._observer
            cmfs = observer_cmfs(observer)
            spectra = image.spectral.radiance[window].reshape(len(pixels), -1).astype(np.float64)
            result["wavelengths_nm"] = [float(v) for v in centres]
            result["radiance"] = [float(v) for v in spectra.mean(axis=0)]
            if len(spectra) > 1:
                error = spectra.std(axis=0, ddof=1) / np.sqrt(len(spectra))
                result["radiance_error"] = [float(v) for v in error]
            result["observer"] = {
                "label": observer,
                "curves": [[float(v) for v in np.interp(centres, GRID_NM, cmfs[:, i])] for i in range(3)],
            }
        with self.changed:
            reference, exposure, observer = self.reference, self.display.exposure, self._observer
        if reference is not None:
            white_y = 2.0**-exposure
            delta = delta_e_2000_map(xyz[None], reference[2][None], observer, observer, white_y=white_y)
            result["delta_e"] = float(np.asarray(delta).reshape(-1)[0])
            result["reference"] = [reference[0], reference[1]]
        return result
