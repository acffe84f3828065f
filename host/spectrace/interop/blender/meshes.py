"""Blender's evaluated meshes (modifiers and geometry nodes applied) as triangle meshes in object space, one per
material slot: each face corner's position, its shading normal (Blender's corner normals, which hold flat faces,
sharp edges and custom normals) and its UV from the active UV map; corners alike in all three share a vertex."""

from __future__ import annotations

import numpy as np

from spectrace.interop.pbrt.meshes import MeshData


def _corner_array(collection, attribute: str, count: int, width: int) -> np.ndarray:
    values = np.empty(count * width, dtype=np.float32)
    collection.foreach_get(attribute, values)
    return values.reshape(count, width)


def evaluated_meshes(obj) -> dict[int, MeshData]:
    """Material slot index -> the triangles of that slot, of an evaluated object (one that has a mesh)."""
    mesh = obj.to_mesh()
    try:
        if mesh is None or len(mesh.polygons) == 0:
            return {}
        mesh.calc_loop_triangles()
        triangles = mesh.loop_triangles
        count = len(triangles)
        corners = np.empty(count * 3, dtype=np.int64)
        triangles.foreach_get("loops", corners)
        slots = np.empty(count, dtype=np.int64)
        triangles.foreach_get("material_index", slots)
        corner_vertex = np.empty(len(mesh.loops), dtype=np.int64)
        mesh.loops.foreach_get("vertex_index", corner_vertex)
        positions = _corner_array(mesh.vertices, "co", len(mesh.vertices), 3)
        normals = _corner_array(mesh.corner_normals, "vector", len(mesh.loops), 3)
        uv_layer = mesh.uv_layers.active
        uvs = _corner_array(uv_layer.uv, "vector", len(mesh.loops), 2) if uv_layer is not None else None
    finally:
        obj.to_mesh_clear()
    # one vertex per distinct (position index, normal, uv): np.unique over the rows' bytes
    columns = [corner_vertex[:, None].view(np.float64).astype(np.float64, copy=False), normals.astype(np.float64)]
    if uvs is not None:
        columns.append(uvs.astype(np.float64))
    rows = np.ascontiguousarray(np.concatenate(columns, axis=1))
    keys = rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    faces_all = inverse.ravel()[corners].reshape(count, 3)
    vertices_all = positions[corner_vertex[first]].astype(np.float64)
    normals_all = normals[first].astype(np.float64)
    uvs_all = uvs[first].astype(np.float64) if uvs is not None else None
    found: dict[int, MeshData] = {}
    for slot in np.unique(slots):
        faces = faces_all[slots == slot]
        used, local = np.unique(faces.ravel(), return_inverse=True)
        found[int(slot)] = MeshData(
            vertices=vertices_all[used],
            faces=local.reshape(-1, 3).astype(np.int64),
            normals=normals_all[used],
            uvs=uvs_all[used] if uvs_all is not None else None,
        )
    return found
