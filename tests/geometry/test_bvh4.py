"""The 4- and 8-wide collapses of the binary BVH: same leaves, boxes that bound their subtrees, a tree (not a DAG),
and a traversal stack that the 8-wide kernel's cannot overflow."""

import numpy as np
import pytest

from spectrace.geometry.bvh import MAX_DEPTH, build_bvh
from spectrace.geometry.bvh4 import BVH8_STACK_SIZE, collapse, collapse_to_bvh4


def _soup(seed, count):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1, 1, (count, 1, 3))
    return centres + rng.normal(0, 0.05, (count, 3, 3))


@pytest.mark.parametrize("width", [4, 8])
@pytest.mark.parametrize("count", [1, 2, 5, 37, 2000])
def test_collapse_keeps_every_leaf_and_bounds_every_subtree(count, width):
    triangles = _soup(count, count)
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2])
    nodes, depth = collapse(bvh, width)
    assert 1 <= depth <= max(bvh.depth, 1)

    child, counts = nodes["child"], nodes["count"]
    low, high = nodes["child_min"], nodes["child_max"]  # (K, 3, 4)
    # Every non-root node is the child of exactly one slot: the collapse makes a tree.
    referenced = np.sort(child[counts == 0])
    np.testing.assert_array_equal(referenced, np.arange(1, len(nodes)))
    # The leaves cover every triangle slot once, with the binary tree's leaf ranges.
    leaf_first, leaf_count = child[counts > 0], counts[counts > 0]
    slots = np.concatenate([np.arange(f, f + c) for f, c in zip(leaf_first, leaf_count)])
    np.testing.assert_array_equal(np.sort(slots), np.arange(count))
    binary_leaves = bvh.nodes[bvh.nodes["count"] > 0]
    assert sorted(zip(leaf_first, leaf_count)) == sorted(zip(binary_leaves["left_first"], binary_leaves["count"]))
    # A leaf's box holds its triangles' vertices; an inner child's box holds every box of its own children.
    vertices = triangles[bvh.prim_order]
    for node, slot in zip(*np.nonzero(counts > 0)):
        held = vertices[child[node, slot] : child[node, slot] + counts[node, slot]].reshape(-1, 3)
        assert np.all(held >= low[node, :, slot]) and np.all(held <= high[node, :, slot])
    for node, slot in zip(*np.nonzero(counts == 0)):
        inner = child[node, slot]
        used = counts[inner] >= 0
        assert used.any()
        assert np.all(low[inner][:, used] >= low[node, :, slot, None])
        assert np.all(high[inner][:, used] <= high[node, :, slot, None])
    # Unused slots are empty boxes, and used ones come first.
    unused = counts < 0
    assert np.all(low.transpose(0, 2, 1)[unused] > high.transpose(0, 2, 1)[unused])
    assert np.all(np.diff(unused.astype(int), axis=1) >= 0)


def test_interior_nodes_fill_their_four_slots_while_they_can():
    """A balanced tree of 64 well separated triangles, one per leaf, collapses to full nodes of four."""
    grid = np.stack(np.meshgrid(*[np.arange(4.0)] * 3, indexing="ij"), -1).reshape(-1, 1, 3) * 10.0
    small = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]])
    triangles = grid + small
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2], max_leaf_size=1)
    nodes, depth = collapse_to_bvh4(bvh)
    assert np.all(nodes["count"] >= 0)
    assert depth == 3 and len(nodes) == 1 + 4 + 16


def _largest_stack(nodes):
    """Most entries a traversal can hold: at a node, the (children - 1) its ancestors and itself pushed, plus one
    for the kernel's push of every hit child before it pops the nearest."""
    used = (nodes["count"] >= 0).sum(axis=1)
    pending = np.zeros(len(nodes), np.int64)
    pending[0] = used[0] - 1
    for node in range(len(nodes)):  # parents come before their children in the level order
        inner = nodes["count"][node] == 0
        pending[nodes["child"][node][inner]] = pending[node] + used[nodes["child"][node][inner]] - 1
    return int(pending.max()) + 1


def test_eight_wide_stack_bound_holds_on_a_deep_tree():
    """A chain of ever smaller boxes makes the binary tree deep; the 8-wide collapse must keep the stack within
    BVH8_STACK_SIZE there, and with a small stack give nodes fewer children rather than overflow it."""
    sizes = 0.5 ** np.arange(120)
    triangles = np.stack([np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) * s + s for s in sizes])
    triangles = np.concatenate([triangles, _soup(3, 3000)])
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2], max_leaf_size=1)
    assert bvh.depth > 30, "the case must be deep"
    nodes, depth = collapse(bvh, 8)
    assert depth <= MAX_DEPTH and _largest_stack(nodes) <= BVH8_STACK_SIZE
    unbounded, _ = collapse(bvh, 8, stack_size=8 * MAX_DEPTH)
    small = bvh.depth + 4
    tight, _ = collapse(bvh, 8, stack_size=small)
    assert _largest_stack(tight) <= small < _largest_stack(unbounded)
    # Where the stack allows it, nodes keep their full width: the same tree as with no bound.
    wide, _ = collapse(bvh, 8, stack_size=_largest_stack(unbounded) + bvh.depth)
    np.testing.assert_array_equal(wide["child"], unbounded["child"])


@pytest.mark.parametrize("offset", [0.0, 1000.0])
def test_quantised_boxes_contain_the_float_boxes_and_stay_within_a_step(offset):
    """Each dequantised child box (origin + q·scale in float32, as the kernel computes it) contains its float box,
    and lies no more than one step (plus the origin's rounding) outside it; a step is at most 2/255 of the node's
    extent. A far offset makes the float32 sums round, and a flat scene gives zero extents."""
    from spectrace.geometry.bvh4 import quantise_nodes

    triangles = _soup(7, 800) + offset
    flat = _soup(8, 200)
    flat[..., 2] = 0.5
    for soup in (triangles, flat):
        bvh = build_bvh(soup[:, 0], soup[:, 1], soup[:, 2])
        nodes, _ = collapse(bvh, 8)
        quantised = quantise_nodes(nodes)
        used = nodes["count"] >= 0
        np.testing.assert_array_equal(quantised["kind"], np.where(used, np.where(nodes["count"] > 0, 1, 0), -1))
        np.testing.assert_array_equal(quantised["child"], nodes["child"])
        origin = quantised["origin"][:, :, None].astype(np.float32)
        scale = quantised["scale"][:, :, None].astype(np.float32)
        assert np.all(np.log2(scale) == np.round(np.log2(scale))), "scales are powers of two"
        low = origin + quantised["q"][:, :3, :].astype(np.float32) * scale
        high = origin + quantised["q"][:, 3:, :].astype(np.float32) * scale
        box_min, box_max = nodes["child_min"], nodes["child_max"]
        inside = ~used[:, None, :] | ((low <= box_min) & (high >= box_max))
        assert inside.all()
        real_min = np.where(used[:, None, :], box_min, np.inf).min(axis=2)
        real_max = np.where(used[:, None, :], box_max, -np.inf).max(axis=2)
        ulp = np.spacing(np.maximum(np.abs(real_min), np.abs(real_max)).astype(np.float32))
        extent = (real_max - real_min).astype(np.float64)
        assert np.all(scale[:, :, 0] <= np.maximum(2 * extent / 255, 2.0**-126) + 2 * ulp)
        slack = (scale + 2 * ulp[:, :, None])[:, :, :] * np.ones_like(low)
        assert np.all(~used[:, None, :] | (box_min - low <= slack))
        assert np.all(~used[:, None, :] | (high - box_max <= slack))
