"""Instancing (kernels/scene.cl, "Instances"): an object's triangles stored once under their own BVH, placed by
instances through a top-level BVH, must be seen exactly as the same scene with the instances expanded into
transformed copies (what the host's transforms give, spectrace.geometry.transforms.apply_transform): the same
surfaces at the same distances as a brute-force intersection of the transformed triangles, the same points, normals,
texture coordinates and materials, the same occlusion; and the object's triangles are stored once however many
instances place it."""

import functools
from dataclasses import replace

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree
from spectrace.core.contract import SCENE_KERNEL_BUFFERS
from spectrace.engine.renderer import Renderer, upload_scene
from spectrace.engine.scene_buffers import build_scene_buffers, render_params
from spectrace.geometry import bvh4
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene.model import Shape

# Placements covering what an affine map can do to a surface: a move, a rotation, a non-uniform scale (normals need
# the inverse transpose), a shear and a mirror (which reverses the expanded copy's winding).
PLACEMENTS = [
    [{"translate": [-1.2, 0.0, 0.0]}],
    [{"rotate": {"axis": [0, 1, 0], "angle": 40}}, {"translate": [1.0, 0.0, 0.4]}],
    [{"scale": [1.4, 0.6, 1.0]}, {"rotate": {"axis": [1, 1, 0], "angle": 25}}, {"translate": [0.0, 0.3, 1.2]}],
    [{"matrix": [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0.3, 1, 0], [0, 0, 0, 1]]}, {"translate": [0.2, 0.1, -1.0]}],
    [{"matrix": [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}, {"translate": [-0.6, 0.8, -0.3]}],
]


def _object_shapes() -> list[Shape]:
    """A smooth, bump-mapped tessellated sphere, a textured cube and a gold rectangle, in object space."""
    rng = np.random.default_rng(11)
    return [
        spectrace.shape(
            "sphere",
            spectrace.plastic(
                (0.7, 0.3, 0.2), roughness=0.2, bump_map=spectrace.bitmap(rng.uniform(0, 1, (8, 8))), bump_scale=0.02
            ),
            tessellated=True,
            transform=[{"scale": 0.4}, {"translate": [0, 0.4, 0]}],
            name="ball",
        ),
        spectrace.shape(
            "cube",
            spectrace.diffuse(spectrace.bitmap(rng.uniform(0, 1, (4, 4, 3)))),
            transform=[{"scale": 0.15}, {"translate": [0.5, 0.2, 0.1]}],
            name="box",
        ),
        spectrace.shape(
            "rectangle",
            spectrace.conductor("Au", roughness=0.3),
            transform=[{"scale": [0.3, 0.2, 1]}, {"translate": [-0.4, 0.3, 0.2]}],
            name="card",
        ),
    ]


def _scenes(placements=PLACEMENTS) -> tuple[spectrace.Scene, spectrace.Scene]:
    """(the scene with instances, the same scene with them expanded into transformed copies)."""
    shapes = _object_shapes()
    obj = spectrace.instanced_object(shapes, name="still life")
    ground = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.5),
        transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 3}],
        name="ground",
    )
    light = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(10.0),
        transform=[{"scale": 0.6}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 3, 0]}],
        name="light",
    )
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 2.5, -4.0), target=(0.0, 0.3, 0.0)),
        width=24,
        height=24,
        spp=4,
        shapes=[ground, light],
        instances=[spectrace.instance(obj, steps) for steps in placements],
    )
    copies = [
        Shape(mesh=apply_transform(s.mesh, transform_matrix(steps, "transform")), material=s.material, name=s.name)
        for steps in placements
        for s in shapes
    ]
    return scene, replace(scene, shapes=[ground, light, *copies], instances=[])


def _rays(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Rays from a shell around the scene toward random points within it."""
    rng = np.random.default_rng(seed)
    origins = rng.normal(size=(count, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True) + [0, 1, 0]
    targets = rng.uniform([-1.8, -0.2, -1.5], [1.8, 1.5, 1.8], (count, 3))
    directions = targets - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return origins, directions


def _trace(kernel_runner, scene, origins, directions, t_max, width=None):
    buffers = build_scene_buffers(scene)
    # The kernels built for every scene (one program per traversal width, whatever the scene), as the renders in the
    # suite use; that a scene's own kernels give the same bits is tests/scene/test_scene_features.py's.
    runner = kernel_runner("testing/scene_hits.cl", traversal_defines(width))
    n = len(origins)
    params = runner.buffer(render_params(scene, buffers, 0, 1))
    scene_args = upload_scene(runner.device.context, buffers)
    assert len(scene_args) == len(SCENE_KERNEL_BUFFERS)
    out = [np.zeros((n, 4), np.float32) for _ in range(4)] + [np.zeros(n, np.int32)]
    four = lambda a: np.concatenate([a, np.zeros((n, 1))], axis=1).astype(np.float32)  # noqa: E731
    args = [
        params,
        *scene_args,
        runner.buffer(four(origins)),
        runner.buffer(four(directions)),
        runner.buffer(t_max.astype(np.float32)),
    ]
    first_out = len(args)
    args += [runner.buffer(o, True) for o in out] + [np.int32(n)]
    runner.run("scene_hits", n, args, {first_out + k: o for k, o in enumerate(out)})
    return buffers, out


def _brute_force(scene: spectrace.Scene, origins: np.ndarray, directions: np.ndarray):
    """Closest hit distance and unit geometric normal (the winding's front) of each ray over every triangle of the
    expanded scene, Möller–Trumbore in float64. Each shape's triangles are tried only on the rays that meet its
    bounding box (a slab test, the box padded): most rays pass far from most copies, so this skips most pairs
    without choosing among the triangles by anything but the distance."""
    best_t = np.full(len(origins), np.inf)
    best_n = np.zeros((len(origins), 3))
    for shape in scene.shapes:
        v0, v1, v2 = shape.mesh.triangles()
        corners = np.concatenate([v0, v1, v2])
        pad = 1e-6 * (1.0 + np.abs(corners).max())
        low, high = corners.min(axis=0) - pad, corners.max(axis=0) + pad
        with np.errstate(divide="ignore", invalid="ignore"):
            near, far = (low - origins) / directions, (high - origins) / directions
        enter = np.minimum(near, far).max(axis=1)
        leave = np.maximum(near, far).min(axis=1)
        rays = np.flatnonzero(~(leave < np.maximum(enter, 0.0)))  # a NaN (a ray in a slab's plane) is tried
        e1, e2 = v1 - v0, v2 - v0
        normals = np.cross(e1, e2)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        for start in range(0, len(rays), 256):
            chosen = rays[start : start + 256]
            o, d = origins[chosen, None, :], directions[chosen, None, :]
            p = np.cross(d, e2[None])
            det = np.einsum("rtk,tk->rt", p, e1)
            with np.errstate(divide="ignore", invalid="ignore"):
                inv = 1.0 / det
                s = o - v0[None]
                u = np.einsum("rtk,rtk->rt", s, p) * inv
                q = np.cross(s, e1[None])
                v = np.einsum("rtk,rtk->rt", np.broadcast_to(d, q.shape), q) * inv
                t = np.einsum("tk,rtk->rt", e2, q) * inv
            ok = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
            t = np.where(ok, t, np.inf)
            k = np.argmin(t, axis=1)
            t = t[np.arange(len(k)), k]
            closer = t < best_t[chosen]  # a tie keeps the earlier shape's triangle, as one argmin over all would
            best_t[chosen[closer]] = t[closer]
            best_n[chosen[closer]] = normals[k[closer]]
    return best_t, best_n


@functools.cache
def _true_hits() -> tuple[np.ndarray, np.ndarray]:
    """The brute-force hits of the traversal test's rays: the same for every traversal, and 10 CPU-s each time."""
    origins, directions = _rays(3000, seed=4)
    t_true, n_true = _brute_force(_scenes()[1], origins, directions)
    t_true.flags.writeable = n_true.flags.writeable = False  # shared by the parametrisations
    return t_true, n_true


@pytest.mark.parametrize("width", [8, "8q", 4, 2])
def test_instanced_hits_match_brute_force_and_the_expanded_copies(kernel_runner, monkeypatch, width):
    """Through every traversal (the 8-wide default, its quantised nodes ("8q"), the 4-wide and binary ones kept for
    comparison), whose node buffers the objects' leaves point into differently."""
    monkeypatch.setattr(bvh4, "QUANTISED_NODES", width == "8q")
    width = 8 if width == "8q" else width
    monkeypatch.setattr(bvh4, "TRAVERSAL_WIDTH", width)
    instanced, expanded = _scenes()
    origins, directions = _rays(3000, seed=4)
    t_true, n_true = _true_hits()
    assert np.isfinite(t_true).mean() > 0.5  # most rays meet something
    # Any-hit queries just short of the true hit see nothing, just past it see it.
    t_max = np.where(np.isfinite(t_true), t_true, 10.0)
    results = {}
    for name, scene in (("instanced", instanced), ("expanded", expanded)):
        short = _trace(kernel_runner, scene, origins, directions, t_max * 0.999, width)[1][4]
        buffers, (hit, point, normal, shading, past) = _trace(
            kernel_runner, scene, origins, directions, t_max * 1.001, width
        )
        results[name] = (hit, point, normal, shading)
        t = hit[:, 0].astype(np.float64)
        # Rays through an edge or a vertex may slip between float32 triangles in either: a handful at most.
        agree = np.isfinite(t) == np.isfinite(t_true)
        assert agree.mean() > 0.998, name
        both = agree & np.isfinite(t_true)
        np.testing.assert_allclose(t[both], t_true[both], rtol=2e-4, err_msg=name)
        facing = np.abs(np.sum(normal[both, :3] * n_true[both], axis=1))
        assert np.quantile(facing, 0.001) > 0.9999, name  # |cos| of the kernel's and the true face normal
        assert np.mean(np.sum(normal[both, :3] * n_true[both], axis=1) > 0) > 0.998, name  # same front
        np.testing.assert_allclose(point[both, :3], origins[both] + t_true[both, None] * directions[both], atol=2e-4)
        assert np.mean(short[np.isfinite(t_true)] == 0) > 0.998 and np.mean(past[np.isfinite(t_true)] == 1) > 0.998
        assert not np.any(past[~np.isfinite(t_true)]), name
    inst, exp = results["instanced"], results["expanded"]
    both = np.isfinite(inst[0][:, 0]) & np.isfinite(exp[0][:, 0])
    same_surface = np.abs(inst[0][both, 0] - exp[0][both, 0]) < 1e-4 * exp[0][both, 0]
    assert same_surface.mean() > 0.998
    sel = np.flatnonzero(both)[same_surface]
    np.testing.assert_array_equal(inst[0][sel, 3], exp[0][sel, 3])  # materials
    np.testing.assert_allclose(inst[0][sel, 1:3], exp[0][sel, 1:3], atol=1e-3)  # texture coordinates
    np.testing.assert_allclose(inst[2][sel, :3], exp[2][sel, :3], atol=1e-4)  # geometric normals
    # Shading normals: an instance interpolates the object's corner normals and then applies M⁻ᵀ (as pbrt-v4 takes an
    # instance's interaction to world space); a copy interpolates its corners' normals, each already turned by M⁻ᵀ
    # and normalised. Under a non-uniform scale the two weigh the corners a little differently.
    np.testing.assert_allclose(inst[3][sel, :3], exp[3][sel, :3], atol=5e-3)
    assert np.unique(inst[0][sel, 3]).size == 5  # every material of the object and the ground were hit


@pytest.mark.slow
def test_an_object_is_stored_once_however_many_instances_place_it():
    few = build_scene_buffers(_scenes(PLACEMENTS[:2])[0])
    many, expanded = (build_scene_buffers(scene) for scene in _scenes(PLACEMENTS * 20))
    object_triangles = sum(len(s.mesh.faces) for s in _object_shapes())
    assert few.instanced_triangle_count == many.instanced_triangle_count == object_triangles
    for name in ("triangle_vertices", "triangle_uvs", "triangle_normals", "triangle_info", "materials"):
        assert getattr(few, name).nbytes == getattr(many, name).nbytes, name
    # What 98 more instances add: their rows and the top-level BVH's nodes, far less than one copy of the object.
    growth = sum(many.__dict__[k].nbytes - few.__dict__[k].nbytes for k in ("instances", "instance_nodes"))
    assert growth <= 98 * (112 + 2 * 32)
    copies = expanded.triangle_vertices.nbytes - many.triangle_vertices.nbytes
    assert copies >= (len(PLACEMENTS) * 20 - 1) * object_triangles * 48


@pytest.mark.slow
def test_instanced_scene_renders_the_expanded_scenes_image(device):
    """Independent replicates (seeds) of both renders: every 6 x 6 block's mean XYZ agrees within 5 standard errors
    of the difference."""
    instanced, expanded = _scenes()
    replicas = {}
    for name, scene in (("instanced", instanced), ("expanded", expanded)):
        # One renderer per scene: a new seed uploads nothing, and the seeds' images are fresh renderers' bits.
        renderer = Renderer(scene, device)
        images = []
        for s in range(8):
            seeded = scene.with_overrides(seed=s + (100 if name == "expanded" else 0))
            renderer.replace_scene(seeded, renderer.buffers, ())
            images.append(renderer.render().xyz)
        replicas[name] = np.stack(images)
    assert replicas["instanced"][..., 1].mean() > 0
    assert_replicas_agree(replicas["instanced"], replicas["expanded"], block=6)
