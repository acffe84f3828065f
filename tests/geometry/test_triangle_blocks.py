"""Leaf blocks of the wide BVHs (geometry/triangle_blocks.py): every leaf's triangles, four (eight) to a block, with
the vertices read back lane by lane equal to the per-triangle vertex array, and chains that cover each leaf
exactly."""

import numpy as np
import pytest

from spectrace.geometry.bvh import build_bvh
from spectrace.geometry.bvh4 import collapse
from spectrace.geometry.triangle_blocks import BLOCK_VECTORS, node_buffer, pack_leaf_blocks


def _leaf_order_vertices(triangles, bvh):
    ordered = triangles[bvh.prim_order].astype(np.float32)
    vertices = np.zeros((len(ordered), 3, 4), np.float32)
    vertices[..., :3] = ordered
    return vertices.reshape(-1, 4)


@pytest.mark.parametrize("width", [4, 8])
@pytest.mark.parametrize("count, max_leaf_size", [(1, 4), (37, 4), (2000, 4), (2000, 16), (2000, 20)])
def test_blocks_hold_every_leaf_triangle_once(count, max_leaf_size, width):
    rng = np.random.default_rng(count + max_leaf_size)
    triangles = rng.uniform(-1, 1, (count, 1, 3)) + rng.normal(0, 0.1, (count, 3, 3))
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2], max_leaf_size=max_leaf_size)
    vertices = _leaf_order_vertices(triangles, bvh)
    nodes4, _ = collapse(bvh, width)
    nodes, blocks = pack_leaf_blocks(nodes4, vertices, lanes=width)
    # Rows of one vector each: a node is 6 box vectors and 2 of ints; offsets are counted in float4s.
    buffer = node_buffer(nodes, blocks).reshape(-1, width)
    assert buffer.shape[0] == len(nodes) * 8 + len(blocks) * BLOCK_VECTORS
    per_float4 = width // 4

    seen = []
    leaf = nodes4["count"] > 0
    np.testing.assert_array_equal(nodes["child"][~leaf], nodes4["child"][~leaf])  # interior links unchanged
    for first, triangle_count, offset in zip(nodes4["child"][leaf], nodes4["count"][leaf], nodes["child"][leaf]):
        slots = []
        while True:
            assert offset % per_float4 == 0, "a block must start aligned for its vector loads"
            row = offset // per_float4
            block = buffer[row : row + BLOCK_VECTORS]
            block_first, lanes, more, _ = block[-1, :4].view(np.int32)
            for lane in range(lanes):
                corners = block[:9, lane].reshape(3, 3)  # (vertex, axis)
                np.testing.assert_array_equal(corners, vertices.reshape(-1, 3, 4)[block_first + lane, :, :3])
                slots.append(block_first + lane)
            assert np.all(block[:9, lanes:] == 0.0)
            if not more:
                break
            assert lanes == width, "only a leaf's last block may be partly filled"
            offset += BLOCK_VECTORS * per_float4
        assert slots == list(range(first, first + triangle_count))
        seen += slots
    assert sorted(seen) == list(range(count))
    if max_leaf_size > width:
        assert np.any(blocks[:, -1, :].view(np.int32)[:, 2] == 1), "some leaf must chain blocks"
