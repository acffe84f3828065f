"""glTF cameras (glTF 2.0, 3.10) as spectrace's `[camera]` and `[film]`: a camera looks along its node's −z with +y
up. A perspective camera's `yfov` (radians) is the vertical field of view (`fov_axis = "y"`); an orthographic one's
`xmag`, `ymag` are half the view's width and height. `aspectRatio` (or xmag / ymag) sets the film's shape; znear
and zfar become the clipping planes. The camera imported is the first node's that has one, or the one chosen by
the camera's index or name (or its node's name); a file without cameras gets one framing its bounds."""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.gltf.context import GltfImport
from spectrace.interop.gltf.nodes import PlacedNode

FILM_WIDTH = 640  # pixels; the height follows the camera's aspect ratio
DEFAULT_ASPECT = 4.0 / 3.0
DEFAULT_FOV_Y = 40.0  # degrees, the framing camera's


def choose_camera(ctx: GltfImport, nodes: list[PlacedNode], choice: str | None) -> PlacedNode | None:
    """The node whose camera is imported: the first in the scene's order, or the one `choice` names (an index
    into `cameras`, or a camera's or node's name)."""
    with_camera = [placed for placed in nodes if "camera" in placed.node]
    if choice is None:
        return with_camera[0] if with_camera else None
    cameras = ctx.doc.array("cameras")
    for placed in with_camera:
        index = placed.node["camera"]
        camera = cameras[index] if isinstance(index, int) and 0 <= index < len(cameras) else {}
        names = [str(index), camera.get("name") if isinstance(camera, dict) else None, placed.node.get("name")]
        if choice in names:
            return placed
    available = []
    for placed in with_camera:
        index = placed.node["camera"]
        camera = cameras[index] if isinstance(index, int) and 0 <= index < len(cameras) else {}
        name = camera.get("name") if isinstance(camera, dict) else None
        available.append(f"{index}" + (f" ({name})" if isinstance(name, str) else ""))
    listed = ", ".join(available) if available else "none: the file has no camera in its scene"
    raise ctx.doc.fail("/cameras", f"no camera '{choice}' placed in the scene (cameras: {listed})")


def _frame(world: np.ndarray) -> tuple[list[float], list[float], list[float]]:
    origin = world[:3, 3]
    forward = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
    up = world[:3, :3] @ np.array([0.0, 1.0, 0.0])
    forward = forward / np.linalg.norm(forward)
    up = up / np.linalg.norm(up)
    return [float(v) for v in origin], [float(v) for v in origin + forward], [float(v) for v in up]


def camera(ctx: GltfImport, placed: PlacedNode) -> tuple[dict, dict]:
    """([camera], [film]) of a node's camera."""
    doc = ctx.doc
    index = doc.index(placed.node, "camera", placed.pointer)
    pointer = f"/cameras/{index}"
    entry = doc.item("cameras", index, f"{placed.pointer}/camera")
    if abs(np.linalg.det(placed.world[:3, :3])) < 1e-12:
        raise doc.fail(placed.pointer, "the camera's node transform is degenerate (a zero scale)")
    origin, target, up = _frame(placed.world)
    kind = entry.get("type")
    table: dict = {"origin": origin, "target": target, "up": up}
    if kind == "perspective":
        where = f"{pointer}/perspective"
        if "perspective" not in entry:
            raise doc.fail(where, "is required for a perspective camera")
        params = doc.obj(entry, "perspective", pointer)
        yfov = doc.number(params, "yfov", where)
        if not 0.0 < yfov < math.pi:
            raise doc.fail(f"{where}/yfov", f"must lie in (0, π) radians, got {yfov:g}")
        aspect = doc.number(params, "aspectRatio", where, DEFAULT_ASPECT)
        if aspect <= 0.0:
            raise doc.fail(f"{where}/aspectRatio", "must be > 0")
        table |= {"type": "perspective", "fov": math.degrees(yfov), "fov_axis": "y"}
        near = doc.number(params, "znear", where, 0.0)
        far = params.get("zfar")
    elif kind == "orthographic":
        where = f"{pointer}/orthographic"
        if "orthographic" not in entry:
            raise doc.fail(where, "is required for an orthographic camera")
        params = doc.obj(entry, "orthographic", pointer)
        xmag, ymag = doc.number(params, "xmag", where), doc.number(params, "ymag", where)
        if xmag == 0.0 or ymag == 0.0:
            raise doc.fail(where, "xmag and ymag must not be zero")
        aspect = abs(xmag / ymag)
        table |= {"type": "orthographic", "view_width": 2.0 * abs(xmag)}
        near = doc.number(params, "znear", where, 0.0)
        far = params.get("zfar")
    else:
        raise doc.fail(f"{pointer}/type", f"unknown camera type {kind!r} (perspective, orthographic)")
    if near < 0.0:
        raise doc.fail(f"{where}/znear", "must be >= 0")
    if near > 0.0:
        table["near_clip"] = near
    if far is not None:
        far = doc.number(params, "zfar", where)
        if far <= near:
            raise doc.fail(f"{where}/zfar", "must be greater than znear")
        table["far_clip"] = far
    return table, film(aspect)


def film(aspect: float) -> dict:
    return {"width": FILM_WIDTH, "height": max(1, round(FILM_WIDTH / aspect))}


def framing_camera(ctx: GltfImport, points: np.ndarray) -> tuple[dict, dict]:
    """A camera on the +z side of the bounds (glTF's front), looking at their centre along −z, far enough that
    the sphere around them fills the vertical field of view."""
    if len(points) == 0:
        if ctx.unrendered_modes:
            kinds = " and ".join(sorted(ctx.unrendered_modes))
            raise ctx.doc.fail("/", f"nothing to render: the scene's primitives are {kinds}, which have no area")
        raise ctx.doc.fail("/", "the scene has no triangles, and no camera to show anything")
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2.0
    radius = max(float(np.linalg.norm(high - low)) / 2.0, 1e-6)
    distance = radius / math.sin(math.radians(DEFAULT_FOV_Y) / 2.0)
    origin = centre + np.array([0.0, 0.0, distance])
    ctx.note(f"the file has no camera: a {DEFAULT_FOV_Y:g}° camera on +z framing the scene's bounds is made")
    table = {
        "type": "perspective",
        "origin": [float(v) for v in origin],
        "target": [float(v) for v in centre],
        "up": [0.0, 1.0, 0.0],
        "fov": DEFAULT_FOV_Y,
        "fov_axis": "y",
    }
    return table, film(DEFAULT_ASPECT)
