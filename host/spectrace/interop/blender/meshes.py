"""Blender's evaluated meshes (modifiers and geometry nodes applied) as triangle meshes in object space, one per
material slot: each face corner's position, its shading normal (Blender's corner normals, which hold sharp edges
and custom normals; none where every face is flat, so that each triangle shades with its own normal as Cycles
does) and its UV from the active UV map; corners alike in all of these share a vertex.

Everything is read with `foreach_get` into numpy arrays of the element type Blender stores (float32, int32: any
other type makes Blender convert element by element), the generic attribute arrays first ("position",
".corner_vert", "material_index"), which Blender copies whole; and no step loops over faces in Python."""

from __future__ import annotations

import numpy as np

from spectrace.interop.pbrt.meshes import MeshData

# Rounds of matching corners against their vertex's first unmatched corner before the remainder is sorted: a
# vertex whose corners hold k distinct normal/UV pairs needs k rounds.
_MATCH_ROUNDS = 8


def _read(collection, attribute: str, count: int, width: int, dtype) -> np.ndarray:
    values = np.empty(count * width, dtype=dtype)
    collection.foreach_get(attribute, values)
    return values.reshape(count, width) if width > 1 else values


def _attribute(mesh, name: str, attribute: str, count: int, width: int, dtype) -> np.ndarray | None:
    """A generic attribute's values (copied whole by Blender), or None where the mesh lacks it."""
    found = mesh.attributes.get(name)
    return None if found is None else _read(found.data, attribute, count, width, dtype)


def shared_corners(corner_vertex: np.ndarray, values: np.ndarray | None, vertex_count: int):
    """Which corners become one vertex: those of the same Blender vertex whose `values` rows (normal, UV; compared
    bit for bit) are equal. Returns (label of each corner, the first corner of each label); labels are numbered in
    the order their first corners come, round by round.

    Most corners equal their vertex's first corner, so each round labels a vertex's first unmatched corner and
    every corner equal to it (linear time); a remainder after `_MATCH_ROUNDS` rounds is grouped by sorting."""
    count = len(corner_vertex)
    order = np.arange(count)
    if values is None:
        first_of_vertex = np.full(vertex_count, -1, dtype=np.int64)
        first_of_vertex[corner_vertex[::-1]] = order[::-1]
        used = first_of_vertex >= 0
        relabel = np.cumsum(used) - 1
        return relabel[corner_vertex], first_of_vertex[used]
    bits = np.ascontiguousarray(values).view(np.uint32).reshape(count, -1)
    label = np.full(count, -1, dtype=np.int64)
    pending = order
    firsts: list[np.ndarray] = []
    labelled = 0
    first_of_vertex = np.empty(vertex_count, dtype=np.int64)
    for _ in range(_MATCH_ROUNDS):
        if len(pending) == 0:
            break
        vertices = corner_vertex[pending]
        first_of_vertex[vertices[::-1]] = pending[::-1]  # the earliest pending corner of each vertex
        leader = first_of_vertex[vertices]
        leaders = pending[leader == pending]
        label[leaders] = labelled + np.arange(len(leaders))
        labelled += len(leaders)
        firsts.append(leaders)
        same = np.all(bits[pending] == bits[leader], axis=1)
        label[pending[same]] = label[leader[same]]
        pending = pending[~same]
    if len(pending):
        keys = np.column_stack([corner_vertex[pending].astype(np.int64), bits[pending].astype(np.int64)])
        _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        rank = np.argsort(np.argsort(first))  # numbered in the order of their first corners
        label[pending] = labelled + rank[inverse.ravel()]
        firsts.append(pending[np.sort(first)])
    return label, np.concatenate(firsts)


def _compact(faces: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """(the vertices `faces` use, in order; `faces` renumbered into them)."""
    used = np.zeros(count, dtype=bool)
    used[faces.ravel()] = True
    relabel = np.cumsum(used) - 1
    return np.flatnonzero(used), relabel[faces]


def evaluated_meshes(obj, with_tangents: bool = False, warn=None) -> dict[int, MeshData]:
    """Material slot index -> the triangles of that slot, of an evaluated object (one that has a mesh).

    `with_tangents` (a normal map shades it) adds each corner's MikkTSpace tangent and bitangent sign on the UV map
    the export uses, as Cycles frames its normal maps (xyz along +u, w the sign: the bitangent is w (n × t), up the
    image), with the corner normals MikkTSpace was given, flat faces' included (a file's tangents go with vertex
    normals). Blender computes tangents on triangles and quads only: a mesh with larger polygons keeps the frame
    of its texture coordinates, and `warn` is told."""
    mesh = obj.to_mesh()
    try:
        if mesh is None or len(mesh.polygons) == 0:
            return {}
        mesh.calc_loop_triangles()
        count, corner_count, vertex_count = len(mesh.loop_triangles), len(mesh.loops), len(mesh.vertices)
        corners = _read(mesh.loop_triangles, "loops", count, 3, np.int32)
        slots = _attribute(mesh, "material_index", "value", len(mesh.polygons), 1, np.int32)
        if slots is not None:
            slots = slots[_read(mesh.loop_triangle_polygons, "value", count, 1, np.int32)]
        corner_vertex = _attribute(mesh, ".corner_vert", "value", corner_count, 1, np.int32)
        if corner_vertex is None:
            corner_vertex = _read(mesh.loops, "vertex_index", corner_count, 1, np.int32)
        positions = _attribute(mesh, "position", "vector", vertex_count, 3, np.float32)
        if positions is None:
            positions = _read(mesh.vertices, "co", vertex_count, 3, np.float32)
        domain = mesh.normals_domain
        normals = None if domain == "FACE" else _read(mesh.corner_normals, "vector", corner_count, 3, np.float32)
        uv_layer = mesh.uv_layers.active
        uvs = _read(uv_layer.uv, "vector", corner_count, 2, np.float32) if uv_layer is not None else None
        tangents = _tangents(mesh, uv_layer, corner_count, warn) if with_tangents and uvs is not None else None
        if tangents is not None and normals is None:
            normals, domain = _read(mesh.corner_normals, "vector", corner_count, 3, np.float32), "CORNER"
    finally:
        obj.to_mesh_clear()
    # smooth shading (normals per vertex) needs no normal in the key: corners of one vertex hold the same one
    keyed = [a for a in (normals if domain == "CORNER" else None, uvs, tangents) if a is not None]
    label, first = shared_corners(corner_vertex, np.column_stack(keyed) if keyed else None, vertex_count)
    faces_all = label[corners]
    vertices_all = positions[corner_vertex[first]].astype(np.float64)
    normals_all = normals[first].astype(np.float64) if normals is not None else None
    uvs_all = uvs[first].astype(np.float64) if uvs is not None else None
    tangents_all = tangents[first].astype(np.float64) if tangents is not None else None
    if slots is None or np.all(slots == slots[0]):
        groups = [(int(slots[0]) if slots is not None else 0, faces_all)]
    else:
        groups = [(int(slot), faces_all[slots == slot]) for slot in np.unique(slots)]
    found: dict[int, MeshData] = {}
    for slot, faces in groups:
        if len(groups) == 1:
            used, local = np.arange(len(first)), faces
        else:
            used, local = _compact(faces, len(first))
        found[slot] = MeshData(
            vertices=vertices_all[used],
            faces=local.astype(np.int64),
            normals=normals_all[used] if normals_all is not None else None,
            uvs=uvs_all[used] if uvs_all is not None else None,
            tangents=tangents_all[used] if tangents_all is not None else None,
        )
    return found


def _tangents(mesh, uv_layer, corner_count: int, warn) -> np.ndarray | None:
    """(corners, 4): each corner's MikkTSpace tangent and bitangent sign on `uv_layer`, or None (a warning) where
    Blender cannot compute them."""
    try:
        mesh.calc_tangents(uvmap=uv_layer.name)
    except RuntimeError as error:
        if warn is not None:
            warn(f"{error}".strip().removeprefix("Error: ") + " (its normal map follows the texture coordinates)")
        return None
    tangents = np.empty((corner_count, 4), dtype=np.float32)
    tangents[:, :3] = _read(mesh.loops, "tangent", corner_count, 3, np.float32)
    tangents[:, 3] = _read(mesh.loops, "bitangent_sign", corner_count, 1, np.float32)
    mesh.free_tangents()
    return tangents
