"""The OpenCL BVH traversal and watertight triangle test against a float64 brute force over every triangle."""

import numpy as np
import pytest

from raytracing_reference import brute_force_closest_hit
from spectrace.geometry.bvh import build_bvh
from spectrace.geometry.bvh4 import device_nodes, traversal_defines

# Every traversal: the binary tree, its 4- and 8-wide collapses, and the 8-wide one with quantised child boxes
# ("8q") (geometry/bvh4.py).
WIDTHS = [2, 4, 8, "8q"]


def _soup(rng, count):
    centres = rng.uniform(-1, 1, (count, 1, 3))
    return centres + rng.normal(0, 0.08, (count, 3, 3))


def _rays(rng, count, triangles):
    """Half the rays aim at a random point of a random triangle (so they hit something), half anywhere."""
    origins = rng.uniform(-1.5, 1.5, (count, 3))
    targets = rng.uniform(-0.8, 0.8, (count, 3))
    aimed = rng.random(count) < 0.5
    picked = triangles[rng.integers(0, len(triangles), aimed.sum())]
    weights = rng.dirichlet(np.ones(3), aimed.sum())[:, :, None]
    targets[aimed] = (weights * picked).sum(axis=1)
    directions = targets - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return origins, directions


def _as_float4(a):
    out = np.zeros((len(a), 4), np.float32)
    out[:, :3] = a
    return out


def _device_scene(triangles, max_leaf_size=4):
    bvh = build_bvh(triangles[:, 0], triangles[:, 1], triangles[:, 2], max_leaf_size=max_leaf_size)
    ordered = triangles[bvh.prim_order].astype(np.float32)
    vertices = np.zeros((len(ordered), 3, 4), np.float32)
    vertices[..., :3] = ordered
    return bvh, vertices.reshape(-1, 4)


def _trace(kernel_runner, kernel, width, bvh, vertices, origins, directions, read=(), written=()):
    """Run `kernel` of the traversal test program over the rays; its arguments after the scene and the rays are
    `read` then `written`, and the `written` arrays are filled in."""
    width, quantised = (8, True) if width == "8q" else (width, False)
    runner = kernel_runner("testing/closest_hit.cl", traversal_defines(width, quantised))
    nodes = device_nodes(bvh, vertices, width, quantised)
    inputs = [nodes, vertices, _as_float4(origins), _as_float4(directions), *read]
    args = [runner.buffer(a) for a in inputs] + [runner.buffer(a, True) for a in written]
    runner.run(kernel, len(origins), [*args, np.int32(len(origins))], dict(enumerate(written, len(inputs))))


def _closest_hits(kernel_runner, width, bvh, vertices, origins, directions):
    """The distance and (BVH-order) triangle index of each ray's closest hit; -1 for a miss."""
    t = np.empty(len(origins), np.float32)
    hit = np.empty(len(origins), np.int32)
    _trace(kernel_runner, "closest_hit", width, bvh, vertices, origins, directions, written=[t, hit])
    return t, hit


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("triangle_count, max_leaf_size", [(1, 4), (7, 4), (3000, 4), (3000, 16)])
def test_closest_hits_equal_brute_force(kernel_runner, triangle_count, max_leaf_size, width):
    """Leaves of up to 16 triangles take several four-triangle blocks in the 4-wide layout (triangle_blocks.py)."""
    rng = np.random.default_rng(triangle_count)
    # Snap to float32 first so the kernel and the reference see the same triangles and rays.
    triangles = _soup(rng, triangle_count).astype(np.float32).astype(np.float64)
    origins, directions = (a.astype(np.float32).astype(np.float64) for a in _rays(rng, 4000, triangles))
    bvh, vertices = _device_scene(triangles, max_leaf_size)
    if max_leaf_size > 4:
        assert bvh.nodes["count"].max() > 8, "the big-leaf case must chain three or more blocks"

    t, hit = _closest_hits(kernel_runner, width, bvh, vertices, origins, directions)

    ref_t, ref_prim = brute_force_closest_hit(origins, directions, triangles[:, 0], triangles[:, 1], triangles[:, 2])
    kernel_prim = np.where(hit >= 0, bvh.prim_order[np.maximum(hit, 0)], -1)
    ref_hit = ref_prim >= 0
    assert ref_hit.sum() > 0.4 * len(origins), "the aimed rays should hit"
    # Float32 cannot resolve rays that graze a triangle (|cos| ~ 1e-4): there hit/miss and t may differ from the
    # float64 reference. Every other ray must agree.
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    hit_triangle = np.where(ref_hit, ref_prim, kernel_prim)
    cosine = np.abs(np.einsum("ij,ij->i", normals[np.maximum(hit_triangle, 0)], directions))
    clear = (hit_triangle < 0) | (cosine > 1e-2)
    assert clear.mean() > 0.97
    assert np.array_equal((hit >= 0)[clear], ref_hit[clear])
    both = clear & ref_hit
    np.testing.assert_allclose(t[both], ref_t[both], rtol=1e-4, atol=1e-5)
    # Ties between triangles at (nearly) the same distance may pick either.
    assert np.mean(kernel_prim[both] == ref_prim[both]) > 0.995


@pytest.mark.parametrize("width", WIDTHS)
def test_shared_edges_are_watertight(kernel_runner, width):
    """Rays aimed exactly at the shared edges and vertices of a tessellated square never slip through."""
    n = 16
    xs = np.linspace(-1, 1, n + 1)
    grid = np.stack(np.meshgrid(xs, xs, indexing="ij"), -1)
    quads = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = grid[i, j], grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1]
            quads += [(a, b, c), (a, c, d)]
    tri2 = np.array(quads)
    triangles = np.concatenate([tri2, np.zeros(tri2.shape[:2] + (1,))], axis=-1)
    bvh, vertices = _device_scene(triangles)
    targets = np.stack(np.meshgrid(xs[1:-1], xs[1:-1], indexing="ij"), -1).reshape(-1, 2)
    targets = np.concatenate([targets, (targets[:-1] + targets[1:]) / 2])  # vertices and edge midpoints
    origins = np.column_stack([targets * 0.3, np.full(len(targets), 2.0)])
    directions = np.column_stack([targets, np.zeros(len(targets))]) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)

    t, hit = _closest_hits(kernel_runner, width, bvh, vertices, origins, directions)
    assert np.all(hit >= 0), f"{np.sum(hit < 0)} rays slipped through shared edges"


@pytest.mark.parametrize("width", WIDTHS)
def test_any_hit_respects_t_max(kernel_runner, width):
    rng = np.random.default_rng(5)
    triangles = _soup(rng, 500).astype(np.float32).astype(np.float64)
    origins, directions = (a.astype(np.float32).astype(np.float64) for a in _rays(rng, 2000, triangles))
    bvh, vertices = _device_scene(triangles)
    ref_t, _ = brute_force_closest_hit(origins, directions, triangles[:, 0], triangles[:, 1], triangles[:, 2])
    t_max = rng.uniform(0.1, 3.0, len(origins)).astype(np.float32)
    # Leave out rays whose closest hit lies within float tolerance of t_max: either answer is right there.
    clear = np.abs(ref_t - t_max) > 1e-3
    occluded = np.empty(len(origins), np.int32)
    _trace(kernel_runner, "any_hit", width, bvh, vertices, origins, directions, [t_max], [occluded])
    expected = ref_t < t_max
    assert 0.1 < expected.mean() < 0.9
    assert np.array_equal(occluded[clear].astype(bool), expected[clear])
