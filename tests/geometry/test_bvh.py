"""The binned-SAH BVH builder: tree structure, conservative float32 bounds, closest hits equal to a brute force
over every triangle, and a lower SAH cost than a naive median split."""

import numpy as np
import pytest
import trimesh

from raytracing_reference import brute_force_closest_hit
from spectrace.geometry import bvh as bvh_module
from spectrace.geometry.bvh import BVH_NODE_DTYPE, build_bvh, sah_cost

KERNEL_STACK_DEPTH = 64
HARD_LEAF_CAP = 16


def _soup(rng, count, spread=10.0, size=0.3):
    centres = rng.uniform(0.0, spread, (count, 1, 3))
    return centres + rng.normal(0.0, size, (count, 3, 3))


def _corners(triangles):
    return triangles[:, 0], triangles[:, 1], triangles[:, 2]


def _bumpy_sphere_and_torus(rng):
    sphere = trimesh.creation.icosphere(subdivisions=3)
    bumps = 1.0 + 0.05 * rng.standard_normal((len(sphere.vertices), 1))
    torus = trimesh.creation.torus(major_radius=1.6, minor_radius=0.3)
    return np.concatenate([(sphere.vertices * bumps)[sphere.faces], torus.vertices[torus.faces]])


# ---------------------------------------------------------------------------------------------------------------
# Independent checks of the tree


def _walk_levels(nodes):
    """Breadth-first walk from the root: list of node-index arrays per depth; fails on shared or stray children."""
    levels = [np.array([0])]
    visits = np.zeros(len(nodes), dtype=np.int64)
    visits[0] = 1
    while True:
        interior = levels[-1][nodes["count"][levels[-1]] == 0]
        if interior.size == 0:
            break
        assert len(levels) <= KERNEL_STACK_DEPTH + 1, "tree deeper than the kernel's traversal stack"
        first = nodes["left_first"][interior].astype(np.int64)
        assert np.all(first >= 1) and np.all(first + 1 < len(nodes)), "child index out of range"
        children = np.concatenate([first, first + 1])
        np.add.at(visits, children, 1)
        levels.append(children)
    assert np.all(visits == 1), "every node must be reached exactly once from the root"
    return levels


def assert_valid_bvh(bvh, triangles, leaf_cap=HARD_LEAF_CAP):
    nodes, order = bvh.nodes, bvh.prim_order
    triangle_count = len(triangles)
    assert nodes.dtype == BVH_NODE_DTYPE
    assert order.dtype == np.int32 and order.shape == (triangle_count,)

    levels = _walk_levels(nodes)
    assert bvh.depth == len(levels) - 1 <= KERNEL_STACK_DEPTH

    leaves = np.flatnonzero(nodes["count"] > 0)
    counts = nodes["count"][leaves].astype(np.int64)
    firsts = nodes["left_first"][leaves].astype(np.int64)
    assert counts.max() <= leaf_cap
    # Leaf ranges tile the slots 0..M-1 without gaps or overlaps, and the slots hold every triangle once.
    by_first = np.argsort(firsts)
    assert firsts[by_first][0] == 0
    assert np.array_equal(firsts[by_first][1:], (firsts + counts)[by_first][:-1])
    assert (firsts + counts).max() == triangle_count
    assert np.array_equal(np.sort(order), np.arange(triangle_count))

    # Children inside parents, in float32 exactly as stored.
    interior = np.flatnonzero(nodes["count"] == 0)
    for child in (nodes["left_first"][interior], nodes["left_first"][interior] + 1):
        assert np.all(nodes["bmin"][interior] <= nodes["bmin"][child])
        assert np.all(nodes["bmax"][interior] >= nodes["bmax"][child])

    # Leaves contain their triangles: the float64 corners and the corners rounded to float32 (what the kernel reads).
    leaf_of_slot = np.repeat(leaves[by_first], counts[by_first])
    corners = triangles[order]  # (M, 3, 3) in slot order
    bmin = nodes["bmin"][leaf_of_slot].astype(np.float64)[:, None, :]
    bmax = nodes["bmax"][leaf_of_slot].astype(np.float64)[:, None, :]
    assert np.all(bmin <= corners) and np.all(corners <= bmax)
    rounded = corners.astype(np.float32)
    assert np.all(nodes["bmin"][leaf_of_slot][:, None, :] <= rounded)
    assert np.all(rounded <= nodes["bmax"][leaf_of_slot][:, None, :])


def _box_area(low, high):
    extent = np.maximum(np.asarray(high, np.float64) - np.asarray(low, np.float64), 0.0)
    return 2.0 * (extent[..., 0] * extent[..., 1] + extent[..., 1] * extent[..., 2] + extent[..., 2] * extent[..., 0])


def _sah_of_nodes(nodes):
    areas = _box_area(nodes["bmin"], nodes["bmax"])
    counts = nodes["count"]
    return float(np.sum(np.where(counts > 0, counts, 1) * areas) / areas[0])


def _naive_median_split_sah(triangles, max_leaf_size=4):
    """SAH cost of a tree that always splits at the centroid median of the longest centroid axis."""
    low, high = triangles.min(axis=1), triangles.max(axis=1)
    centroids = 0.5 * (low + high)
    total = 0.0
    pending = [np.arange(len(triangles))]
    while pending:
        members = pending.pop()
        area = _box_area(low[members].min(axis=0), high[members].max(axis=0))
        if len(members) <= max_leaf_size:
            total += area * len(members)
            continue
        total += area
        axis = np.argmax(np.ptp(centroids[members], axis=0))
        by_axis = members[np.argsort(centroids[members, axis], kind="stable")]
        pending += [by_axis[: len(members) // 2], by_axis[len(members) // 2 :]]
    return total / _box_area(low.min(axis=0), high.max(axis=0))


# ---------------------------------------------------------------------------------------------------------------
# Reference traversal: a plain stack walk in Python


def _ray_box_interval(origin, direction, low, high):
    """(t_near, t_far) of a ray through a box; an axis the ray runs parallel to either holds it or rules it out."""
    moving = direction != 0.0
    if np.any(~moving & ((origin < low) | (origin > high))):
        return np.inf, -np.inf
    slab_a = (low[moving] - origin[moving]) / direction[moving]
    slab_b = (high[moving] - origin[moving]) / direction[moving]
    return np.max(np.minimum(slab_a, slab_b), initial=-np.inf), np.min(np.maximum(slab_a, slab_b), initial=np.inf)


def _traverse_closest_hits(bvh, triangles, origins, directions):
    nodes, order = bvh.nodes, bvh.prim_order
    bmin, bmax = nodes["bmin"].astype(np.float64), nodes["bmax"].astype(np.float64)
    t_out = np.full(len(origins), np.inf)
    prim_out = np.full(len(origins), -1)
    for ray, (origin, direction) in enumerate(zip(origins, directions)):
        best_t, best_prim = np.inf, -1
        stack = [0]
        while stack:
            node = stack.pop()
            t_near, t_far = _ray_box_interval(origin, direction, bmin[node], bmax[node])
            # A whisker of slack: containment is asserted exactly elsewhere; this only absorbs slab rounding,
            # so that a box is never skipped for a hit that ties the best one to within rounding.
            slack = 1e-9 * max([abs(x) for x in (t_near, t_far) if np.isfinite(x)] + [1.0])
            if t_near > t_far + slack or t_far < -slack or t_near > best_t + slack:
                continue
            count, first = int(nodes["count"][node]), int(nodes["left_first"][node])
            if count == 0:
                stack += [first, first + 1]
                continue
            # In index order, so that a tie inside the leaf also goes to the lower triangle index.
            leaf_triangles = np.sort(order[first : first + count])
            t, local = brute_force_closest_hit(origin[None], direction[None], *_corners(triangles[leaf_triangles]))
            # Equal distances resolve to the lower triangle index, as the brute force does.
            if local[0] >= 0 and (t[0], leaf_triangles[local[0]]) < (best_t, best_prim if best_prim >= 0 else np.inf):
                best_t, best_prim = t[0], leaf_triangles[local[0]]
        t_out[ray], prim_out[ray] = best_t, best_prim
    return t_out, prim_out


def _rays_towards(rng, count, centre, radius):
    directions = rng.standard_normal((count, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    targets = centre + rng.uniform(-radius, radius, (count, 3))
    return targets - 2.0 * radius * directions, directions


# ---------------------------------------------------------------------------------------------------------------


def test_node_layout_matches_the_kernel_struct():
    # kernels/types.h: float bmin[3]; int left_first; float bmax[3]; int count;  (32 bytes)
    assert BVH_NODE_DTYPE.itemsize == 32
    assert [BVH_NODE_DTYPE.fields[name][1] for name in ("bmin", "left_first", "bmax", "count")] == [0, 12, 16, 28]


def test_brute_force_reference_on_hand_made_rays():
    square = np.array([[[-1, -1, 0], [1, -1, 0], [1, 1, 0]], [[-1, -1, 0], [1, 1, 0], [-1, 1, 0]]], float)
    far_square = square + [0, 0, -3]
    triangles = np.concatenate([far_square, square])
    origins = np.array([[0.5, -0.2, 2], [-0.5, 0.2, 2], [3, 0, 2], [0, 0, 2], [0.2, 0.1, -1]])
    directions = np.array([[0, 0, -1], [0, 0, -1], [0, 0, -1], [1, 0, 0], [0, 0, 1]], float)
    t, prim = brute_force_closest_hit(origins, directions, *_corners(triangles))
    # Down onto the near square (2 away, triangle below / above its diagonal), a miss beside it,
    # a ray parallel to both planes, and a ray from between the squares that only sees the near one.
    np.testing.assert_array_equal(prim, [2, 3, -1, -1, 2])
    np.testing.assert_allclose(t, [2, 2, np.inf, np.inf, 1])
    t_clipped, _ = brute_force_closest_hit(origins[:1], directions[:1], *_corners(triangles), t_min=2.5)
    np.testing.assert_allclose(t_clipped, [5])


def test_brute_force_reference_has_no_cracks_between_shared_edges():
    # A square of 8 x 8 cells, two triangles each; rays aimed exactly at interior vertices and edge midpoints.
    xs = np.linspace(-1.0, 1.0, 9)
    corner = np.stack(np.meshgrid(xs, xs, indexing="ij"), axis=-1)
    a, b, c, d = corner[:-1, :-1], corner[1:, :-1], corner[1:, 1:], corner[:-1, 1:]
    flat = np.concatenate([np.stack([a, b, c], axis=2), np.stack([a, c, d], axis=2)]).reshape(-1, 3, 2)
    triangles = np.concatenate([flat, np.zeros((len(flat), 3, 1))], axis=2)
    interior = corner[1:-1, 1:-1].reshape(-1, 2)
    targets = np.concatenate([interior, 0.5 * (interior[:-1] + interior[1:])])
    origins = np.column_stack([0.3 * targets, np.full(len(targets), 2.0)])
    directions = np.column_stack([targets, np.zeros(len(targets))]) - origins
    t, prim = brute_force_closest_hit(origins, directions, *_corners(triangles))
    assert np.all(prim >= 0)
    np.testing.assert_allclose(t, 1.0)  # o + 1 * (target - o) is the target
    # And the tree walk agrees, though the hit points lie exactly on box faces.
    _, walked = _traverse_closest_hits(build_bvh(*_corners(triangles)), triangles, origins, directions)
    np.testing.assert_array_equal(walked, prim)


@pytest.mark.parametrize("count", [2, 50, 3000])
def test_random_soup_structure(count):
    rng = np.random.default_rng(count)
    triangles = _soup(rng, count)
    assert_valid_bvh(build_bvh(*_corners(triangles)), triangles)


def test_real_mesh_structure_and_leaf_size_parameter():
    triangles = _bumpy_sphere_and_torus(np.random.default_rng(1))
    default = build_bvh(*_corners(triangles))
    assert_valid_bvh(default, triangles)
    single = build_bvh(*_corners(triangles), max_leaf_size=1)
    assert_valid_bvh(single, triangles)
    # Smaller leaves are allowed, not forced: the SAH still merges neighbours where splitting does not pay.
    leaf_count = [np.count_nonzero(tree.nodes["count"]) for tree in (default, single)]
    assert leaf_count[1] > 1.5 * leaf_count[0]
    wide = build_bvh(*_corners(triangles), max_leaf_size=24, bins=4)
    assert_valid_bvh(wide, triangles, leaf_cap=24)


@pytest.mark.parametrize("scene", ["soup", "real mesh"])
def test_traversal_finds_the_brute_force_closest_hits(scene):
    rng = np.random.default_rng(7)
    if scene == "soup":
        triangles = _soup(rng, 2000, spread=4.0, size=0.15)
        origins, directions = _rays_towards(rng, 300, centre=2.0, radius=2.5)
    else:
        triangles = _bumpy_sphere_and_torus(rng)
        origins, directions = _rays_towards(rng, 300, centre=0.0, radius=2.0)
    bvh = build_bvh(*_corners(triangles))
    t, prim = _traverse_closest_hits(bvh, triangles, origins, directions)
    ref_t, ref_prim = brute_force_closest_hit(origins, directions, *_corners(triangles))
    assert 0.3 < np.mean(ref_prim >= 0) < 0.95, "the rays should both hit and miss"
    np.testing.assert_array_equal(prim, ref_prim)
    np.testing.assert_allclose(t, ref_t, rtol=1e-12)


def test_binned_sah_beats_median_split_on_clustered_scene():
    rng = np.random.default_rng(3)
    cluster_centres = rng.uniform(0.0, 20.0, (6, 1, 1, 3))
    clusters = cluster_centres + rng.normal(0.0, 0.2, (6, 300, 3, 3))
    sizes = [4, 10, 40, 80, 400, 1000]  # clusters of very different density
    clustered = np.concatenate([c[:n] for c, n in zip(clusters, sizes)] + [_soup(rng, 100, spread=20.0, size=0.5)])
    bvh = build_bvh(*_corners(clustered))
    assert_valid_bvh(bvh, clustered)
    binned = _sah_of_nodes(bvh.nodes)
    assert bvh.sah_cost == pytest.approx(binned, rel=1e-9)
    assert sah_cost(bvh.nodes) == pytest.approx(binned, rel=1e-9)
    assert binned < 0.8 * _naive_median_split_sah(clustered)


def _round_float32_outward(values, toward):
    rounded = values.astype(np.float32)
    overshot = rounded > values if toward < 0 else rounded < values
    return np.where(overshot, np.nextafter(rounded, np.float32(toward)), rounded)


def _subtree_triangles(nodes, order, root):
    found, stack = [], [root]
    while stack:
        node = stack.pop()
        count, first = int(nodes["count"][node]), int(nodes["left_first"][node])
        if count:
            found.append(order[first : first + count])
        else:
            stack += [first, first + 1]
    return np.concatenate(found)


def test_root_split_is_the_cheapest_binned_plane():
    """Wald 2007: 16 equal bins over the centroid bounds on each axis; the root takes the cheapest boundary."""
    rng = np.random.default_rng(21)
    # Skewed density, so the best plane is nowhere near the middle of the bounds.
    triangles = rng.exponential(1.0, (500, 1, 3)) ** 2 + rng.normal(0.0, 0.1, (500, 3, 3))
    bvh = build_bvh(*_corners(triangles), bins=16)
    # The builder bins the float32 boxes (rounded outward) and their float32 centres.
    low = _round_float32_outward(triangles.min(axis=1), toward=-np.inf)
    high = _round_float32_outward(triangles.max(axis=1), toward=np.inf)
    centroid = (np.float32(0.5) * (low + high)).astype(np.float64)
    c_low, c_high = centroid.min(axis=0), centroid.max(axis=0)
    best = np.inf
    for axis in range(3):
        bins = np.minimum(((centroid[:, axis] - c_low[axis]) * (16 / (c_high[axis] - c_low[axis]))).astype(int), 15)
        for last_left in range(15):
            left = bins <= last_left
            if left.all() or not left.any():
                continue
            cost = sum(_box_area(low[side].min(axis=0), high[side].max(axis=0)) * side.sum() for side in (left, ~left))
            best = min(best, cost)
    first = int(bvh.nodes["left_first"][0])
    chosen = sum(
        _box_area(bvh.nodes["bmin"][child], bvh.nodes["bmax"][child])
        * len(_subtree_triangles(bvh.nodes, bvh.prim_order, child))
        for child in (first, first + 1)
    )
    assert chosen == pytest.approx(best, rel=1e-9)


@pytest.mark.parametrize(("gap", "expect_split"), [(0.5, False), (2.0, True)])
def test_two_triangles_split_only_when_the_sah_says_so(gap, expect_split):
    # Flat triangles with boxes [0,1]x[0,1] and [gap,gap+1]x[0,1] in z = 0: box areas 2, 2 and 2(1+gap).
    # Leaf cost 2 against split cost 1 + (2 + 2) / (2 (1 + gap)): a split pays only once the boxes are apart.
    assert (1 + 4 / (2 * (1 + gap)) < 2) == expect_split
    corner = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    triangles = np.stack([corner, corner + [gap, 0.0, 0.0]])
    bvh = build_bvh(*_corners(triangles), max_leaf_size=1)
    assert_valid_bvh(bvh, triangles)
    assert (bvh.nodes["count"][0] == 0) == expect_split


def test_single_triangle_is_a_root_leaf():
    triangles = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    bvh = build_bvh(*_corners(triangles))
    assert len(bvh.nodes) == 1 and bvh.nodes["count"][0] == 1 and bvh.depth == 0
    assert_valid_bvh(bvh, triangles)
    np.testing.assert_array_equal(bvh.nodes["bmin"][0], [0, 0, 0])
    np.testing.assert_array_equal(bvh.nodes["bmax"][0], [1, 1, 0])


def test_identical_triangles_split_by_the_hard_cap():
    triangle = np.array([[0.1, 0.2, 0.3], [1.1, 0.2, 0.3], [0.1, 1.7, 0.3]])
    triangles = np.repeat(triangle[None], 1000, axis=0)
    bvh = build_bvh(*_corners(triangles))
    assert_valid_bvh(bvh, triangles)
    # No plane separates identical centroids; splitting only for the cap gives leaves of 16 >= n > 8.
    counts = bvh.nodes["count"][bvh.nodes["count"] > 0]
    assert counts.min() > HARD_LEAF_CAP // 2


def test_zero_area_and_axis_aligned_flat_triangles():
    rng = np.random.default_rng(11)
    triangles = _soup(rng, 600, spread=3.0, size=0.2)
    triangles[:100, 2] = triangles[:100, 1]  # two corners equal
    triangles[100:200, 2] = 0.5 * (triangles[100:200, 0] + triangles[100:200, 1])  # collinear corners
    triangles[200:300, :, :] = triangles[200:300, :1, :]  # all three corners equal: a point
    # Flat in planes of constant z, each its own float32 value so the stored box has zero thickness
    # (and no two coplanar triangles overlap, which would make the closest one a matter of rounding).
    triangles[300:, :, 2] = triangles[300:, :1, 2].astype(np.float32)
    bvh = build_bvh(*_corners(triangles))
    assert_valid_bvh(bvh, triangles)
    origins, directions = _rays_towards(rng, 100, centre=1.5, radius=2.0)
    t, prim = _traverse_closest_hits(bvh, triangles, origins, directions)
    ref_t, ref_prim = brute_force_closest_hit(origins, directions, *_corners(triangles))
    assert np.mean(ref_prim >= 0) > 0.2
    np.testing.assert_array_equal(prim, ref_prim)
    np.testing.assert_allclose(t, ref_t, rtol=1e-12)


def test_depth_guard_caps_a_peeling_tree(monkeypatch):
    # Triangles at x = 16^i, each a fixed fraction of its distance: every binned split peels off the farthest
    # triangle, so the tree is as deep as there are triangles unless the depth guard steps in. float32 cannot
    # hold enough such triangles to reach the real limit of 64, so the test lowers the limit.
    count = 30
    scale = 16.0 ** np.arange(count)
    unit = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.01]])
    triangles = scale[:, None, None] * (unit + [1.0, 0.0, 0.0])
    unguarded = build_bvh(*_corners(triangles), max_leaf_size=1)
    assert unguarded.depth == count - 1
    assert_valid_bvh(unguarded, triangles)

    limit = 8
    monkeypatch.setattr(bvh_module, "MAX_DEPTH", limit)
    guarded = build_bvh(*_corners(triangles), max_leaf_size=1)
    assert guarded.depth <= limit
    assert_valid_bvh(guarded, triangles, leaf_cap=1)


def test_bad_input_is_rejected():
    with pytest.raises(ValueError):
        build_bvh(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(ValueError):
        build_bvh(np.full((1, 3), np.nan), np.zeros((1, 3)), np.ones((1, 3)))


def test_sampled_binning_keeps_the_tree_valid_and_good(monkeypatch):
    """Nodes above the sample size bin an evenly spaced sample of their triangles: every triangle still lands in
    exactly one leaf whose box holds it, and the tree still beats the median split by the same margin."""
    rng = np.random.default_rng(3)
    cluster_centres = rng.uniform(0.0, 20.0, (6, 1, 1, 3))
    clusters = cluster_centres + rng.normal(0.0, 0.2, (6, 300, 3, 3))
    sizes = [4, 10, 40, 80, 400, 1000]
    clustered = np.concatenate([c[:n] for c, n in zip(clusters, sizes)] + [_soup(rng, 100, spread=20.0, size=0.5)])
    monkeypatch.setattr(bvh_module, "SAMPLED_BINNING_TRIANGLES", 32)
    bvh = build_bvh(*_corners(clustered))
    assert_valid_bvh(bvh, clustered)
    assert bvh.sah_cost < 0.8 * _naive_median_split_sah(clustered)


@pytest.mark.parametrize(("threads", "nodes_per_thread"), [(2, 1), (3, 1), (8, 1), (2, 8)])
def test_threads_build_the_same_tree(monkeypatch, threads, nodes_per_thread):
    """Subtrees built on several threads, then joined level by level, give the single-thread tree bit for bit."""
    monkeypatch.setattr(bvh_module, "PARALLEL_BUILD_TRIANGLES", 100)
    monkeypatch.setattr(bvh_module, "PARALLEL_NODES_PER_THREAD", nodes_per_thread)
    triangles = _bumpy_sphere_and_torus(np.random.default_rng(5))
    single = build_bvh(*_corners(triangles), threads=1)
    split_level = bvh_module._split_level
    parts: list[int] = []

    def recording_split(level, count):
        groups = split_level(level, count)
        parts.append(len(groups))
        return groups

    monkeypatch.setattr(bvh_module, "_split_level", recording_split)
    shared = build_bvh(*_corners(triangles), threads=threads)
    # One split into 2..threads groups (nodes too uneven to cut evenly may merge two threads' shares).
    assert len(parts) == 1 and 2 <= parts[0] <= threads, "the build never went onto threads: nothing compared"
    assert_valid_bvh(shared, triangles)
    assert shared.depth == single.depth
    np.testing.assert_array_equal(shared.nodes, single.nodes)
    np.testing.assert_array_equal(shared.prim_order, single.prim_order)


def test_leaf_blocks_price_a_leaf_by_its_blocks():
    """Eight unit triangles in a row along x, each 1 deep in z: the row's box is 8 x 1 x 1 (area 34), each half's
    4 x 1 x 1 (area 18). Priced by triangles the halves cost 1 + (18·4 + 18·4)/34 = 5.2 < 8, a split; priced by
    four-triangle blocks they cost 1 + (18·1 + 18·1)/34 = 2.06 > 2, the row's two blocks, so it stays one leaf."""
    row = np.array([[[i, 0.0, 0.0], [i + 1.0, 0.0, 1.0], [i, 1.0, 0.0]] for i in range(8)])
    by_triangles = build_bvh(*_corners(row), max_leaf_size=4)
    by_blocks = build_bvh(*_corners(row), max_leaf_size=4, leaf_block=4)
    assert_valid_bvh(by_triangles, row)
    assert_valid_bvh(by_blocks, row)
    assert list(by_triangles.nodes["count"]) == [0, 4, 4]
    assert list(by_blocks.nodes["count"]) == [8]


def test_leaf_blocks_keep_a_valid_tree_that_fills_its_blocks():
    """On a real mesh, block pricing still gives a valid tree, and its leaves fill their blocks better."""
    triangles = _bumpy_sphere_and_torus(np.random.default_rng(7))
    by_triangles = build_bvh(*_corners(triangles), max_leaf_size=8)
    by_blocks = build_bvh(*_corners(triangles), max_leaf_size=8, leaf_block=4)
    assert_valid_bvh(by_blocks, triangles)

    def blocks(bvh):
        counts = bvh.nodes["count"][bvh.nodes["count"] > 0]
        return int((-(-counts // 4)).sum())

    assert blocks(by_blocks) < blocks(by_triangles)


def test_leaf_block_must_be_positive():
    row = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    with pytest.raises(ValueError, match="leaf_block"):
        build_bvh(*_corners(row), leaf_block=0)


def _furnished_room(rng):
    """A room's six walls (12 large triangles, 10 x 3 x 8) around small furniture: five bumpy balls of 1,280
    triangles each, two resting on the floor."""
    room = trimesh.creation.box(extents=[10.0, 3.0, 8.0])
    parts = [room.vertices[room.faces]]
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    for centre in ([-3.0, -1.2, -2.0], [2.5, -1.2, 1.0], [0.0, 0.5, 0.0], [-4.0, 1.0, 3.0], [3.5, 0.0, -3.0]):
        bumps = 1.0 + 0.05 * rng.standard_normal((len(ball.vertices), 1))
        parts.append((ball.vertices * bumps + centre)[ball.faces])
    return np.concatenate(parts)


def test_sampled_binning_bins_every_large_triangle():
    """A sampled node's sample gains each of its triangles whose box has at least LARGE_TRIANGLE_SHARE of the node's
    surface area, counted once, while the sampled small ones share the rest of the node's count; a node too small to
    be sampled is left alone."""
    rng = np.random.default_rng(21)
    triangles = _furnished_room(rng)  # 12 walls, then 6,400 small triangles
    node_size = bvh_module.SAMPLED_BINNING_TRIANGLES + 1000
    order = rng.permutation(len(triangles))
    big_node = np.sort(np.concatenate([np.arange(12), order[order >= 12][: node_size - 12]]))
    small_node = order[order >= 12][node_size - 12 : node_size + 88]
    members = np.concatenate([big_node, small_node])
    boxes = np.concatenate([triangles[members].min(axis=1), triangles[members].max(axis=1)], axis=1).T
    counts = np.array([len(big_node), len(small_node)])
    level = bvh_module._Level(
        triangle_ids=members.astype(np.int32),
        boxes=boxes.astype(np.float32),
        counts=counts,
        slot_offsets=np.array([0, len(big_node)]),
        tree_index=np.array([0, 1]),
    )
    starts = np.array([0, len(big_node)])
    lo = np.stack([boxes[:3, : len(big_node)].min(axis=1), boxes[:3, len(big_node) :].min(axis=1)])
    hi = np.stack([boxes[3:, : len(big_node)].max(axis=1), boxes[3:, len(big_node) :].max(axis=1)])
    extent = hi - lo
    node_half_area = extent[:, 0] * extent[:, 1] + extent[:, 1] * extent[:, 2] + extent[:, 2] * extent[:, 0]
    sample = bvh_module.SAMPLED_BINNING_TRIANGLES
    stride = np.arange(sample) * len(big_node) // sample
    positions = np.concatenate([stride, starts[1] + np.arange(len(small_node))])
    joined, joined_counts, weights = bvh_module._with_large_triangles(
        level, starts, np.array([0, 1]), node_half_area, positions, np.array([sample, len(small_node)])
    )

    size = boxes[3:] - boxes[:3]
    half_area = size[0] * size[1] + size[1] * size[2] + size[2] * size[0]
    large = np.flatnonzero(half_area[: len(big_node)] >= bvh_module.LARGE_TRIANGLE_SHARE * node_half_area[0])
    assert set(members[large]) == set(range(12)), "the room's walls, and only they, are large"
    assert set(stride) <= set(joined) and set(large) <= set(joined)
    assert joined_counts[0] == len(set(stride) | set(large)) and joined_counts[1] == len(small_node)
    assert weights is not None
    first = weights[: joined_counts[0]]
    np.testing.assert_array_equal(first[np.isin(joined[: joined_counts[0]], large)], 1.0)
    assert first.sum() == pytest.approx(len(big_node), rel=1e-12)
    np.testing.assert_array_equal(weights[joined_counts[0] :], 1.0)


def test_sampled_binning_in_a_room_finds_the_brute_force_hits(monkeypatch):
    """Built with sampled nodes that bin their large triangles, the tree is valid and the traversal finds the
    brute-force closest hits of rays inside the room."""
    triangles = _furnished_room(np.random.default_rng(11))
    monkeypatch.setattr(bvh_module, "SAMPLED_BINNING_TRIANGLES", 64)
    sampled = build_bvh(*_corners(triangles), max_leaf_size=8, leaf_block=4)
    assert_valid_bvh(sampled, triangles)
    rng = np.random.default_rng(12)
    origins = rng.uniform([-4.9, -1.4, -3.9], [4.9, 1.4, 3.9], (300, 3))
    directions = rng.normal(size=(300, 3))
    t, prim = _traverse_closest_hits(sampled, triangles, origins, directions)
    ref_t, ref_prim = brute_force_closest_hit(origins, directions, *_corners(triangles))
    assert np.all(ref_prim >= 0), "every ray inside the closed room hits something"
    np.testing.assert_array_equal(prim, ref_prim)
    np.testing.assert_allclose(t, ref_t, rtol=1e-12)


def test_threads_build_the_same_tree_with_large_triangles(monkeypatch):
    """The sampled nodes' large triangles are found per node, so threads still give the single-thread tree."""
    monkeypatch.setattr(bvh_module, "SAMPLED_BINNING_TRIANGLES", 64)
    monkeypatch.setattr(bvh_module, "PARALLEL_BUILD_TRIANGLES", 100)
    monkeypatch.setattr(bvh_module, "PARALLEL_NODES_PER_THREAD", 1)
    triangles = _furnished_room(np.random.default_rng(13))
    single = build_bvh(*_corners(triangles), max_leaf_size=8, leaf_block=4, threads=1)
    shared = build_bvh(*_corners(triangles), max_leaf_size=8, leaf_block=4, threads=3)
    np.testing.assert_array_equal(shared.nodes, single.nodes)
    np.testing.assert_array_equal(shared.prim_order, single.prim_order)
