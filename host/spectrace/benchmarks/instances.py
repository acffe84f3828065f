"""`spectrace bench instances`: what instancing saves. One object (a bumpy height-field patch of about `triangles`
triangles) placed `count` times on a grid with seeded turns, rendered with the object stored once under the
two-level BVH (kernels/scene.cl, "Instances") and, unless skipped, with the instances expanded into transformed
copies: the scene's device memory (every scene buffer), the set-up (BVH builds, upload, kernel build) and the
samples per second of a warm render, timed around the kernel passes as `bench scaling` does. Both images are the
same scene's: their mean luminance is reported as a check that the two estimate the same picture."""

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from spectrace.device import open_device
from spectrace.engine.memory import scene_arrays
from spectrace.engine.renderer import Renderer
from spectrace.geometry.mesh import TriangleMesh
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.lights.constant import ConstantEnvironment
from spectrace.lights.distant import DistantLight
from spectrace.materials import MATERIALS
from spectrace.scene.model import Camera, Instance, InstancedObject, Scene, Shape
from spectrace.spectral.spectrum import Spectrum


def height_field(triangles: int, seed: int = 1) -> TriangleMesh:
    """A 0.8 x 0.8 patch in the xz plane with sine bumps and a little noise: 2 n² triangles, n = √(triangles / 2)."""
    n = max(1, round(np.sqrt(triangles / 2)))
    x, z = np.meshgrid(np.linspace(-0.4, 0.4, n + 1), np.linspace(-0.4, 0.4, n + 1))
    y = 0.05 * np.sin(25 * x) * np.cos(19 * z) + 0.01 * np.random.default_rng(seed).standard_normal(x.shape)
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = index[:-1, :-1].ravel(), index[:-1, 1:].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel()
    faces = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])
    return TriangleMesh(np.stack([x.ravel(), y.ravel(), z.ravel()], 1), faces)


def instanced_scene(count: int, triangles: int, size: int, spp: int, max_depth: int) -> Scene:
    """The object placed `count` times on a square grid (0.9 apart), each turned about y and lifted a little."""
    rng = np.random.default_rng(7)
    material = MATERIALS["diffuse"].make((0.5, 0.4, 0.3))
    obj = InstancedObject(shapes=[Shape(mesh=height_field(triangles), material=material, name="patch")], name="patch")
    side = int(np.ceil(np.sqrt(count)))
    instances = []
    for i in range(count):
        steps: list[dict] = [
            {"rotate": {"axis": [0, 1, 0], "angle": float(rng.uniform(0, 360))}},
            {
                "translate": [
                    0.9 * (i % side - (side - 1) / 2),
                    float(rng.uniform(0, 0.3)),
                    0.9 * (i // side - (side - 1) / 2),
                ]
            },
        ]
        instances.append(Instance(object=obj, to_world=transform_matrix(steps, "transform"), name=f"patch{i}"))
    return Scene(
        camera=Camera(origin=(0.0, 0.6 * side + 1.0, -0.9 * side - 0.5), target=(0.0, 0.0, 0.0)),
        width=size,
        height=size,
        spp=spp,
        max_depth=max_depth,
        shapes=[],
        lights=[
            DistantLight(direction=(0.3, -1.0, 0.4), irradiance=Spectrum.constant(2.0)),
            ConstantEnvironment(Spectrum.constant(0.1)),
        ],
        instances=instances,
    )


def expanded(scene: Scene) -> Scene:
    """The same scene with every instance a transformed copy of the object's shapes."""
    copies = [
        Shape(mesh=apply_transform(shape.mesh, instance.to_world), material=shape.material, name=shape.name)
        for instance in scene.instances
        for shape in instance.object.shapes
    ]
    return replace(scene, shapes=[*scene.shapes, *copies], instances=[])


def _measure(scene: Scene, device, spp: int) -> dict:
    started = time.perf_counter()
    renderer = Renderer(scene, device)
    setup = time.perf_counter() - started
    renderer.run_pass(1)
    renderer.reset()
    image = renderer.render(spp=spp)
    buffers = renderer.buffers
    return {
        "stored_triangles": buffers.triangle_count + buffers.instanced_triangle_count,
        "placed_triangles": buffers.triangle_count
        + sum(len(s.mesh.faces) for i in scene.instances for s in i.object.shapes),
        "scene_device_bytes": int(sum(a.nbytes for a in scene_arrays(buffers).values())),
        "setup_seconds": setup,
        "bvh_seconds": buffers.bvh_seconds,
        "samples_per_second": scene.width * scene.height * image.spp / image.render_seconds,
        "mean_y": float(image.xyz[..., 1].mean()),
    }


def run_instances_bench(
    count: int,
    triangles: int,
    size: int,
    spp: int,
    max_depth: int,
    device_key: str | None,
    with_expanded: bool = True,
    log: Callable[[str], None] = lambda text: None,
) -> dict:
    device = open_device(device_key)
    scene = instanced_scene(count, triangles, size, spp, max_depth)
    result: dict = {"runtime": device.report.key, "count": count, "size": size, "spp": spp, "max_depth": max_depth}
    result["instanced"] = _measure(scene, device, spp)
    log(f"instanced: {result['instanced']['samples_per_second'] / 1e6:.3f} M samples/s")
    if with_expanded:
        result["expanded"] = _measure(expanded(scene), device, spp)
        log(f"expanded: {result['expanded']['samples_per_second'] / 1e6:.3f} M samples/s")
    return result


def instances_tables(result: dict) -> list:
    from rich.table import Table

    table = Table(
        title=f"instancing: {result['count']} instances ({result['runtime']}, {result['size']}², {result['spp']} spp, "
        f"max_depth {result['max_depth']})"
    )
    for column in (
        "scene",
        "triangles placed",
        "stored",
        "scene device MiB",
        "set-up s",
        "BVH s",
        "M samples/s",
        "mean Y",
    ):
        table.add_column(column, justify="right")
    for name in ("instanced", "expanded"):
        if name in result:
            r = result[name]
            table.add_row(
                name,
                f"{r['placed_triangles']:,}",
                f"{r['stored_triangles']:,}",
                f"{r['scene_device_bytes'] / 2**20:.1f}",
                f"{r['setup_seconds']:.1f}",
                f"{r['bvh_seconds']:.1f}",
                f"{r['samples_per_second'] / 1e6:.3f}",
                f"{r['mean_y']:.5f}",
            )
    return [table]
