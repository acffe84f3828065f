"""Bounding volume hierarchy over triangles: a binned surface-area-heuristic build, vectorised with numpy.

The tree is built breadth-first, one level at a time. Every node of a level is binned in the same numpy
calls (each triangle carries the id of its node), so the Python work per level is a fixed number of array
operations, whatever the number of nodes or triangles in it.

Method: binned SAH over centroid bounds (Wald 2007, "On fast construction of SAH-based bounding volume
hierarchies"; pbrt-v4, Sec. 7.3.2), 12 bins per axis by default as in pbrt-v4 (against 16: 10-17 % less build
time on 1.3-2 M triangles for SAH costs 0.06-0.1 % higher). Cost model: traversing a node costs 1, intersecting a
triangle costs 1, so a split of node N into L and R costs 1 + (A(L) |L| + A(R) |R|) / A(N) against |N| for a
leaf. With leaf_block = b > 1 (the 4-wide traversal tests leaves b triangles at a time) a side's |S| becomes its
blocks ceil(|S| / b), each costing BLOCK_COST, as Embree's builders price leaves of b-wide primitives (Wald et al.
2008 pack leaves the same way): a leaf of 5 triangles then costs as much as one of 8. A node becomes a leaf when
it holds <= max_leaf_size triangles or no split beats the leaf, except that nodes
above FORCED_SPLIT_LEAF_SIZE are always split. Where binning cannot separate the centroids (all coincide), or where
the depth left before MAX_DEPTH runs short, the node is split at the middle of its triangles in Morton order.

What makes it fast on millions of triangles (docs/performance.md, "BVH build"):
- The triangles are first sorted along the Z-order (Morton) curve through their box centres (Lauterbach et al.
  2009; pbrt-v4's HLBVH sorts the same codes). The partitions are stable, so every node keeps its triangles in
  that order: a node's neighbours sit together in memory, and a median split needs no sort.
- A node of more than SAMPLED_BINNING_TRIANGLES triangles fills its bins from an evenly spaced sample of that
  many of them (spread over the node's surface by the Morton order), then sends every triangle to the side of the
  chosen plane. On 2 M triangles this halves the binning work of the upper levels for an SAH cost within a few
  percent. The sample also holds every large triangle of the node (a box of at least LARGE_TRIANGLE_SHARE of the
  node's surface area), each counted once while the others stand for the rest: a room's walls and floor are a few
  triangles among hundreds of thousands, which the sample alone misses, and the plane it then picks puts a wall into a
  node of small objects whose box becomes the whole room (living room: SAH cost 40.5 with the plain sample, 27.3
  binning every triangle, 25.8 with the large triangles and SAMPLED_BINS bins; renders 1.14-1.24x faster, the same
  image; docs/performance.md, "Large triangles in the sampled binning").
- Once a level holds a few nodes per thread the subtrees below are built on threads (numpy's array loops mostly run
  without the GIL), one per core the process may use (at most MAX_BUILD_THREADS) unless told otherwise; each
  thread writes its own leaves' slots, and the levels are joined in order, so the tree is the one a single thread
  builds, bit for bit, whatever the number of threads.

Layout (mirrors `BVHNode` in kernels/types.h): an interior node has count == 0 and its children at
left_first and left_first + 1; a leaf has count > 0 triangles in slots prim_order[left_first : left_first +
count]. Node 0 is the root. Bounds are float32 rounded outward, so they contain their float64 triangles and
also those triangles' vertices rounded to the nearest float32.
"""

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from time import perf_counter

import numpy as np

from spectrace.core.contract import BVH_NODE_DTYPE, MAX_DEPTH

# Above this many triangles a node is split even where the SAH prefers a leaf, so leaf loops stay short.
FORCED_SPLIT_LEAF_SIZE = 16
# Cost of testing one leaf block (leaf_block triangles at once) against traversing a node, when leaf_block > 1.
BLOCK_COST = 1.0
# Nodes of more triangles fill their bins from an evenly spaced sample of this many of them (module docstring).
SAMPLED_BINNING_TRIANGLES = 512
# A sampled node's triangles whose boxes have at least this share of its box's surface area join its sample
# (_with_large_triangles).
LARGE_TRIANGLE_SHARE = 1.0 / 64.0
# Bins per axis of a sampled node (at least build_bvh's bins).
SAMPLED_BINS = 16
# Bits per axis of the Morton codes that order the triangles before the build (3 x 21 = 63 bits).
MORTON_BITS = 21
# Levels of at least this many triangles are shared out between threads, by subtree (module docstring).
PARALLEL_BUILD_TRIANGLES = 65536
# The subtrees go to threads once a level has this many nodes per thread: cut between more nodes, the threads' shares
# of triangles come out more even (2.04 M-triangle Lego scene, 2 threads: the larger share 62 % of the triangles cut
# at 2 nodes, 51 % at 16), for a few more levels built on one thread.
PARALLEL_NODES_PER_THREAD = 8
# Most threads a build uses by default: past a few, the levels above the split, built on one thread, dominate.
MAX_BUILD_THREADS = 8
# Nodes x bins evaluated per binning pass; bounds the temporary per-bin arrays to a few MB.
_SAH_CHUNK_BIN_ENTRIES = 1 << 18


@dataclass
class BVH:
    nodes: np.ndarray  # (K,) BVH_NODE_DTYPE, node 0 is the root
    prim_order: np.ndarray  # (M,) int32: triangle index held by each leaf slot
    depth: int  # edges on the longest root-to-leaf path (a root leaf has depth 0)
    sah_cost: float  # see sah_cost()
    build_seconds: float


@dataclass
class _Level:
    """The triangles still to be split, grouped by node, with everything the binning reads. The nodes are stored
    in the order the last partition left them (every left child, then every right child), not in the tree's."""

    triangle_ids: np.ndarray  # (A,) int32
    boxes: np.ndarray  # (6, A) float32 rows: min x, y, z, max x, y, z (rounded outward)
    counts: np.ndarray  # (N,) int64 triangles per node, every one >= 1
    slot_offsets: np.ndarray  # (N,) int64 first prim_order slot of each node
    tree_index: np.ndarray  # (N,) int64 each node's place in the tree's level (children of a node side by side)


@dataclass
class _SplitPlan:
    """Per-node outcome of the binned SAH: the cheapest split plane, as an axis and a last left bin."""

    cost: np.ndarray  # (N,) float64 sum A(child) |child| of the best split, inf where none is valid
    axis: np.ndarray  # (N,) int64
    last_left_bin: np.ndarray  # (N,) int64


@dataclass
class _LevelSplits:
    """What happens to each node of a level, and the binning from which the partition finds each plane."""

    is_split: np.ndarray  # (N,) bool: interior node (else leaf)
    use_median: np.ndarray  # (N,) bool: split at the middle of the node's triangles instead of the SAH plane
    plan: _SplitPlan
    bin_origin: np.ndarray  # (N, 3) float64 low corner of the centroid bounds
    bin_scale: np.ndarray  # (N, 3) float64 bins per unit length (0 on axes where all centroids coincide)


def build_bvh(
    v0: np.ndarray,
    v1: np.ndarray,
    v2: np.ndarray,
    max_leaf_size: int = 4,
    bins: int = 12,
    threads: int | None = None,
    leaf_block: int = 1,
) -> BVH:
    """Build a binned-SAH BVH over triangles (v0[i], v1[i], v2[i]), each (M, 3) in scene units, on `threads`
    threads (None: default_build_threads()); the tree is the same for any number of threads. Threads pay off only
    where cores are free (docs/performance.md, "BVH build"), and the split costs a copy of the level it starts at.

    leaf_block: the traversal tests a leaf's triangles this many at a time, so the SAH prices a leaf by its blocks,
    ceil(count / leaf_block), each costing BLOCK_COST (see the module's cost model); 1 is the classic triangle count."""
    start = perf_counter()
    if max_leaf_size < 1:
        raise ValueError(f"max_leaf_size must be >= 1, got {max_leaf_size}")
    if bins < 2:
        raise ValueError(f"bins must be >= 2, got {bins}")
    if leaf_block < 1:
        raise ValueError(f"leaf_block must be >= 1, got {leaf_block}")
    boxes = _triangle_boxes_float32(v0, v1, v2)
    triangle_count = boxes.shape[1]
    forced_split_above = max(FORCED_SPLIT_LEAF_SIZE, max_leaf_size)

    # Morton order first: every later partition is stable, so each node keeps its triangles in this order, and an
    # evenly spaced sample of them is spread over the node's whole surface.
    morton = _morton_order(boxes)
    prim_order = np.empty(triangle_count, dtype=np.int32)
    root = _Level(
        triangle_ids=morton,
        boxes=_take_columns(boxes, morton),
        counts=np.array([triangle_count], dtype=np.int64),
        slot_offsets=np.zeros(1, dtype=np.int64),
        tree_index=np.zeros(1, dtype=np.int64),
    )
    del boxes, morton  # the level holds them now, in Morton order; each level frees its parent's arrays
    threads = default_build_threads() if threads is None else max(1, threads)

    def build_levels(top: _Level, top_depth: int, until_parallel: bool) -> tuple[list[np.ndarray], _Level | None]:
        """Levels from `top` down, children numbered from 0 within each level (offset later): to the leaves, or
        until a level is large enough and has a node for each thread."""
        levels: list[np.ndarray] = []
        current: _Level | None = top
        del top  # so that each level's arrays are freed once the next one is made
        while current is not None:
            if (
                until_parallel
                and current.counts.size >= threads * PARALLEL_NODES_PER_THREAD
                and current.triangle_ids.size >= PARALLEL_BUILD_TRIANGLES
            ):
                break
            depth = top_depth + len(levels)
            if depth > MAX_DEPTH:  # the depth guard in _choose_splits makes this unreachable
                raise RuntimeError(f"BVH build exceeded depth {MAX_DEPTH}")
            nodes, current = _build_level(
                current, depth, prim_order, max_leaf_size, forced_split_above, bins, leaf_block
            )
            levels.append(nodes)
        return levels, current

    holder = [root]
    del root
    top_levels, rest = build_levels(holder.pop(), 0, until_parallel=threads > 1)
    levels = [[nodes] for nodes in top_levels]  # each level as parts: one, or one per thread below the split
    if rest is not None:
        # Disjoint subtrees, in level order: each thread writes its own leaves' slots and its own nodes, and the
        # levels are then joined in the same order, so the tree is the one a single thread builds.
        groups = _split_level(_in_tree_order(rest), threads)
        del rest
        with ThreadPoolExecutor(threads) as pool:
            parts = list(pool.map(lambda part: build_levels(part, len(top_levels), False)[0], groups))
        empty = np.zeros(0, dtype=BVH_NODE_DTYPE)
        levels += [[part[j] if j < len(part) else empty for part in parts] for j in range(max(map(len, parts)))]
    _number_children(levels)
    all_nodes = np.concatenate([part for parts in levels for part in parts])
    return BVH(
        nodes=all_nodes,
        prim_order=prim_order,
        depth=len(levels) - 1,
        sah_cost=sah_cost(all_nodes),
        build_seconds=perf_counter() - start,
    )


def default_build_threads() -> int:
    """The cores this process may run on (its CPU affinity), at most MAX_BUILD_THREADS."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # no affinity call on this platform (macOS, Windows)
        cores = os.cpu_count() or 1
    return max(1, min(cores, MAX_BUILD_THREADS))


def _split_level(level: _Level, parts: int) -> list[_Level]:
    """The level's nodes cut into `parts` consecutive groups of about equal triangle counts (none empty)."""
    ends = np.cumsum(level.counts)
    total = int(ends[-1])
    cuts = np.searchsorted(ends, total * np.arange(1, parts) / parts, side="left") + 1
    cuts = np.unique(np.clip(cuts, 1, level.counts.size - 1)) if level.counts.size > 1 else np.zeros(0, np.int64)
    groups = []
    for first, last in zip(np.concatenate(([0], cuts)), np.concatenate((cuts, [level.counts.size]))):
        begin = int(ends[first] - level.counts[first])
        end = int(ends[last - 1])
        groups.append(
            _Level(
                triangle_ids=level.triangle_ids[begin:end],
                boxes=level.boxes[:, begin:end],
                counts=level.counts[first:last],
                slot_offsets=level.slot_offsets[first:last],
                tree_index=level.tree_index[first:last] - first,
            )
        )
    return groups


def _in_tree_order(level: _Level) -> _Level:
    """The level with its nodes (and their triangles) in the tree's order, so that consecutive nodes are
    consecutive subtrees."""
    order = np.argsort(level.tree_index)
    counts = level.counts[order]
    run_starts = (np.cumsum(level.counts) - level.counts)[order]
    source = np.arange(int(counts.sum())) + np.repeat(run_starts - (np.cumsum(counts) - counts), counts)
    return _Level(
        triangle_ids=level.triangle_ids[source],
        boxes=_take_columns(level.boxes, source),
        counts=counts,
        slot_offsets=level.slot_offsets[order],
        tree_index=np.arange(counts.size),
    )


def _number_children(levels: list[list[np.ndarray]]) -> None:
    """Make the interior nodes' left_first (numbered from 0 within their part of the next level) global indices.
    A level has either one part or as many as the next level, part k's children being in the next level's part k."""
    start = 0
    for depth, parts in enumerate(levels):
        next_start = start + sum(part.size for part in parts)
        if depth + 1 < len(levels):
            following = levels[depth + 1]
            offsets = [next_start]
            if len(parts) == len(following):
                offsets = list(next_start + np.cumsum([0] + [part.size for part in following[:-1]]))
            for part, offset in zip(parts, offsets):
                part["left_first"][part["count"] == 0] += offset
        start = next_start


def sah_cost(nodes: np.ndarray) -> float:
    """Expected cost of a random ray: sum over interior nodes A(n)/A(root) + sum over leaves A(l)/A(root) * count.

    A flat or point-like root (area 0) is scored with every area ratio equal to 1, the limit of shrinking a
    scene uniformly."""
    areas = _box_areas(nodes["bmin"].astype(np.float64), nodes["bmax"].astype(np.float64))
    counts = nodes["count"].astype(np.float64)
    per_node_cost = np.where(counts > 0, counts, 1.0)
    root_area = areas[0]
    if root_area <= 0.0:
        return float(per_node_cost.sum())
    return float((areas / root_area * per_node_cost).sum())


def _triangle_boxes_float32(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """(6, M) float32 triangle bounds, min rounded down and max rounded up so they hold the exact triangle."""
    corners = [np.asarray(v, dtype=np.float64) for v in (v0, v1, v2)]
    shape = corners[0].shape
    if len(shape) != 2 or shape[1] != 3 or shape[0] == 0 or any(c.shape != shape for c in corners):
        raise ValueError(f"build_bvh needs three (M, 3) vertex arrays with M >= 1, got {[c.shape for c in corners]}")
    boxes = np.empty((6, shape[0]), dtype=np.float32)
    # One coordinate at a time keeps the float64 temporaries to a single column.
    for axis in range(3):
        a, b, c = (corner[:, axis] for corner in corners)
        if not (np.isfinite(a).all() and np.isfinite(b).all() and np.isfinite(c).all()):
            raise ValueError("build_bvh got NaN or infinite vertex coordinates")
        boxes[axis] = _round_float32(np.minimum(np.minimum(a, b), c), toward=-np.inf)
        boxes[axis + 3] = _round_float32(np.maximum(np.maximum(a, b), c), toward=np.inf)
    return boxes


def _round_float32(values: np.ndarray, toward: float) -> np.ndarray:
    """float64 -> float32, rounding toward -inf or +inf instead of to nearest."""
    rounded = values.astype(np.float32)
    overshot = rounded > values if toward < 0 else rounded < values
    return np.where(overshot, np.nextafter(rounded, np.float32(toward)), rounded)


def _box_areas(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Surface areas of boxes given as (..., 3) corner arrays, in float64."""
    extent = np.maximum(high - low, 0.0)
    x, y, z = extent[..., 0], extent[..., 1], extent[..., 2]
    return 2.0 * (x * y + y * z + z * x)


def _morton_order(boxes: np.ndarray) -> np.ndarray:
    """(M,) int32 order of the triangles along the Z-order curve through their box centres."""
    centre = boxes[:3].astype(np.float64) + boxes[3:]
    low = centre.min(axis=1, keepdims=True)
    extent = centre.max(axis=1, keepdims=True) - low
    cells = float(1 << MORTON_BITS)
    with np.errstate(divide="ignore"):
        scale = np.where(extent > 0.0, cells / extent, 0.0)
    cell = np.minimum((centre - low) * scale, cells - 1.0).astype(np.uint64)
    code = _spread_bits(cell[0]) << np.uint64(2)
    code |= _spread_bits(cell[1]) << np.uint64(1)
    code |= _spread_bits(cell[2])
    return np.argsort(code, kind="stable").astype(np.int32)


def _spread_bits(value: np.ndarray) -> np.ndarray:
    """Each bit of a MORTON_BITS-bit integer moved to three times its position (two zero bits after each)."""
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F)):
        value = (value | (value << np.uint64(shift))) & np.uint64(mask)
    value = (value | (value << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    return (value | (value << np.uint64(2))) & np.uint64(0x1249249249249249)


def _levels_to_leaf_by_halving(counts: np.ndarray, max_leaf_size: int) -> np.ndarray:
    """Levels of object-median splits needed until every piece holds <= max_leaf_size triangles."""
    pieces = -(-counts // max_leaf_size)
    return np.ceil(np.log2(pieces.astype(np.float64))).astype(np.int64)


def _build_level(
    level: _Level,
    depth: int,
    prim_order: np.ndarray,
    max_leaf_size: int,
    forced_split_above: int,
    bins: int,
    leaf_block: int,
) -> tuple[np.ndarray, "_Level | None"]:
    """Make the nodes of one tree level; write leaf triangles into prim_order; return the next level."""
    counts = level.counts
    node_count = counts.size
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    node_of_triangle = np.repeat(np.arange(node_count, dtype=np.int32), counts)

    rows = np.zeros(node_count, dtype=BVH_NODE_DTYPE)  # in the level's order; `nodes` below in the tree's
    low = np.stack([np.minimum.reduceat(row, starts) for row in level.boxes[:3]], axis=1)
    high = np.stack([np.maximum.reduceat(row, starts) for row in level.boxes[3:]], axis=1)
    rows["bmin"] = low
    rows["bmax"] = high

    splits = _choose_splits(level, starts, low, high, depth, max_leaf_size, forced_split_above, bins, leaf_block)

    _emit_leaves(level, starts, node_of_triangle, ~splits.is_split, prim_order)
    rows["count"] = np.where(splits.is_split, 0, counts)
    rows["left_first"] = level.slot_offsets
    split_nodes = np.flatnonzero(splits.is_split)
    nodes = np.empty_like(rows)
    nodes[level.tree_index] = rows
    if split_nodes.size == 0:
        return nodes, None

    goes_right, right_counts = _triangle_sides(level, starts, node_of_triangle, splits, bins)

    # Children side by side in the tree, numbered within the next level (_number_children makes them node
    # indices), in the order of their parents there.
    rank = np.empty(split_nodes.size, np.int64)
    rank[np.argsort(level.tree_index[split_nodes])] = np.arange(split_nodes.size)
    nodes["left_first"][level.tree_index[split_nodes]] = 2 * rank
    return nodes, _partition(level, splits.is_split, goes_right, right_counts, 2 * rank)


def _choose_splits(
    level: _Level,
    starts: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    depth: int,
    max_leaf_size: int,
    forced_split_above: int,
    bins: int,
    leaf_block: int,
) -> _LevelSplits:
    """Decide per node: leaf, SAH split, or a split at the middle (when binning cannot separate or depth runs out)."""
    counts = level.counts
    may_split = counts > max_leaf_size
    plan = _SplitPlan(
        cost=np.full(counts.size, np.inf),
        axis=np.zeros(counts.size, dtype=np.int64),
        last_left_bin=np.zeros(counts.size, dtype=np.int64),
    )
    bin_origin = np.zeros((counts.size, 3))
    bin_scale = np.zeros((counts.size, 3))
    node_area = _box_areas(low.astype(np.float64), high.astype(np.float64))
    sampled = may_split & (counts > SAMPLED_BINNING_TRIANGLES)
    for nodes, node_bins in ((may_split & ~sampled, bins), (sampled, max(bins, SAMPLED_BINS))):
        if nodes.any():
            _binned_sah(level, starts, nodes, 0.5 * node_area, bin_origin, bin_scale, node_bins, plan, leaf_block)

    # 1 + BLOCK_COST * cost / A(node) < BLOCK_COST * blocks, written without dividing so flat nodes (area 0) never
    # prefer splitting; with leaf_block 1 and BLOCK_COST 1 this is 1 + cost / A(node) < count.
    block_cost = BLOCK_COST if leaf_block > 1 else 1.0
    sah_prefers_split = plan.cost < (_blocks(counts, leaf_block) - 1.0 / block_cost) * node_area
    is_split = may_split & (sah_prefers_split | (counts > forced_split_above))
    # Halving finishes within MAX_DEPTH from any node that keeps depth + levels_to_leaf <= MAX_DEPTH,
    # which holds at the root; an SAH split can leave a child nearly as large as its parent, so it is
    # only allowed while that bound has a level to spare.
    depth_exhausted = depth + _levels_to_leaf_by_halving(counts, max_leaf_size) >= MAX_DEPTH
    use_median = is_split & (~np.isfinite(plan.cost) | depth_exhausted)
    return _LevelSplits(is_split=is_split, use_median=use_median, plan=plan, bin_origin=bin_origin, bin_scale=bin_scale)


def _bin_of(values: np.ndarray, origin: np.ndarray, scale: np.ndarray, bins: int) -> np.ndarray:
    """Bin index of each centroid coordinate (the partition's planes are its bin boundaries). A triangle left out of
    a node's sample may lie outside the sample's centroid bounds: it goes to the first or the last bin."""
    index = np.subtract(values, origin, dtype=np.float64)
    index *= scale
    np.clip(index, 0.0, bins - 1, out=index)
    return index.astype(np.int32)


def _binned_sah(
    level: _Level,
    starts: np.ndarray,
    may_split: np.ndarray,
    node_half_area: np.ndarray,
    bin_origin: np.ndarray,
    bin_scale: np.ndarray,
    bins: int,
    plan: _SplitPlan,
    leaf_block: int,
) -> None:
    """Fill plan, bin_origin and bin_scale for the nodes in may_split, from an evenly spaced sample of at most
    SAMPLED_BINNING_TRIANGLES of each one's triangles (with its large triangles, _with_large_triangles), in chunks of
    nodes so the per-bin arrays stay small."""
    candidates = np.flatnonzero(may_split)
    counts = level.counts[candidates]
    sample_counts = np.minimum(counts, SAMPLED_BINNING_TRIANGLES)
    sample_starts = np.cumsum(sample_counts) - sample_counts
    weights = None
    if candidates.size == level.counts.size and np.array_equal(sample_counts, counts):
        boxes = level.boxes
    else:
        node = np.repeat(np.arange(candidates.size), sample_counts)
        rank = np.arange(int(sample_counts.sum())) - sample_starts[node]
        positions = starts[candidates][node] + rank * counts[node] // sample_counts[node]
        if (counts > SAMPLED_BINNING_TRIANGLES).any():
            positions, sample_counts, weights = _with_large_triangles(
                level, starts, candidates, node_half_area, positions, sample_counts
            )
            sample_starts = np.cumsum(sample_counts) - sample_counts
        boxes = _take_columns(level.boxes, positions)
    # The partition recomputes these centres from the same float32 boxes by the same expression.
    centroids = np.float32(0.5) * (boxes[:3] + boxes[3:])
    centroid_low = np.stack([np.minimum.reduceat(row, sample_starts) for row in centroids], axis=1)
    centroid_high = np.stack([np.maximum.reduceat(row, sample_starts) for row in centroids], axis=1)
    origin = centroid_low.astype(np.float64)
    extent = centroid_high.astype(np.float64) - origin
    # Finite in float64 even for float32 denormal extents.
    with np.errstate(divide="ignore"):
        scale = np.where(extent > 0.0, bins / extent, 0.0)
    bin_origin[candidates] = origin
    bin_scale[candidates] = scale
    ends = sample_starts + sample_counts
    nodes_per_chunk = max(1, _SAH_CHUNK_BIN_ENTRIES // bins)
    for chunk_begin in range(0, candidates.size, nodes_per_chunk):
        chunk = slice(chunk_begin, min(chunk_begin + nodes_per_chunk, candidates.size))
        first = int(sample_starts[chunk.start])
        last = int(ends[chunk.stop - 1])
        nodes = candidates[chunk]
        cost, axis, last_left_bin = _best_binned_split(
            centroids[:, first:last],
            boxes[:, first:last],
            sample_counts[chunk],
            origin[chunk],
            scale[chunk],
            bins,
            leaf_block,
            None if weights is None else weights[first:last],
        )
        plan.cost[nodes] = cost
        plan.axis[nodes] = axis
        plan.last_left_bin[nodes] = last_left_bin


def _with_large_triangles(
    level: _Level,
    starts: np.ndarray,
    candidates: np.ndarray,
    node_half_area: np.ndarray,
    positions: np.ndarray,
    sample_counts: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(positions, sample counts, weights or None): the evenly spaced samples of the nodes `candidates` (positions in
    the level, grouped by node) joined by every large triangle of a sampled node, each sampled triangle weighted by the
    triangles it stands for. A large triangle is one whose box's surface area is at least LARGE_TRIANGLE_SHARE of its
    node's. The few large triangles of a room (walls, floor) decide where its first splits go, but an evenly spaced
    sample of a node full of small ones mostly misses them, and the split the sample chose then sends each to one side,
    whose box becomes the room (living room: SAH cost 40.5 sampled against 27.3 binning every triangle). Each large
    triangle counts once; the sample's other triangles share the rest of the node's count. Weights None (every
    triangle counts once, as without large triangles) where no sampled node has a large triangle."""
    counts = level.counts[candidates]
    sampled = np.zeros(level.counts.size, bool)
    sampled[candidates[counts > SAMPLED_BINNING_TRIANGLES]] = True
    # Whole contiguous rows in float32 (a few passes over the level) rather than gathering the sampled nodes' columns.
    threshold = np.where(sampled, LARGE_TRIANGLE_SHARE * node_half_area, np.inf).astype(np.float32)
    boxes = level.boxes
    dx, dy, dz = boxes[3] - boxes[0], boxes[4] - boxes[1], boxes[5] - boxes[2]
    half_area = dx * dy
    half_area += dy * dz
    dz *= dx
    half_area += dz
    large = np.flatnonzero(half_area >= np.repeat(threshold, level.counts))
    if large.size == 0:
        return positions, sample_counts, None
    large_node = np.searchsorted(starts, large, side="right") - 1  # every node holds >= 1 triangle
    large_per_node = np.bincount(large_node, minlength=level.counts.size)
    # A node made mostly of large triangles keeps its plain sample: the sample stays within twice its size.
    too_many = large_per_node > SAMPLED_BINNING_TRIANGLES
    large = large[~too_many[large_node]]
    if large.size == 0:
        return positions, sample_counts, None
    large_per_node[too_many] = 0
    # Sorted positions stay grouped by node, in the candidates' order (both follow the level's order).
    joined = np.union1d(positions, large)
    rank = np.searchsorted(candidates, np.searchsorted(starts, joined, side="right") - 1)
    joined_counts = np.bincount(rank, minlength=candidates.size)
    is_large = np.zeros(int(level.counts.sum()), bool)
    is_large[large] = True
    large_in_node = large_per_node[candidates]
    small_share = np.where(
        large_in_node > 0, (counts - large_in_node) / np.maximum(joined_counts - large_in_node, 1), 1.0
    )
    weights = np.where(is_large[joined], 1.0, small_share[rank])
    return joined, joined_counts, weights


def _best_binned_split(
    centroids: np.ndarray,
    boxes: np.ndarray,
    counts: np.ndarray,
    bin_origin: np.ndarray,
    bin_scale: np.ndarray,
    bins: int,
    leaf_block: int,
    weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bin every node's triangles on each axis and sweep the bin boundaries for the cheapest SAH split; each triangle
    counts `weights` triangles (None: one)."""
    node_count = counts.size
    node_of_triangle = np.repeat(np.arange(node_count, dtype=np.int32), counts)
    best_cost = np.full(node_count, np.inf)
    best_axis = np.zeros(node_count, dtype=np.int64)
    best_bin = np.zeros(node_count, dtype=np.int64)
    all_nodes = np.arange(node_count)
    for axis in range(3):
        bin_index = _bin_of(
            centroids[axis], np.repeat(bin_origin[:, axis], counts), np.repeat(bin_scale[:, axis], counts), bins
        )
        # Node-major keys keep the scattered reductions local in memory; the sweeps then want bin-major rows.
        node_bin = node_of_triangle.astype(np.intp) * bins + bin_index  # ufunc.at is fastest with intp indices
        bin_counts = np.bincount(node_bin, minlength=node_count * bins).reshape(node_count, bins).T
        bin_weights = None
        if weights is not None:
            bin_weights = np.bincount(node_bin, weights, minlength=node_count * bins).reshape(node_count, bins).T
        bin_boxes = np.empty((6, node_count * bins), dtype=np.float32)
        bin_boxes[:3] = np.inf
        bin_boxes[3:] = -np.inf
        for row in range(3):
            np.minimum.at(bin_boxes[row], node_bin, boxes[row])
            np.maximum.at(bin_boxes[row + 3], node_bin, boxes[row + 3])
        bin_boxes = np.ascontiguousarray(bin_boxes.reshape(6, node_count, bins).transpose(0, 2, 1))
        cost = _split_costs(
            bin_boxes,
            np.ascontiguousarray(bin_counts),
            leaf_block,
            None if bin_weights is None else np.ascontiguousarray(bin_weights),
        )
        axis_best_bin = np.argmin(cost, axis=0)
        axis_best_cost = cost[axis_best_bin, all_nodes]
        better = axis_best_cost < best_cost
        best_cost[better] = axis_best_cost[better]
        best_axis[better] = axis
        best_bin[better] = axis_best_bin[better]
    return best_cost, best_axis, best_bin


def _split_costs(
    bin_boxes: np.ndarray, bin_counts: np.ndarray, leaf_block: int = 1, bin_weights: np.ndarray | None = None
) -> np.ndarray:
    """(bins-1, N) cost A(L) B(L) + A(R) B(R) of splitting after each bin, B the blocks of leaf_block triangles
    (the triangle count when leaf_block is 1); inf where a side would be empty.

    bin_boxes is (6, bins, N) (min xyz, max xyz; an empty bin is the +inf/-inf box), bin_counts (bins, N);
    bin_weights (bins, N): the triangles the binned ones stand for, priced instead of bin_counts where given."""
    bins = bin_counts.shape[0]
    # Running unions from the left (bins 0..k) and from the right (bins k+1..); a Python loop over the few
    # bins is far faster than ufunc.accumulate along a short axis.
    left = np.empty_like(bin_boxes[:, :-1])
    right = np.empty_like(bin_boxes[:, :-1])
    left[:, 0] = bin_boxes[:, 0]
    right[:, -1] = bin_boxes[:, -1]
    for k in range(1, bins - 1):
        _union(left[:, k - 1], bin_boxes[:, k], out=left[:, k])
        _union(right[:, -k], bin_boxes[:, -k - 1], out=right[:, -k - 1])
    left_count = np.cumsum(bin_counts, axis=0)[:-1]
    right_count = bin_counts.sum(axis=0) - left_count
    left_priced, right_priced = left_count, right_count
    if bin_weights is not None:
        left_priced = np.cumsum(bin_weights, axis=0)[:-1]
        right_priced = np.maximum(bin_weights.sum(axis=0) - left_priced, 0.0)
    with np.errstate(invalid="ignore"):
        cost = _row_box_areas(left) * _blocks(left_priced, leaf_block) + _row_box_areas(right) * _blocks(
            right_priced, leaf_block
        )
    return np.where((left_count > 0) & (right_count > 0), cost, np.inf)


def _blocks(counts: np.ndarray, leaf_block: int) -> np.ndarray:
    """Blocks of leaf_block triangles that `counts` triangles fill (the counts themselves for leaf_block 1)."""
    return counts if leaf_block == 1 else -(-counts // leaf_block)


def _union(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """Union of boxes stored as (6, ...) rows: min xyz then max xyz."""
    np.minimum(a[:3], b[:3], out=out[:3])
    np.maximum(a[3:], b[3:], out=out[3:])


def _row_box_areas(boxes: np.ndarray) -> np.ndarray:
    """Surface areas (float64) of boxes stored as (6, ...) rows; the empty box gives +inf."""
    x, y, z = (boxes[3:] - boxes[:3]).astype(np.float64)
    return 2.0 * (x * y + y * z + z * x)


def _emit_leaves(
    level: _Level, starts: np.ndarray, node_of_triangle: np.ndarray, is_leaf: np.ndarray, prim_order: np.ndarray
) -> None:
    """Write the triangles of this level's leaves into their prim_order slots."""
    in_leaf = is_leaf[node_of_triangle]
    if not in_leaf.any():
        return
    triangles = np.flatnonzero(in_leaf)
    nodes = node_of_triangle[triangles]
    slots = level.slot_offsets[nodes] + (triangles - starts[nodes])
    prim_order[slots] = level.triangle_ids[triangles]


def _triangle_sides(
    level: _Level, starts: np.ndarray, node_of_triangle: np.ndarray, splits: _LevelSplits, bins: int
) -> tuple[np.ndarray, np.ndarray]:
    """(goes_right, rights): for each triangle, whether it goes to the right child of its node (meaningless for
    leaves), and how many go right in each node."""
    counts, plan = level.counts, splits.plan
    nodes = np.arange(counts.size)
    # A centroid c is in a bin after last_left_bin when (c - origin) * scale >= last_left_bin + 1, i.e. when c is
    # at least the plane's position rounded up to float32. Comparing lo + hi (= 2c exactly) with twice that on all
    # three axes, the two others' planes at +inf, takes a few passes over 4-byte arrays per triangle.
    with np.errstate(divide="ignore", invalid="ignore"):
        plane = splits.bin_origin[nodes, plan.axis] + (plan.last_left_bin + 1) / splits.bin_scale[nodes, plan.axis]
    plane_up = plane.astype(np.float32)
    plane_up = np.where(plane_up < plane, np.nextafter(plane_up, np.float32(np.inf)), plane_up)
    twice_plane = np.full((3, counts.size), np.inf, np.float32)
    splitting = splits.is_split & ~splits.use_median
    twice_plane[plan.axis[splitting], nodes[splitting]] = 2 * plane_up[splitting]
    goes_right = np.zeros(node_of_triangle.size, bool)
    for axis in range(3):
        goes_right |= (level.boxes[axis] + level.boxes[axis + 3]) >= np.repeat(twice_plane[axis], counts)

    # A triangle exactly on the plane, rounded the other way, could leave a side empty: those nodes, and the ones
    # binning could not split, are halved in Morton order.
    rights = np.add.reduceat(goes_right, starts, dtype=np.int64)
    halve = splits.is_split & (splits.use_median | (rights == 0) | (rights == counts))
    median_triangles = np.flatnonzero(np.repeat(halve, counts))
    median_nodes = node_of_triangle[median_triangles]
    goes_right[median_triangles] = (median_triangles - starts[median_nodes]) >= counts[median_nodes] // 2
    if halve.any():
        rights[halve] = counts[halve] - counts[halve] // 2
    return goes_right, rights


def _partition(
    level: _Level, is_split: np.ndarray, goes_right: np.ndarray, right_counts: np.ndarray, left_tree_index: np.ndarray
) -> _Level:
    """The next level: the split nodes' triangles in one stable partition, every node's left-goers in node order,
    then every node's right-goers, so the children come as all left children, then all right children.
    left_tree_index: the place of each split node's left child in the next level of the tree."""
    split_nodes = np.flatnonzero(is_split)
    right_counts = right_counts[split_nodes]
    left_counts = level.counts[split_nodes] - right_counts
    if not (np.all(left_counts > 0) and np.all(right_counts > 0)):  # every split leaves triangles on both sides
        raise RuntimeError("BVH build produced an empty child")
    in_split = np.repeat(is_split, level.counts)
    source = np.concatenate([np.flatnonzero(in_split & ~goes_right), np.flatnonzero(in_split & goes_right)])
    parent_slots = level.slot_offsets[split_nodes]
    return _Level(
        triangle_ids=level.triangle_ids[source],
        boxes=_take_columns(level.boxes, source),
        counts=np.concatenate([left_counts, right_counts]),
        slot_offsets=np.concatenate([parent_slots, parent_slots + left_counts]),
        tree_index=np.concatenate([left_tree_index, left_tree_index + 1]),
    )


def _take_columns(rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """rows[:, columns], one contiguous row at a time (several times faster than 2-D fancy indexing)."""
    gathered = np.empty((rows.shape[0], columns.size), dtype=rows.dtype)
    for row, out in zip(rows, gathered):
        np.take(row, columns, out=out)
    return gathered
