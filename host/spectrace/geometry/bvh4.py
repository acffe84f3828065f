"""Collapse of the binary SAH tree (spectrace.geometry.bvh) into a 4-wide tree for float4 box tests.

Each 4-wide node holds its children's boxes in SoA form, so one visit slab-tests four boxes with float4
arithmetic (Wald et al. 2008, "Getting rid of packets: efficient SIMD single-ray traversal using multi-branching
BVHs"; Dammertz et al. 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing"). A node is formed
from a binary interior node by repeatedly opening its largest-area interior child (replacing it with its two
children) until it has four children or only leaves remain, the greedy rule of the papers above. The collapse
works one level of 4-wide nodes at a time, with the same numpy calls for every node of the level.

Layout (mirrors `BVH4Node` in kernels/types.h): child_min[axis][k], child_max[axis][k] the box of child k;
child[k] a 4-wide node index when count[k] == 0, the first triangle slot of a leaf when count[k] > 0; an unused
slot has count[k] == -1 (and an empty box). Node 0 is the root; a binary tree that is a single leaf becomes a root
with that leaf as its only child. The leaf triangle slots are the binary tree's, so prim_order is unchanged.
"""

import numpy as np

from spectrace.geometry.bvh import BVH, MAX_DEPTH
from spectrace.geometry.triangle_blocks import LANES, node_buffer, pack_leaf_blocks

BVH4_NODE_DTYPE = np.dtype(
    {
        "names": ["child_min", "child_max", "child", "count"],
        "formats": [("<f4", (3, 4)), ("<f4", (3, 4)), ("<i4", (4,)), ("<i4", (4,))],
        "offsets": [0, 48, 96, 112],
        "itemsize": 128,
    }
)

WIDTH = 4


def collapse_to_bvh4(bvh: BVH) -> tuple[np.ndarray, int]:
    """(nodes, depth): the 4-wide tree over the same leaves as `bvh`, and its longest root-to-leaf path in edges."""
    binary = bvh.nodes
    is_leaf = binary["count"] > 0
    box_min = binary["bmin"].astype(np.float64)
    box_max = binary["bmax"].astype(np.float64)
    extent = np.maximum(box_max - box_min, 0.0)
    # Half the surface area: only its ranking matters, to pick which child to open.
    area = extent[:, 0] * extent[:, 1] + extent[:, 1] * extent[:, 2] + extent[:, 2] * extent[:, 0]

    if is_leaf[0]:
        level = np.array([[0, -1, -1, -1]], dtype=np.int64)
    else:
        level = _open_children(np.array([0]), binary, is_leaf, area)
    levels = []
    while level.shape[0] > 0:
        levels.append(level)
        inner = (level >= 0) & ~is_leaf[np.maximum(level, 0)]
        parents = level[inner]
        level = _open_children(parents, binary, is_leaf, area) if parents.size else np.empty((0, WIDTH), np.int64)

    node_count = sum(rows.shape[0] for rows in levels)
    nodes = np.zeros(node_count, dtype=BVH4_NODE_DTYPE)
    first = 0
    for rows in levels:
        count = rows.shape[0]
        used = rows >= 0
        source = np.maximum(rows, 0)
        leaf = used & is_leaf[source]
        inner = used & ~leaf
        # 4-wide nodes of the next level are numbered in the order their binary nodes appear here (row-major).
        next_index = first + count + np.cumsum(inner.ravel()).reshape(inner.shape) - 1
        block = nodes[first : first + count]
        block["child"] = np.where(leaf, binary["left_first"][source], np.where(inner, next_index, 0))
        block["count"] = np.where(leaf, binary["count"][source], np.where(inner, 0, -1))
        for axis in range(3):
            block["child_min"][:, axis, :] = np.where(used, binary["bmin"][source, axis], np.inf)
            block["child_max"][:, axis, :] = np.where(used, binary["bmax"][source, axis], -np.inf)
        first += count
    return nodes, len(levels)


def _open_children(parents: np.ndarray, binary: np.ndarray, is_leaf: np.ndarray, area: np.ndarray) -> np.ndarray:
    """(P, 4) binary node ids (-1 unused) of the children of the 4-wide nodes made from binary interior `parents`."""
    left = binary["left_first"][parents].astype(np.int64)
    children = np.full((parents.size, WIDTH), -1, dtype=np.int64)
    children[:, 0] = left
    children[:, 1] = left + 1
    rows = np.arange(parents.size)
    for used in (2, 3):
        safe = np.maximum(children, 0)
        openable = (children >= 0) & ~is_leaf[safe]
        score = np.where(openable, area[safe], -1.0)
        pick = np.argmax(score, axis=1)
        can = openable[rows, pick]
        opened = children[rows[can], pick[can]]
        first_child = binary["left_first"][opened].astype(np.int64)
        children[rows[can], pick[can]] = first_child
        children[rows[can], used] = first_child + 1
    return children


# Traversal the renders use: 4 (this module's nodes), or 2 (binary nodes, kernels/bvh.cl trace_bvh_binary).
# The 4-wide one traces 1.5-1.9x the closest-hit rays/s of the binary one on both CPU runtimes
# (docs/performance.md, "Traversal changes, measured").
TRAVERSAL_WIDTH = 4
# Largest leaf the SAH build may make for the 4-wide traversal: its leaves are tested four triangles at a time
# (geometry/triangle_blocks.py), so a leaf of 5-8 costs two block tests, not up to eight triangle tests. Against
# leaves of 4, measured in alternating runs on both CPU runtimes: the Cornell box 3-7 % more samples/s, closest-hit
# rays on 20,480 triangles 7-12 % more, on 1.3 M triangles within the runs' noise (docs/performance.md).
LEAF_SIZE = 8
# The SAH build prices a leaf by those blocks (build_bvh's leaf_block), so it prefers leaves that fill them: against
# pricing by triangles, measured in alternating runs on both CPU runtimes, the Cornell box and the living room
# rendered faster with the same image (docs/performance.md, "Block-aware SAH").
LEAF_BLOCK = LANES if TRAVERSAL_WIDTH == 4 else 1
# Entries of the 4-wide kernel's stack (kernels/bvh.cl BVH4_STACK_SIZE): a visit pushes at most three, and the
# collapse never makes a path longer than the binary tree's (<= MAX_DEPTH), so the stack cannot overflow.
BVH4_STACK_SIZE = 3 * MAX_DEPTH + 1


def device_nodes(bvh: BVH, triangle_vertices: np.ndarray, width: int | None = None) -> np.ndarray:
    """The node buffer the traversal of `width` (default TRAVERSAL_WIDTH) reads: the binary nodes, or the 4-wide
    nodes followed by their leaves' triangle blocks (geometry/triangle_blocks.py). triangle_vertices: (3·M, 4)
    float32 in leaf slot order, as uploaded for shading."""
    width = TRAVERSAL_WIDTH if width is None else width
    if width == 2:
        return bvh.nodes
    if width != WIDTH:
        raise ValueError(f"BVH traversal width must be 2 or 4, got {width}")
    nodes, depth = collapse_to_bvh4(bvh)
    if 3 * depth + 1 > BVH4_STACK_SIZE:
        raise RuntimeError(f"4-wide BVH depth {depth} exceeds what the traversal stack holds")  # unreachable
    return node_buffer(*pack_leaf_blocks(nodes, triangle_vertices))


def traversal_defines(width: int | None = None) -> dict[str, int]:
    """Kernel build defines selecting the traversal of `width` (none for the binary one)."""
    width = TRAVERSAL_WIDTH if width is None else width
    return {"BVH_WIDTH": 4} if width == WIDTH else {}
