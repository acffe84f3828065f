"""`spectrace bench session`: what an edit of a live session costs (spectrace.session).

For each scene (the living room, the Cornell box and the textured teapot by default, and an instanced scene built in
Python) and each kind of edit (a camera move, one reflectance, one light's power, an exposure change, an instance
transform where the scene has instances): the time from `Session.update` to the end of the first pass after it, less
a pass's own time (the median of warm passes; for the exposure, which keeps the samples, the update and the image
read back), as the median of a few alternating edits (of a textured reflectance, its texture's uv_scale); and the
same edit made by loading and building the scene again (load_scene with the edited key, a new session, its first
pass), once. Mitsuba 3's Cornell box is timed the same way with `mi.traverse(scene)` and `params.update()`
followed by a render of one sample per pixel, where Mitsuba is installed (its `hdrfilm` has no exposure; its
instance edit moves a wall's `to_world`).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from pathlib import Path

from spectrace.resources import scenes_dir

DEFAULT_SCENES = ("living_room.toml", "cornell_box.toml", "teapot.toml")
INSTANCES = 64  # of the instanced scene (spectrace.benchmarks.instances), the one with instances to move
KINDS = ("camera move", "one reflectance", "one light's power", "exposure", "instance transform")


def _edits(parameters: dict[str, object]) -> dict[str, tuple[dict, dict]]:
    """Two alternating edits of each kind the scene has (by its session's key paths)."""
    found: dict[str, tuple[dict, dict]] = {}
    origin = parameters.get("camera.origin")
    if isinstance(origin, list):
        moved = [float(origin[0]) + 0.01, *origin[1:]]
        found["camera move"] = ({"camera.origin": moved}, {"camera.origin": origin})
    reflectance = next((k for k in parameters if k.startswith("materials.") and k.endswith(".reflectance")), None)
    if reflectance is not None:
        value = parameters[reflectance]
        if isinstance(value, dict) and "texture" in value:  # a textured one: its texture's placement
            scale = float(value.get("uv_scale", 1.0))
            found["one reflectance"] = ({reflectance: value | {"uv_scale": 1.25 * scale}}, {reflectance: value})
        elif isinstance(value, dict):  # a scene file's spectrum table
            found["one reflectance"] = ({reflectance: {"rgb": [0.6, 0.2, 0.1]}}, {reflectance: value})
        elif isinstance(value, (int, float)):  # a scene built in Python: its constructor's argument
            found["one reflectance"] = ({reflectance: 0.5 * float(value) or 0.3}, {reflectance: value})
    power = next(
        (k for k in parameters if k.startswith("lights.") and k.rsplit(".", 1)[1] in ("power", "intensity")), None
    )
    emitter = next((k for k in parameters if k.startswith("shapes.") and k.endswith(".emitter.radiance")), None)
    if power is not None and isinstance(parameters[power], (int, float)):
        found["one light's power"] = ({power: 2.0 * parameters[power]}, {power: parameters[power]})  # type: ignore[operator]
    elif emitter is not None:
        key = emitter.removesuffix(".radiance") + ".scale"
        found["one light's power"] = ({key: 2.0}, {key: 1.0})
    found["exposure"] = ({"film.exposure": 1.0}, {"film.exposure": 0.0})
    transform = next((k for k in parameters if k.startswith("instances.") and k.endswith(".transform")), None)
    if transform is not None:
        steps = list(parameters[transform])  # type: ignore[call-overload]
        found["instance transform"] = ({transform: [*steps, {"translate": [0.01, 0.0, 0.0]}]}, {transform: steps})
    return found


def _file_key(session, key: str) -> str:
    """A session key in the scene file's form (array entries by index), for load_scene's overrides."""
    return session._data_key(key)


def _scene_row(path: Path | None, width: int | None, pass_spp: int, repeats: int, device, log) -> dict:
    """The row of the scene file at `path`, or (None) of the instanced scene built in Python."""
    from spectrace.benchmarks.instances import instanced_scene
    from spectrace.scene import load_scene
    from spectrace.session import Session

    overrides = {} if width is None or path is None else _film_overrides(path, width)
    started = time.perf_counter()
    if path is None:
        scene = instanced_scene(INSTANCES, 20_000, width or 128, 1, 8)
    else:
        scene = load_scene(path, overrides)
    load_seconds = time.perf_counter() - started
    started = time.perf_counter()
    session = Session(scene, device=device, pass_spp=pass_spp)
    open_seconds = time.perf_counter() - started
    for _ in range(2):  # warm: the first passes pay for the queue's and the caches' start
        session.step()
    passes = []
    for _ in range(max(3, repeats)):
        started = time.perf_counter()
        session.step()
        passes.append(time.perf_counter() - started)
    pass_seconds = statistics.median(passes)
    row: dict = {
        "scene": path.name if path is not None else f"{INSTANCES} instances (Python)",
        "width": scene.width,
        "height": scene.height,
        "triangles": session.renderer.buffers.triangle_count + session.renderer.buffers.instanced_triangle_count,
        "pass_spp": pass_spp,
        "load_seconds": load_seconds,
        "open_seconds": open_seconds,
        "pass_seconds": pass_seconds,
        "kinds": {},
    }
    for kind, (edit, back) in _edits(session.parameters()).items():
        costs, update_costs, how = [], [], ""
        for i in range(repeats):
            changes = edit if i % 2 == 0 else back
            started = time.perf_counter()
            report = session.update(changes)
            updated = time.perf_counter()
            if report.restarted:
                session.step()
                costs.append(time.perf_counter() - started - pass_seconds)
            else:  # the image's setting alone: no pass to wait for, the image of the samples kept shows it
                session.image()
                costs.append(time.perf_counter() - started)
            update_costs.append(updated - started)
            how = ", ".join(sorted({step.how for step in report.steps} - {"checked"}))
        session.update(edit)
        edited = session.scene
        started = time.perf_counter()
        if path is not None:  # as a script does without a session: the file loaded with the edit, then rendered
            edited = load_scene(path, overrides | {_file_key(session, key): value for key, value in edit.items()})
        rebuilt = Session(edited, device=session.renderer.device, pass_spp=pass_spp)
        rebuilt.step()
        rebuild = time.perf_counter() - started - pass_seconds
        rebuilt.close()
        row["kinds"][kind] = {
            "how": how,
            "update_seconds": statistics.median(update_costs),
            "beyond_pass_seconds": statistics.median(costs),
            "rebuild_beyond_pass_seconds": rebuild,
        }
        log(
            f"{row['scene']}: {kind}: {statistics.median(costs) * 1e3:.1f} ms beyond the pass ({how}); "
            f"rebuilt {rebuild:.2f} s"
        )
    session.close()
    return row


def _film_overrides(path: Path, width: int) -> dict[str, object]:
    """The film scaled to `width` pixels across, its aspect kept."""
    from spectrace.scene.loader import read_scene_data

    film = read_scene_data(path)["film"]
    return {"film.width": width, "film.height": max(1, round(width * film["height"] / film["width"]))}


def _mitsuba_row(width: int, repeats: int, log) -> dict:
    """Mitsuba 3's Cornell box edited through mi.traverse and re-rendered at one sample per pixel."""
    from spectrace.benchmarks.mitsuba_runtime import usable_variants

    usable = usable_variants()
    if not usable.available:
        return {"notes": usable.notes}
    import mitsuba as mi
    import numpy as np

    variant = usable.available[0]
    mi.set_variant(variant)
    scene_dict = mi.cornell_box()
    scene_dict["sensor"]["film"]["width"] = scene_dict["sensor"]["film"]["height"] = width
    started = time.perf_counter()
    scene = mi.load_dict(scene_dict)
    load_seconds = time.perf_counter() - started

    def render() -> None:
        np.asarray(mi.render(scene, spp=1))  # the copy out waits for Dr.Jit's asynchronous launch

    for _ in range(2):
        render()
    passes = []
    for _ in range(max(3, repeats)):
        started = time.perf_counter()
        render()
        passes.append(time.perf_counter() - started)
    pass_seconds = statistics.median(passes)
    params = mi.traverse(scene)
    to_world = params["sensor.to_world"]
    moved = mi.Transform4f().translate([0.01, 0.0, 0.0]) @ to_world
    wall = params["red-wall.to_world"]
    shifted = mi.Transform4f().translate([0.0, 0.01, 0.0]) @ wall
    edits = {
        "camera move": ("sensor.to_world", moved, to_world),
        "one reflectance": ("red.reflectance.value", mi.Color3f(0.6, 0.2, 0.1), params["red.reflectance.value"]),
        "one light's power": (
            "light.emitter.radiance.value",
            2.0 * params["light.emitter.radiance.value"],
            params["light.emitter.radiance.value"],
        ),
        "instance transform": ("red-wall.to_world", shifted, wall),
    }
    row: dict = {"scene": f"Mitsuba 3 cornell_box ({variant})", "width": width, "height": width, "pass_spp": 1}
    row |= {"load_seconds": load_seconds, "pass_seconds": pass_seconds, "kinds": {}}
    for kind, (key, value, back) in edits.items():
        costs = []
        for i in range(repeats):
            started = time.perf_counter()
            params[key] = value if i % 2 == 0 else back
            params.update()
            render()
            costs.append(time.perf_counter() - started - pass_seconds)
        row["kinds"][kind] = {"how": "traverse/update", "beyond_pass_seconds": statistics.median(costs)}
        log(f"mitsuba: {kind}: {statistics.median(costs) * 1e3:.1f} ms beyond the pass")
    row["notes"] = usable.notes
    return row


def run_session_bench(
    scenes: list[Path] | None,
    width: int | None,
    pass_spp: int,
    repeats: int,
    device_key: str | None,
    mitsuba: bool = True,
    log: Callable[[str], None] = lambda text: None,
) -> dict:
    from spectrace.device import open_device

    device = open_device(device_key)
    paths: list[Path | None] = [*(scenes or [scenes_dir() / name for name in DEFAULT_SCENES]), None]
    result: dict = {"runtime": device.report.key, "rows": [], "notes": []}
    for path in paths:
        result["rows"].append(_scene_row(path, width, pass_spp, repeats, device, log))
    if mitsuba:
        try:
            row = _mitsuba_row(width or 256, repeats, log)
        except ImportError:
            result["notes"].append("Mitsuba 3 is not installed: no comparison (pip install 'spectrace[bench]')")
        else:
            if "kinds" in row:
                result["rows"].append(row)
            result["notes"] += row.get("notes", [])
    return result


def session_tables(result: dict) -> list:
    from rich.table import Table

    table = Table(
        title=f"cost of an edit beyond the first pass after it, ms [update() alone, ms] (rebuilding instead, s), "
        f"on {result['runtime']}"
    )
    for column in ("scene", "pixels", "triangles", "pass ms", *KINDS):
        table.add_column(column, justify="right")
    for row in result["rows"]:
        cells = []
        for kind in KINDS:
            cost = row["kinds"].get(kind)
            if cost is None:
                cells.append("-")
                continue
            text = f"{cost['beyond_pass_seconds'] * 1e3:.1f}"
            if "update_seconds" in cost:
                text += f" [{cost['update_seconds'] * 1e3:.1f}]"
            if "rebuild_beyond_pass_seconds" in cost:
                text += f" (rebuilt {cost['rebuild_beyond_pass_seconds']:.2f})"
            cells.append(text)
        table.add_row(
            row["scene"],
            f"{row['width']}x{row['height']}",
            f"{row.get('triangles', 0):,}" if "triangles" in row else "-",
            f"{row['pass_seconds'] * 1e3:.1f}",
            *cells,
        )
    return [table]
