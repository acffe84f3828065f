"""The importer against trimesh's own glTF reader and writer, an implementation written apart from it: the world
triangles of a node hierarchy (TRS and matrices, a mesh placed three times) are the triangles trimesh's scene
places, and a file trimesh writes (its own buffer layout, a PBR material with a texture) imports with its
material's values."""

from __future__ import annotations

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf

from spectrace.interop.gltf import gltf_scene_data

trimesh = pytest.importorskip("trimesh")


def _triangles(vertices: np.ndarray, faces: np.ndarray, world: np.ndarray) -> np.ndarray:
    points = vertices @ world[:3, :3].T + world[:3, 3]
    return points[faces]


def _canonical(triangles: np.ndarray) -> np.ndarray:
    """Triangles as a sorted array of their rounded corners, each triangle's corners rotated to start at the
    smallest: the same set whatever order two readers list them in."""
    rounded = np.round(triangles, 6)
    keys = [tuple(map(tuple, t)) for t in rounded]
    canonical = []
    for corners in keys:
        start = corners.index(min(corners))
        canonical.append(corners[start:] + corners[:start])
    return np.array(sorted(canonical))


def test_world_triangles_match_trimesh(tmp_path):
    rng = np.random.default_rng(7)
    gltf = Gltf()
    positions = rng.normal(size=(6, 3))
    mesh = gltf.mesh(positions, [0, 1, 2, 2, 3, 4, 4, 5, 0])
    other = gltf.mesh(rng.normal(size=(3, 3)))
    quaternion = rng.normal(size=4)
    quaternion /= np.linalg.norm(quaternion)
    matrix = np.eye(4)
    matrix[:3, :3] = rng.normal(size=(3, 3))
    matrix[:3, 3] = rng.normal(size=3)
    leaf = gltf.node(root=False, mesh=mesh, translation=[1, 2, 3], scale=[1, -2, 0.5])
    middle = gltf.node(root=False, mesh=other, rotation=quaternion.tolist(), children=[leaf])
    gltf.node(matrix=matrix.T.reshape(-1).tolist(), children=[middle])
    gltf.node(mesh=mesh, translation=[-4, 0, 0])
    gltf.node(mesh=mesh, rotation=[0, 0, 0.6, 0.8])
    path = gltf.write(tmp_path / "tree.glb")

    data, ctx = gltf_scene_data(path, tmp_path / "tree.toml")
    ours = []
    for shape in data.get("shapes", []):
        mesh_data = ctx.meshes[shape["file"]]
        world = np.array(shape["transform"][0]["matrix"]) if "transform" in shape else np.eye(4)
        ours.append(_triangles(mesh_data.vertices, mesh_data.faces, world))
    for instance in data.get("instances", []):
        world = np.array(instance["transform"][0]["matrix"]) if "transform" in instance else np.eye(4)
        for shape in data["objects"][instance["object"]]["shapes"]:
            mesh_data = ctx.meshes[shape["file"]]
            ours.append(_triangles(mesh_data.vertices, mesh_data.faces, world))
    assert len(data["instances"]) == 3, "the mesh placed by three nodes is one object"

    scene = trimesh.load(path, force="scene", process=False)
    theirs = []
    for node in scene.graph.nodes_geometry:
        world, name = scene.graph[node]
        geometry = scene.geometry[name]
        theirs.append(_triangles(np.asarray(geometry.vertices), np.asarray(geometry.faces), world))
    ours_all, theirs_all = np.concatenate(ours), np.concatenate(theirs)
    assert ours_all.shape == theirs_all.shape
    np.testing.assert_allclose(_canonical(ours_all), _canonical(theirs_all), atol=2e-6)


def test_a_file_trimesh_writes_imports_with_its_material(tmp_path):
    from PIL import Image

    box = trimesh.creation.box(extents=[1, 2, 3])
    uv = np.random.default_rng(1).random((len(box.vertices), 2))
    image = Image.fromarray(np.full((4, 4, 3), [200, 100, 50], np.uint8))
    material = trimesh.visual.material.PBRMaterial(
        baseColorTexture=image, metallicFactor=0.3, roughnessFactor=0.6, doubleSided=True
    )
    box.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    path = tmp_path / "box.glb"
    path.write_bytes(trimesh.Scene(box).export(file_type="glb"))

    data, ctx = gltf_scene_data(path, tmp_path / "box.toml")
    ((name, table),) = data["materials"].items()
    assert table["metallic"] == pytest.approx(0.3) and table["roughness"] == pytest.approx(0.6)
    assert table["base_color"]["texture"] == "bitmap" and "two_sided" not in table
    (shape,) = data["shapes"]
    mesh = ctx.meshes[shape["file"]]
    assert shape["material"] == name and len(mesh.faces) == 12
    np.testing.assert_allclose(np.ptp(mesh.vertices, axis=0), [1, 2, 3], atol=1e-6)
    # trimesh writes v up the image flipped to glTF's v down; the PLY stores 1 − v: trimesh's own uv back
    order = np.lexsort(mesh.vertices.T)
    reference = np.lexsort(box.vertices.T)
    np.testing.assert_allclose(mesh.uvs[order], uv[reference], atol=1e-6)
