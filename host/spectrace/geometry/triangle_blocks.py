"""Leaf triangles of the wide BVHs packed four (eight) to a block, so the kernel tests them with float4 (float8)
arithmetic.

A leaf's triangles are tested one after the other in the binary traversal; in the 4-wide (8-wide) one they are
tested four (eight) at a time, each lane one triangle (Wald et al. 2008 pack leaves the same way, for the same
reason), which measured cheaper than the scalar loop on both CPU runtimes here (docs/performance.md, "Current
figures").

Block layout for L lanes (4 or 8; 10 vectors of L floats, read by kernels/triangle_blocks.cl): vector
`3 * vertex + axis` holds that coordinate of the triangle's vertex 0, 1 or 2 in lanes 0..L-1, one triangle per lane;
the last vector starts with four ints (first triangle slot, triangles in this block, 1 when another block of the
same leaf follows, 0), zeros after them. A leaf of n triangles takes ceil(n / L) consecutive blocks; unused lanes
hold zeros and are masked by the count. The leaf's triangles are the binary tree's slots, so prim_order and every
per-triangle array are unchanged.
"""

import numpy as np

LANES = 4
BLOCK_VECTORS = 10  # a block of L lanes is this many vectors of L floats


def pack_leaf_blocks(
    nodes4: np.ndarray, triangle_vertices: np.ndarray, lanes: int = LANES
) -> tuple[np.ndarray, np.ndarray]:
    """(nodes, blocks): a copy of the wide nodes whose leaf children point at their first block (child[k] = the
    block's float4 offset from the start of the node buffer, which holds the nodes, then the blocks), and the
    (B, BLOCK_VECTORS, lanes) float32 blocks. triangle_vertices: (3·M, 4) float32 in leaf slot order. The nodes'
    and blocks' sizes are multiples of `lanes` floats, so every block starts aligned for its vector loads."""
    nodes = nodes4.copy()
    vertices = np.asarray(triangle_vertices, np.float32).reshape(-1, 3, 4)[:, :, :3]  # (M, vertex, axis)
    node_index, slot = np.nonzero(nodes["count"] > 0)
    first = nodes["child"][node_index, slot].astype(np.int64)
    count = nodes["count"][node_index, slot].astype(np.int64)
    blocks_per_leaf = -(-count // lanes)
    block_count = int(blocks_per_leaf.sum())
    leaf_first_block = np.cumsum(blocks_per_leaf) - blocks_per_leaf

    # Every block: the leaf it belongs to and its position within that leaf.
    leaf_of_block = np.repeat(np.arange(len(first)), blocks_per_leaf)
    position = np.arange(block_count) - leaf_first_block[leaf_of_block]
    block_first = first[leaf_of_block] + lanes * position
    block_lanes = np.minimum(count[leaf_of_block] - lanes * position, lanes)
    more = (position + 1 < blocks_per_leaf[leaf_of_block]).astype(np.int32)

    lane = np.arange(lanes)
    used = lane[None, :] < block_lanes[:, None]  # (B, lane)
    coordinates = vertices[np.where(used, block_first[:, None] + lane[None, :], 0)]  # (B, lane, vertex, axis)
    coordinates[~used] = 0.0  # the few unused lanes, in place: no second array of every block's corners
    blocks = np.zeros((block_count, BLOCK_VECTORS, lanes), np.float32)
    # Written through a (B, vertex, axis, lane) view of the first nine vectors: one strided copy, no temporary.
    blocks[:, :9, :].reshape(block_count, 3, 3, lanes)[...] = coordinates.transpose(0, 2, 3, 1)
    meta = np.stack([block_first, block_lanes, more, np.zeros_like(more)], axis=1).astype(np.int32)
    blocks[:, 9, :4] = meta.view(np.float32)

    node_float4s = nodes.dtype.itemsize // 16
    offset = len(nodes) * node_float4s + (BLOCK_VECTORS * lanes // 4) * leaf_first_block
    if len(offset) and offset.max() > np.iinfo(np.int32).max:
        raise ValueError("BVH too large for 32-bit leaf block offsets")
    nodes["child"][node_index, slot] = offset
    return nodes, blocks


def node_buffer(nodes: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """The device buffer: the nodes' bytes followed by the blocks', as one float32 array."""
    return np.concatenate([nodes.view(np.float32).reshape(-1), blocks.reshape(-1)])
