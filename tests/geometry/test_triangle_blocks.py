"""Leaf blocks of the 4-wide BVH (geometry/triangle_blocks.py): every leaf's triangles, four to a block, with the
vertices read back lane by lane equal to the per-triangle vertex array, and chains that cover each leaf exactly."""

import numpy as np
import pytest

from spectrace.geometry.bvh import build_bvh
from spectrace.geometry.bvh4 import collapse_to_bvh4
from spectrace.geometry.triangle_blocks import LEAF_BLOCK_FLOAT4S, node_buffer, pack_leaf_blocks


def _leaf_order_vertices(triangles, bvh):
    ordered = triangles[bvh.prim_order].astype(np.float32)
    vertices = np.zeros((len(ordered), 3, 4), np.float32)
    vertices[..., :3] = ordered
    return vertices.reshape(-1, 4)


@pytest.mark.parametrize("count, max_leaf_size", [(1, 4), (37, 4), (2000, 4), (2000, 16)])
def test_blocks_hold_every_leaf_triangle_once(count, max_leaf_size):
    rng = np.random.default_rng(count + max_leaf_size)
    triangles = rng.uniform(-1, 1, (count, 1, 3)) + rng.normal(0, 0.1, (count, 3, 3))
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2], max_leaf_size=max_leaf_size)
    vertices = _leaf_order_vertices(triangles, bvh)
    nodes4, _ = collapse_to_bvh4(bvh)
    nodes, blocks = pack_leaf_blocks(nodes4, vertices)
    buffer = node_buffer(nodes, blocks).reshape(-1, 4)
    assert buffer.shape[0] == len(nodes) * 8 + len(blocks) * LEAF_BLOCK_FLOAT4S

    seen = []
    leaf = nodes4["count"] > 0
    np.testing.assert_array_equal(nodes["child"][~leaf], nodes4["child"][~leaf])  # interior links unchanged
    for first, triangle_count, offset in zip(nodes4["child"][leaf], nodes4["count"][leaf], nodes["child"][leaf]):
        slots = []
        while True:
            block = buffer[offset : offset + LEAF_BLOCK_FLOAT4S]
            block_first, lanes, more, _ = block[-1].view(np.int32)
            for lane in range(lanes):
                corners = block[:9, lane].reshape(3, 3)  # (vertex, axis)
                np.testing.assert_array_equal(corners, vertices.reshape(-1, 3, 4)[block_first + lane, :, :3])
                slots.append(block_first + lane)
            assert np.all(block[:9, lanes:] == 0.0)
            if not more:
                break
            assert lanes == 4, "only a leaf's last block may be partly filled"
            offset += LEAF_BLOCK_FLOAT4S
        assert slots == list(range(first, first + triangle_count))
        seen += slots
    assert sorted(seen) == list(range(count))
    if max_leaf_size > 4:
        assert np.any(blocks[:, -1, :].view(np.int32)[:, 2] == 1), "some leaf must chain blocks"
