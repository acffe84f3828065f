"""Flatten a resolved Scene into the arrays the kernels read (layouts in kernels/types.h)."""

from dataclasses import dataclass

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.bvh import BVH, build_bvh
from spectrace.render.device_types import (
    LIGHT_DTYPE,
    MATERIAL_DIFFUSE,
    MATERIAL_DTYPE,
    RENDER_PARAMS_DTYPE,
    TRIANGLE_INFO_DTYPE,
)
from spectrace.scene.model import Scene
from spectrace.spectral.colorimetry import cmf_table_normalised
from spectrace.spectral.table import SpectrumTable


@dataclass
class SceneBuffers:
    bvh: BVH
    triangle_vertices: np.ndarray  # (3·M, 4) float32, BVH leaf order
    triangle_info: np.ndarray  # (M,) TRIANGLE_INFO_DTYPE
    materials: np.ndarray  # MATERIAL_DTYPE
    lights: np.ndarray  # LIGHT_DTYPE
    light_cdf: np.ndarray  # (L + 1,) float32
    spectra: np.ndarray  # float32 table
    cmf: np.ndarray  # (471, 4) float32: x̄, ȳ, z̄ / ∫ȳ

    @property
    def triangle_count(self) -> int:
        return len(self.triangle_info)

    def device_bytes(self) -> int:
        arrays = (self.bvh.nodes, self.triangle_vertices, self.triangle_info, self.materials, self.lights,
                  self.light_cdf, self.spectra, self.cmf)
        return sum(a.nbytes for a in arrays)


def build_scene_buffers(scene: Scene) -> SceneBuffers:
    table = SpectrumTable()
    material_index: dict[int, int] = {}
    material_rows = []
    v0s, v1s, v2s, tri_material, tri_emitter = [], [], [], [], []
    emitters = []
    for shape in scene.shapes:
        key = id(shape.material)
        if key not in material_index:
            material_index[key] = len(material_rows)
            material_rows.append((MATERIAL_DIFFUSE, table.add(shape.material.reflectance), 0, 0))
        v0, v1, v2 = shape.mesh.triangles()
        v0s.append(v0), v1s.append(v1), v2s.append(v2)
        tri_material.append(np.full(len(v0), material_index[key], np.int32))
        emitter_id = -1
        if shape.emitter is not None:
            emitter_id = len(emitters)
            emitters.append(shape.emitter)
        tri_emitter.append(np.full(len(v0), emitter_id, np.int32))
    v0, v1, v2 = (np.concatenate(a) for a in (v0s, v1s, v2s))
    if len(v0) == 0:
        raise SpectraceError("the scene has no triangles")
    tri_material = np.concatenate(tri_material)
    tri_emitter = np.concatenate(tri_emitter)

    bvh = build_bvh(v0, v1, v2)
    order = bvh.prim_order
    v0, v1, v2 = v0[order], v1[order], v2[order]
    tri_material, tri_emitter = tri_material[order], tri_emitter[order]

    vertices = np.zeros((len(v0), 3, 4), np.float32)
    vertices[:, 0, :3], vertices[:, 1, :3], vertices[:, 2, :3] = v0, v1, v2

    areas = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    emitting = np.flatnonzero((tri_emitter >= 0) & (areas > 0))
    lights = np.zeros(len(emitting), LIGHT_DTYPE)
    emitter_offsets = [table.add(e.radiance) for e in emitters]
    # Next-event estimation picks a triangle in proportion to the power it emits (area x mean radiance x sides),
    # so bright large lights get most samples; any positive weights would be unbiased.
    power = np.zeros(len(emitting))
    for j, t in enumerate(emitting):
        e = emitters[tri_emitter[t]]
        lights[j] = (t, emitter_offsets[tri_emitter[t]], 1.0, 0.0, areas[t], int(e.two_sided), 0, 0)
        power[j] = areas[t] * max(float(e.radiance.values.mean()), 0.0) * (2.0 if e.two_sided else 1.0)
    light_index = np.full(len(v0), -1, np.int32)
    if len(emitting):
        if power.sum() <= 0:
            power[:] = areas[emitting]
        pmf = power / power.sum()
        lights["pmf"] = pmf
        light_index[emitting] = np.arange(len(emitting), dtype=np.int32)
        cdf = np.concatenate([[0.0], np.cumsum(pmf)])
        cdf[-1] = 1.0
    else:
        cdf = np.array([0.0, 1.0])
    triangle_info = np.zeros(len(v0), TRIANGLE_INFO_DTYPE)
    triangle_info["material"] = tri_material
    triangle_info["light"] = light_index

    cmf = np.zeros((cmf_table_normalised().shape[0], 4), np.float32)
    cmf[:, :3] = cmf_table_normalised()
    materials = np.array(material_rows, MATERIAL_DTYPE) if material_rows else np.zeros(1, MATERIAL_DTYPE)
    return SceneBuffers(
        bvh=bvh,
        triangle_vertices=vertices.reshape(-1, 4),
        triangle_info=triangle_info,
        materials=materials,
        lights=lights if len(lights) else np.zeros(1, LIGHT_DTYPE),
        light_cdf=cdf.astype(np.float32),
        spectra=table.data,
        cmf=cmf,
    )


def render_params(scene: Scene, light_count: int, sample_begin: int, sample_count: int) -> np.ndarray:
    origin, forward, right, up = scene.camera.basis(scene.width / scene.height)
    params = np.zeros(1, RENDER_PARAMS_DTYPE)
    params["camera_origin"][0, :3] = origin
    params["camera_forward"][0, :3] = forward
    params["camera_right"][0, :3] = right
    params["camera_up"][0, :3] = up
    params["width"], params["height"] = scene.width, scene.height
    params["max_depth"], params["rr_depth"] = scene.max_depth, scene.rr_depth
    params["light_count"] = light_count
    params["seed"] = scene.seed
    params["sample_begin"], params["sample_count"] = sample_begin, sample_count
    return params
