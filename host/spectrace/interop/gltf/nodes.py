"""The node hierarchy (glTF 2.0, 3.5): each node's local transform, a `matrix` or translation-rotation-scale
(T · R · S, the quaternion as x, y, z, w), and the world transform of every node the chosen scene reaches, parent
before child. The units are the file's (metres) and its axes (+y up, a camera and a light looking along −z)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spectrace.interop.gltf.document import GltfDocument


@dataclass
class PlacedNode:
    index: int
    world: np.ndarray  # 4 x 4, acting on column vectors
    node: dict

    @property
    def pointer(self) -> str:
        return f"/nodes/{self.index}"


def quaternion_matrix(q: list[float]) -> np.ndarray:
    """The rotation of a unit quaternion (x, y, z, w); glTF asks for unit quaternions, normalised here against
    rounding in the file."""
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def local_matrix(doc: GltfDocument, node: dict, pointer: str) -> np.ndarray:
    if "matrix" in node:
        values = doc.numbers(node, "matrix", pointer, 16, [])
        return np.array(values, dtype=np.float64).reshape(4, 4).T  # stored column by column
    translation = doc.numbers(node, "translation", pointer, 3, [0.0, 0.0, 0.0])
    rotation = doc.numbers(node, "rotation", pointer, 4, [0.0, 0.0, 0.0, 1.0])
    scale = doc.numbers(node, "scale", pointer, 3, [1.0, 1.0, 1.0])
    if np.linalg.norm(rotation) == 0.0:
        raise doc.fail(f"{pointer}/rotation", "a zero quaternion is no rotation")
    matrix = np.eye(4)
    matrix[:3, :3] = quaternion_matrix(rotation) * np.asarray(scale)
    matrix[:3, 3] = translation
    return matrix


def scene_roots(doc: GltfDocument) -> tuple[list[int], str]:
    """The root nodes of the scene to import: `scene`, else the first of `scenes`, else every node no node
    names as a child (a file without scenes: glTF leaves it to the application)."""
    scenes = doc.array("scenes")
    chosen = doc.index(doc.json, "scene", "")
    if chosen is not None or scenes:
        index = chosen or 0
        scene = doc.item("scenes", index, "/scene" if chosen is not None else "/scenes")
        roots = scene.get("nodes", [])
        if not isinstance(roots, list):
            raise doc.fail(f"/scenes/{index}/nodes", "must be an array of node indices")
        return roots, f"/scenes/{index}/nodes"
    children = {c for node in doc.array("nodes") if isinstance(node, dict) for c in node.get("children", [])}
    return [i for i in range(len(doc.array("nodes"))) if i not in children], "/nodes"


def placed_nodes(doc: GltfDocument) -> list[PlacedNode]:
    """Every node the scene reaches with its world transform, depth first in the file's order. A node reached
    twice (a child of two parents, or of itself) is refused: glTF's nodes form disjoint trees."""
    roots, roots_pointer = scene_roots(doc)
    placed: list[PlacedNode] = []
    seen: set[int] = set()
    pending = [(index, np.eye(4), f"{roots_pointer}/{i}") for i, index in reversed(list(enumerate(roots)))]
    while pending:
        index, parent, pointer = pending.pop()
        node = doc.item("nodes", index, pointer)
        if index in seen:
            raise doc.fail(pointer, f"node {index} is reached twice (the nodes must form trees, without cycles)")
        seen.add(index)
        where = f"/nodes/{index}"
        world = parent @ local_matrix(doc, node, where)
        placed.append(PlacedNode(index, world, node))
        children = node.get("children", [])
        if not isinstance(children, list):
            raise doc.fail(f"{where}/children", "must be an array of node indices")
        pending += [(child, world, f"{where}/children/{i}") for i, child in reversed(list(enumerate(children)))]
    return placed
