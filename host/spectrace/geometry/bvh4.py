"""Collapse of the binary SAH tree (spectrace.geometry.bvh) into a 4- or 8-wide tree for float4 / float8 box tests.

Each wide node holds its children's boxes in SoA form, so one visit slab-tests four (eight) boxes with float4
(float8) arithmetic (Wald et al. 2008, "Getting rid of packets: efficient SIMD single-ray traversal using
multi-branching BVHs"; Dammertz et al. 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing"). A
node is formed from a binary interior node by repeatedly opening its largest-area interior child (replacing it with
its two children) until it has four (eight) children or only leaves remain, the greedy rule of the papers above.
The collapse works one level of wide nodes at a time, with the same numpy calls for every node of the level.

Layout (mirrors `BVH4Node` and `BVH8Node` in kernels/types.h): child_min[axis][k], child_max[axis][k] the box of
child k; child[k] a wide node index when count[k] == 0, the first triangle slot of a leaf when count[k] > 0; an unused
slot has count[k] == -1 (and an empty box). Node 0 is the root; a binary tree that is a single leaf becomes a root
with that leaf as its only child. The leaf triangle slots are the binary tree's, so prim_order is unchanged.
"""

import numpy as np

from spectrace.core.contract import BVH4_NODE_DTYPE, BVH8_NODE_DTYPE, BVH8_STACK_SIZE, MAX_DEPTH
from spectrace.geometry.bvh import BVH
from spectrace.geometry.triangle_blocks import LANES, node_buffer, pack_leaf_blocks

NODE_DTYPES = {4: BVH4_NODE_DTYPE, 8: BVH8_NODE_DTYPE}

# The 8-wide node with its children's boxes quantised to 8 bits per plane relative to the node's own box (Ylitie et
# al. 2017, "Efficient incoherent ray traversal on GPUs through compressed wide BVHs"): half the float node's bytes.
# q[0..2] the lower planes (x, y, z), q[3..5] the upper ones, of child k in lane k: the plane is origin[axis] +
# q * scale[axis] in float32, scale a power of two, so the kernel's dequantisation rounds once, exactly as here.
# kind[k]: -1 unused slot, 0 a wide node, 1 a leaf. Mirrors BVH8QNode in kernels/types.h.
BVH8Q_NODE_DTYPE = np.dtype(
    {
        "names": ["child", "q", "kind", "origin", "scale"],
        "formats": [("<i4", (8,)), ("u1", (6, 8)), ("i1", (8,)), ("<f4", (3,)), ("<f4", (3,))],
        "offsets": [0, 32, 80, 88, 100],
        "itemsize": 128,
    }
)


def collapse_to_bvh4(bvh: BVH) -> tuple[np.ndarray, int]:
    """(nodes, depth): the 4-wide tree over the same leaves as `bvh`, and its longest root-to-leaf path in edges."""
    return collapse(bvh, 4)


def collapse(bvh: BVH, width: int, stack_size: int | None = None) -> tuple[np.ndarray, int]:
    """(nodes, depth): the `width`-wide tree (4 or 8) over the same leaves as `bvh`, and its longest root-to-leaf
    path in edges.

    stack_size bounds the traversal stack. Every entry on the stack was pushed by an ancestor of the node being
    visited, and a visit pushes at most its node's (children - 1) (the kernel pushes all of them, then pops one), so
    the stack never holds more than 1 + the sum of (children - 1) over a root-to-node path. A node gets fewer
    children where that sum, plus one entry for each level its binary subtree could still add below it with two
    children a node, would pass stack_size; two children always fit while the binary tree's height stays below
    stack_size. Default: no bound for width 4 (its kernel's stack holds three entries a level), BVH8_STACK_SIZE for
    width 8."""
    if width not in NODE_DTYPES:
        raise ValueError(f"BVH width must be 4 or 8, got {width}")
    if stack_size is None:
        stack_size = BVH8_STACK_SIZE if width == 8 else (width - 1) * MAX_DEPTH + 1
    binary = bvh.nodes
    is_leaf = binary["count"] > 0
    height = _binary_heights(binary, is_leaf)
    if height[0] >= stack_size:
        raise ValueError(f"a binary BVH {height[0]} deep does not fit a {width}-wide stack of {stack_size}")
    box_min = binary["bmin"].astype(np.float64)
    box_max = binary["bmax"].astype(np.float64)
    extent = np.maximum(box_max - box_min, 0.0)
    # Half the surface area: only its ranking matters, to pick which child to open.
    area = extent[:, 0] * extent[:, 1] + extent[:, 1] * extent[:, 2] + extent[:, 2] * extent[:, 0]

    def open_level(parents: np.ndarray, pushed_above: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The children of the wide nodes made from `parents`, and the pushes on the path to each, its own included."""
        most = stack_size - pushed_above - height[parents] + 1
        children = _open_children(parents, binary, is_leaf, area, width, most)
        return children, pushed_above + (children >= 0).sum(axis=1) - 1

    if is_leaf[0]:
        level = np.full((1, width), -1, dtype=np.int64)
        level[0, 0] = 0
        pushed = np.zeros(1, np.int64)
    else:
        level, pushed = open_level(np.array([0]), np.zeros(1, np.int64))
    levels = []
    while level.shape[0] > 0:
        levels.append(level)
        inner = (level >= 0) & ~is_leaf[np.maximum(level, 0)]
        if not inner.any():
            break
        # Row-major, like the wide nodes of the next level: each inherits its parent's pushes.
        level, pushed = open_level(level[inner], np.broadcast_to(pushed[:, None], level.shape)[inner])

    dtype = NODE_DTYPES[width]
    node_count = sum(rows.shape[0] for rows in levels)
    nodes = np.zeros(node_count, dtype=dtype)
    first = 0
    for rows in levels:
        count = rows.shape[0]
        used = rows >= 0
        source = np.maximum(rows, 0)
        leaf = used & is_leaf[source]
        inner = used & ~leaf
        # Wide nodes of the next level are numbered in the order their binary nodes appear here (row-major).
        next_index = first + count + np.cumsum(inner.ravel()).reshape(inner.shape) - 1
        block = nodes[first : first + count]
        block["child"] = np.where(leaf, binary["left_first"][source], np.where(inner, next_index, 0))
        block["count"] = np.where(leaf, binary["count"][source], np.where(inner, 0, -1))
        for axis in range(3):
            block["child_min"][:, axis, :] = np.where(used, binary["bmin"][source, axis], np.inf)
            block["child_max"][:, axis, :] = np.where(used, binary["bmax"][source, axis], -np.inf)
        first += count
    return nodes, len(levels)


def _binary_heights(binary: np.ndarray, is_leaf: np.ndarray) -> np.ndarray:
    """Edges from each binary node down to its deepest leaf: the levels found from the root down, then the heights
    from the deepest level up, one numpy step per level."""
    levels = [np.array([0])]
    while True:
        inner = levels[-1][~is_leaf[levels[-1]]]
        if not inner.size:
            break
        left = binary["left_first"][inner].astype(np.int64)
        levels.append(np.concatenate([left, left + 1]))
    height = np.zeros(len(binary), np.int64)
    for nodes in levels[-2::-1]:
        inner = nodes[~is_leaf[nodes]]
        left = binary["left_first"][inner].astype(np.int64)
        height[inner] = 1 + np.maximum(height[left], height[left + 1])
    return height


def _open_children(
    parents: np.ndarray, binary: np.ndarray, is_leaf: np.ndarray, area: np.ndarray, width: int, most: np.ndarray
) -> np.ndarray:
    """(P, width) binary node ids (-1 unused) of the children of the wide nodes made from binary interior `parents`,
    at most `most` (P,) children each (and at least two)."""
    left = binary["left_first"][parents].astype(np.int64)
    children = np.full((parents.size, width), -1, dtype=np.int64)
    children[:, 0] = left
    children[:, 1] = left + 1
    rows = np.arange(parents.size)
    for used in range(2, width):
        safe = np.maximum(children, 0)
        openable = (children >= 0) & ~is_leaf[safe]
        score = np.where(openable, area[safe], -1.0)
        pick = np.argmax(score, axis=1)
        can = openable[rows, pick] & (used < most)
        opened = children[rows[can], pick[can]]
        first_child = binary["left_first"][opened].astype(np.int64)
        children[rows[can], pick[can]] = first_child
        children[rows[can], used] = first_child + 1
    return children


# Traversal the renders use: 8 (float8 nodes and eight-triangle leaf blocks), 4 (float4 ones), or 2 (binary nodes,
# kernels/bvh.cl trace_bvh_binary). The 4-wide one traces 1.5-1.9x the closest-hit rays/s of the binary one on both
# CPU runtimes, the 8-wide one more again (docs/performance.md, "Traversal changes, measured").
TRAVERSAL_WIDTH = 8
# Largest leaf the SAH build may make for the wide traversals: their leaves are tested four (eight) triangles at a
# time (geometry/triangle_blocks.py), so a leaf of 5-8 costs one or two block tests, not up to eight triangle tests.
# Against leaves of 4, measured in alternating runs on both CPU runtimes with the 4-wide traversal: the Cornell box
# 3-7 % more samples/s, closest-hit rays on 20,480 triangles 7-12 % more, on 1.3 M triangles within the runs' noise
# (docs/performance.md).
LEAF_SIZE = 8
# The SAH build prices a leaf by blocks of four (build_bvh's leaf_block), so it prefers leaves that fill them: against
# pricing by triangles, measured in alternating runs on both CPU runtimes, the Cornell box and the living room
# rendered faster with the same image (docs/performance.md, "Block-aware SAH"). The 8-wide traversal keeps the same
# binary tree, so both wide traversals visit the same leaves and give the same hits.
LEAF_BLOCK = LANES if TRAVERSAL_WIDTH in (4, 8) else 1


# Whether the 8-wide traversal reads quantised nodes (BVH8Q_NODE_DTYPE) rather than float ones. Off: measured in
# alternating runs on both CPU runtimes it did not win on both (docs/performance.md, "Quantised 8-wide nodes").
QUANTISED_NODES = False


def quantise_nodes(nodes: np.ndarray) -> np.ndarray:
    """The 8-wide float nodes (BVH8_NODE_DTYPE, leaf children already pointing at their blocks) as quantised nodes:
    each child box rounded outwards, lower planes down and upper planes up, so the box the kernel dequantises
    contains the float box and the traversal visits every child the float one visits."""
    used = nodes["count"] >= 0  # (N, 8)
    box_min = nodes["child_min"].astype(np.float32)  # (N, 3, 8)
    box_max = nodes["child_max"].astype(np.float32)
    lo = np.where(used[:, None, :], box_min, np.inf).min(axis=2)  # (N, 3): the node's own box
    hi = np.where(used[:, None, :], box_max, -np.inf).max(axis=2)
    origin = lo.astype(np.float32)
    # The smallest power of two whose 255 steps reach past the node's upper plane in float32 (checked below), and
    # no smaller than 2^-126, so the scale is never a denormal a device might flush to zero.
    extent = np.maximum(hi.astype(np.float64) - origin, 0.0)
    exponent = np.maximum(np.ceil(np.log2(np.maximum(extent, 1e-300) / 255.0)), -126.0)
    for _ in range(4):
        reach = origin + np.float32(255.0) * np.exp2(exponent).astype(np.float32)
        short = reach < hi
        if not short.any():
            break
        exponent = exponent + short
    scale = np.exp2(exponent).astype(np.float32)  # (N, 3)

    def plane(q: np.ndarray) -> np.ndarray:
        """What the kernel computes for quantised planes q (N, 3, 8): one float32 product (exact) and sum."""
        return origin[:, :, None] + q.astype(np.float32) * scale[:, :, None]

    with np.errstate(invalid="ignore", over="ignore"):
        offset_min = (box_min.astype(np.float64) - origin[:, :, None]) / scale[:, :, None]
        offset_max = (box_max.astype(np.float64) - origin[:, :, None]) / scale[:, :, None]
    q_lo = np.clip(np.floor(np.where(used[:, None, :], offset_min, 0.0)), 0, 255)
    q_hi = np.clip(np.ceil(np.where(used[:, None, :], offset_max, 0.0)), 0, 255)
    for _ in range(4):  # the float64 quotients can round to the wrong side of a plane: step outwards until not
        low_over = used[:, None, :] & (plane(q_lo) > box_min)
        high_under = used[:, None, :] & (plane(q_hi) < box_max)
        q_lo = np.where(low_over, np.maximum(q_lo - 1, 0), q_lo)
        q_hi = np.where(high_under, np.minimum(q_hi + 1, 255), q_hi)
    contains = ~used[:, None, :] | ((plane(q_lo) <= box_min) & (plane(q_hi) >= box_max))
    if not contains.all():
        raise ValueError("a quantised BVH box does not contain its child's box")
    out = np.zeros(len(nodes), dtype=BVH8Q_NODE_DTYPE)
    out["child"] = nodes["child"]
    out["q"][:, :3, :] = q_lo.astype(np.uint8)
    out["q"][:, 3:, :] = q_hi.astype(np.uint8)
    out["kind"] = np.where(used, np.where(nodes["count"] > 0, 1, 0), -1)
    out["origin"] = origin
    out["scale"] = scale
    return out


def device_nodes(
    bvh: BVH, triangle_vertices: np.ndarray, width: int | None = None, quantised: bool | None = None
) -> np.ndarray:
    """The node buffer the traversal of `width` (default TRAVERSAL_WIDTH) reads: the binary nodes, or the wide
    nodes followed by their leaves' triangle blocks of `width` lanes (geometry/triangle_blocks.py); 8-wide nodes
    quantised when `quantised` (default QUANTISED_NODES). triangle_vertices: (3·M, 4) float32 in leaf slot order,
    as uploaded for shading."""
    width = TRAVERSAL_WIDTH if width is None else width
    if width == 2:
        return bvh.nodes
    if width not in NODE_DTYPES:
        raise ValueError(f"BVH traversal width must be 2, 4 or 8, got {width}")
    nodes, _ = collapse(bvh, width)
    nodes, blocks = pack_leaf_blocks(nodes, triangle_vertices, lanes=width)
    if width == 8 and (QUANTISED_NODES if quantised is None else quantised):
        # The blocks follow the smaller nodes: every leaf offset moves down by the bytes saved (in float4s).
        shift = len(nodes) * (BVH8_NODE_DTYPE.itemsize - BVH8Q_NODE_DTYPE.itemsize) // 16
        nodes["child"] = np.where(nodes["count"] > 0, nodes["child"] - shift, nodes["child"])
        return node_buffer(quantise_nodes(nodes), blocks)
    return node_buffer(nodes, blocks)


def traversal_defines(width: int | None = None, quantised: bool | None = None) -> dict[str, int]:
    """Kernel build defines selecting the traversal of `width` (none for the binary one), with quantised 8-wide
    nodes when `quantised` (default QUANTISED_NODES)."""
    width = TRAVERSAL_WIDTH if width is None else width
    if width not in NODE_DTYPES:
        return {}
    if width == 8 and (QUANTISED_NODES if quantised is None else quantised):
        return {"BVH_WIDTH": 8, "BVH8_QUANTISED": 1}
    return {"BVH_WIDTH": width}
