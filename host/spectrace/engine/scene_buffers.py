"""Flatten a resolved Scene into the arrays the kernels read (layouts in kernels/types.h)."""

import tracemalloc
from collections.abc import Callable
from dataclasses import dataclass, field
from time import perf_counter
from typing import Any, TypeVar

import numpy as np

from spectrace.core.contract import (
    ANALYTIC_SHAPE_DTYPE,
    HIDE_AREA_EMITTERS,
    HIDE_ENVIRONMENT,
    INSTANCE_DTYPE,
    LIGHT_DTYPE,
    MATERIAL_DTYPE,
    MEDIUM_DTYPE,
    RENDER_PARAMS_DTYPE,
    TRIANGLE_INFO_DTYPE,
    TRIANGLE_NO_MATERIAL,
)
from spectrace.engine.curve_buffers import curve_segments
from spectrace.engine.glowing_media import glow_table
from spectrace.engine.mesh_attribute_rows import write_attribute_tables
from spectrace.engine.vertex_tangents import corner_tangents, smooth_rows
from spectrace.errors import SpectraceError
from spectrace.geometry.analytic import AnalyticSurface
from spectrace.geometry.bvh import BVH, BVH_NODE_DTYPE, build_bvh
from spectrace.geometry.bvh4 import LEAF_BLOCK, LEAF_SIZE, device_nodes
from spectrace.geometry.curves import CurveSurface
from spectrace.geometry.grid_volume import medium_row
from spectrace.geometry.sdf_grid import append_grid_blocks
from spectrace.integrators import INTEGRATORS
from spectrace.lights import DEVICE_LIGHTS, light_module
from spectrace.lights import area as area_light
from spectrace.lights.area import AreaEmitter
from spectrace.lights.base import LightRows
from spectrace.materials import append_material_rows, uv_material_textures, write_detail
from spectrace.materials.surface import cut_out_problem
from spectrace.scene.model import Instance, InstancedObject, Scene
from spectrace.spectral.colorimetry import cmf_table_normalised
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import TextureRows


@dataclass
class SceneBuffers:
    bvh: BVH
    nodes: (
        np.ndarray
    )  # what the traversal reads: bvh.nodes, or their 4-wide collapse and leaf blocks (geometry/bvh4.py)
    triangle_vertices: np.ndarray  # (3·M, 4) float32, BVH leaf order
    triangle_info: np.ndarray  # (M,) TRIANGLE_INFO_DTYPE
    triangle_count: int  # arrays hold one dummy entry when there are no triangles
    materials: np.ndarray  # MATERIAL_DTYPE
    lights: np.ndarray  # LIGHT_DTYPE
    light_count: int
    environment_light: int  # index into lights, or -1
    light_cdf: np.ndarray  # (L + 1,) float32
    triangle_uvs: np.ndarray  # (3·M, 2) float32 texture coordinates, BVH leaf order
    # (3·S, 4) float32 unit shading normals (x, y, z, 0) at the corners of the S triangles that have vertex normals,
    # in BVH leaf order; a triangle's TriangleInfo.normals is its index here, -1 for flat shading (one dummy entry
    # when no triangle has any); a triangle with file tangents owns the next slot too (engine/vertex_tangents.py)
    triangle_normals: np.ndarray
    texels: np.ndarray  # (n, 4) float32: images of environment maps and textured emitters, after one dummy texel;
    # material textures' texels, addressed in floats (kernels/texture.cl)
    # marginal CDF over rows (H + 1), then each row's CDF (W + 1): see kernels/light_environment_map.cl
    map_cdf: np.ndarray
    spectra: np.ndarray  # float32 table
    cmf: np.ndarray  # (471, 4) float32: x̄, ȳ, z̄ / ∫ȳ
    media: np.ndarray  # MEDIUM_DTYPE (one dummy entry when there are none)
    medium_count: int
    textures: np.ndarray  # TEXTURE_DTYPE (one dummy entry when there are none)
    texture_count: int
    # ANALYTIC_SHAPE_DTYPE (one dummy entry when there are none); shape k's TriangleInfo is entry triangle_count + k
    shapes: np.ndarray = field(default_factory=lambda: np.zeros(1, ANALYTIC_SHAPE_DTYPE))
    shape_count: int = 0
    # BVH_NODE_DTYPE: the binary BVH over the analytic shapes' boxes (kernels/scene.cl intersect_shapes); a root
    # every ray misses when there are none
    shape_nodes: np.ndarray = field(default_factory=lambda: _empty_bvh().nodes)
    # What the acceleration structure cost: wall seconds of the binary build plus the traversal's node buffer
    # (bvh.build_seconds is the first alone), and the most memory the two allocated at once (None when tracemalloc
    # was already tracing something else, whose figures this would disturb).
    bvh_seconds: float = 0.0
    bvh_peak_bytes: int | None = None
    # INSTANCE_DTYPE rows in the top-level BVH's leaf order (one dummy row when there are none); the instanced
    # objects' triangles are stored once each, at the slots after the analytic shapes' (kernels/scene.cl)
    instances: np.ndarray = field(default_factory=lambda: np.zeros(1, INSTANCE_DTYPE))
    instance_count: int = 0
    # float32: the top-level binary BVH (BVH_NODE_DTYPE) over the instances' world boxes, then each object's own
    # node buffer (Instance.nodes is its float4 offset); a root every ray misses when there are none
    instance_nodes: np.ndarray = field(default_factory=lambda: _empty_bvh().nodes.view(np.float32).copy())
    instanced_triangle_count: int = 0  # triangles stored for the instanced objects (each object's once)
    # analytic shapes of the instanced objects (each object's once), in object space: rows shape_count on of
    # `shapes`, TriangleInfo slots triangle_count + row
    instanced_shape_count: int = 0
    # Surfaces without material and without a medium inside (lights seen through, Mitsuba's null bsdf): visibility
    # queries must cross them as they cross media's index-matched boundaries (kernels/scene.cl)
    null_surfaces: bool = False
    # The glowing media's table in `spectra` where light paths start (engine/glowing_media.py), -1: none
    glow_table: int = -1
    # What an edit of the scene's materials, lights or instance placements needs to re-pack those rows alone
    # (spectrace.engine.scene_edits); kept only when asked (build_scene_buffers(keep_packing=True)), never uploaded.
    packing: "ScenePacking | None" = None


@dataclass
class ScenePacking:
    """The build's state that the shading rows and the top level depend on: the spectrum table and texture rows they
    were appended to (so a re-packed row reuses what is unchanged and appends only what is new), the geometry's
    share of the light rows, and the instanced objects (their BVHs, built once)."""

    table: SpectrumTable
    textures: TextureRows
    scene_radius: float
    own_radius: float  # the scene radius of the shapes without the instances
    own_box: tuple[np.ndarray, np.ndarray] | None  # the box of the shapes without the instances (None: no shapes)
    triangle_emitter: np.ndarray  # each triangle's index among the emitting shapes, or -1 (BVH leaf order)
    triangle_areas: np.ndarray
    emitting: np.ndarray  # the emitting triangles, in light row order
    # (emitter index, analytic shape index, surface) of each emitting analytic shape, in light row order
    shape_emitters: list[tuple[int, int, AnalyticSurface]]
    objects: "_ObjectTriangles"
    area_rows: int  # the light rows of the shapes' emitters, which come first
    light_spans: list[tuple[int, int]]  # the light rows [start, end) each of the scene's lights wrote
    light_power: list[float]  # each light row's power estimate, which the rows' pmf is made from


def light_table(rows: list[tuple], power: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """The Light rows with the probability of picking each, and the CDF of those probabilities (float64; one dummy
    row and [0, 1] when there are no lights)."""
    lights = np.array(rows, LIGHT_DTYPE) if rows else np.zeros(1, LIGHT_DTYPE)
    return lights, light_distribution(lights, power)


def light_distribution(lights: np.ndarray, power: list[float]) -> np.ndarray:
    """Sets the probability of picking each of the Light rows `lights` (`pmf`) from the `power` each emits, and
    returns the CDF of those probabilities (float64; [0, 1] when there are no lights)."""
    if not power:
        return np.array([0.0, 1.0])
    # Next-event estimation picks a light in proportion to an estimate of the power it emits (pbrt-v4's
    # power light sampler); any positive weights would be unbiased, these put samples where the light is.
    weights = np.maximum(np.array(power, float), 0.0)
    if weights.sum() <= 0:
        weights[:] = 1.0
    pmf = weights / weights.sum()
    lights["pmf"][: len(power)] = pmf
    cdf = np.concatenate([[0.0], np.cumsum(pmf)])
    cdf[-1] = 1.0
    return cdf


def _radius_with_instances(
    own_radius: float, own_box: tuple[np.ndarray, np.ndarray] | None, instance_boxes: np.ndarray | None
) -> float:
    """The scene radius the lights are placed by: the shapes' own, grown to half the diagonal of the box that also
    holds the instances' world boxes."""
    radius = own_radius
    if instance_boxes is not None:
        lo, hi = instance_boxes[:, 0].min(axis=0), instance_boxes[:, 1].max(axis=0)
        if own_box is not None:
            lo, hi = np.minimum(lo, own_box[0]), np.maximum(hi, own_box[1])
            radius = max(own_radius, 0.5 * float(np.linalg.norm(hi - lo)))
        else:
            radius = 0.5 * float(np.linalg.norm(hi - lo))
    return max(radius, 1e-6)


def _unit_normals(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """(M, 3) unit normals of the winding (v0, v1, v2), computed in float64; zero for a degenerate triangle."""
    n = np.cross(np.asarray(v1, np.float64) - v0, np.asarray(v2, np.float64) - v0)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _corner_normals(parts: list[np.ndarray | None], counts: list[int]) -> np.ndarray | None:
    """(M, 3, 3) corner normals of all shapes' triangles, NaN for the flat shapes'; None when every shape is flat
    (the usual case, which then costs no host memory either)."""
    if all(part is None for part in parts):
        return None
    return np.concatenate([np.full((n, 3, 3), np.nan) if part is None else part for part, n in zip(parts, counts)])


def build_scene_buffers(scene: Scene, keep_packing: bool = False) -> SceneBuffers:
    """The scene's device buffers; `keep_packing`: also keep what re-packing its shading rows and its top level
    takes (SceneBuffers.packing), as a live session does."""
    response = scene.film_response
    # A film range of its own puts every spectrum on the film's grid (refusing those that do not reach it).
    table = (
        SpectrumTable(response.grid_nm, extend_rgb=response.extend_rgb) if response.has_own_grid else SpectrumTable()
    )
    texel_chunks = [np.zeros((1, 4), np.float32)]
    textures = TextureRows(table, texel_chunks)
    material_index: dict[int, int] = {}
    material_rows: list[np.ndarray] = []
    v0s: list[np.ndarray] = []
    v1s: list[np.ndarray] = []
    v2s: list[np.ndarray] = []
    uvs: list[np.ndarray] = []
    normal_parts: list[np.ndarray | None] = []
    tangent_parts: list[np.ndarray | None] = []
    material_parts: list[np.ndarray] = []
    emitter_parts: list[np.ndarray] = []
    interior_parts: list[np.ndarray] = []
    emitters: list[AreaEmitter] = []
    medium_index: dict[int, int] = {}
    medium_rows: list[tuple[int, int, float, int, int]] = []
    # surface (a curve: its segments, engine/curve_buffers.py), material, emitter, interior
    analytic: list[tuple[Any, int, int, int]] = []
    meshed: list[tuple] = []  # (shape, first triangle, count): where mesh attributes are read (mesh_attribute_rows)
    for shape in scene.shapes:
        interior = -1
        if shape.interior is not None:
            interior = medium_index.setdefault(id(shape.interior), len(medium_rows))
            if interior == len(medium_rows):
                medium_rows.append(medium_row(shape.interior, table))
        key = id(shape.material)
        if shape.material is None:
            if shape.interior is None and shape.emitter is None:
                raise SpectraceError(f"shape '{shape.name}' has neither a material nor an interior nor an emitter")
            material_index[key] = TRIANGLE_NO_MATERIAL
        else:
            append_material_rows(shape.material, material_rows, table, textures, material_index)
        if (
            problem := cut_out_problem(shape.material, shape.emitter is not None, shape.interior is not None)
        ) is not None:
            raise SpectraceError(f"shape '{shape.name}': {problem}")
        if shape.material is not None and shape.mesh.uvs is None and uv_material_textures(shape.material):
            raise SpectraceError(
                f"shape '{shape.name}' has no texture coordinates, but its material has a texture "
                f"({', '.join(uv_material_textures(shape.material))})"
            )
        if shape.emitter is not None and shape.emitter.image is not None and shape.mesh.uvs is None:
            raise SpectraceError(f"shape '{shape.name}' has no texture coordinates, but its emitter shows an image")
        emitter_id = -1
        if shape.emitter is not None:
            emitter_id = len(emitters)
            emitters.append(shape.emitter)
        if shape.analytic is not None:
            if isinstance(shape.analytic, CurveSurface) and emitter_id >= 0:
                raise SpectraceError(f"shape '{shape.name}': a curve cannot emit light (give it no emitter)")
            analytic.append((shape.analytic, material_index[key], emitter_id, interior))
            continue
        v0, v1, v2, corner_uvs, corner_normals = shape.mesh.corners()
        meshed.append((shape, sum(len(v) for v in v0s), len(v0)))
        v0s.append(v0)
        v1s.append(v1)
        v2s.append(v2)
        uvs.append(corner_uvs)
        normal_parts.append(corner_normals)
        tangent_parts.append(shape.mesh.corner_tangents())
        material_parts.append(np.full(len(v0), material_index[key], np.int32))
        interior_parts.append(np.full(len(v0), interior, np.int32))
        emitter_parts.append(np.full(len(v0), emitter_id, np.int32))

    if v0s and sum(len(v) for v in v0s):
        v0, v1, v2, uv = (np.concatenate(a) for a in (v0s, v1s, v2s, uvs))
        corner_normals = _corner_normals(normal_parts, [len(v) for v in v0s])
        tangents = corner_tangents(tangent_parts, [len(v) for v in v0s])
        tri_material, tri_emitter = np.concatenate(material_parts), np.concatenate(emitter_parts)
        tri_interior = np.concatenate(interior_parts)
        bvh, bvh_seconds, bvh_peak = _measured(
            lambda: build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK)
        )
        order = bvh.prim_order
        v0, v1, v2, uv = v0[order], v1[order], v2[order], uv[order]
        corner_normals = corner_normals[order] if corner_normals is not None else None
        tangents = tangents[order] if tangents is not None else None
        tri_material, tri_emitter, tri_interior = tri_material[order], tri_emitter[order], tri_interior[order]
        scene_radius = 0.5 * float(np.linalg.norm(bvh.nodes[0]["bmax"] - bvh.nodes[0]["bmin"]))
    else:
        v0 = v1 = v2 = np.zeros((0, 3))
        uv = np.zeros((0, 3, 2))
        corner_normals = tangents = None
        tri_material = tri_emitter = tri_interior = np.zeros(0, np.int32)
        bvh, bvh_seconds, bvh_peak = _empty_bvh(), 0.0, 0
        scene_radius = 1.0
    shape_bvh = _empty_bvh()
    if analytic:
        # The analytic shapes get a BVH of their own over their exact boxes, from the same builder (a box as the
        # triangle (lower, upper, lower) has that box as its bounds); they are stored in its leaf order.
        # A curve is one primitive per segment (geometry/curves.py).
        analytic = curve_segments(analytic)
        boxes = np.array([surface.bounds() for surface, *_ in analytic])
        shape_bvh = build_bvh(boxes[:, 0], boxes[:, 1], boxes[:, 0], max_leaf_size=2)
        analytic = [analytic[i] for i in shape_bvh.prim_order]
        corners = [np.array([bvh.nodes[0]["bmin"], bvh.nodes[0]["bmax"]])] if len(v0) else []
        corners.append(np.array([shape_bvh.nodes[0]["bmin"], shape_bvh.nodes[0]["bmax"]]))
        lo, hi = np.min([c[0] for c in corners], axis=0), np.max([c[1] for c in corners], axis=0)
        scene_radius = 0.5 * float(np.linalg.norm(hi - lo))
    objects = _ObjectTriangles(
        scene.instances,
        len(v0) + len(analytic),
        len(analytic),
        material_index,
        material_rows,
        medium_index,
        medium_rows,
        table,
        textures,
    )
    own_radius = scene_radius
    roots = ([bvh.nodes[0]] if len(v0) else []) + ([shape_bvh.nodes[0]] if analytic else [])
    own_box = (
        (np.min([r["bmin"] for r in roots], axis=0), np.max([r["bmax"] for r in roots], axis=0)) if roots else None
    )
    scene_radius = _radius_with_instances(own_radius, own_box, objects.instance_boxes)

    vertices = np.zeros((max(len(v0), 1), 3, 4), np.float32)
    vertices[: len(v0), 0, :3], vertices[: len(v0), 1, :3], vertices[: len(v0), 2, :3] = v0, v1, v2
    # The spare w of each triangle's three vertices holds its unit geometric normal (x, y, z), so shading reads it
    # with the vertices instead of computing cross and normalize at every hit and light sample
    # (kernels/light_triangle.cl).
    vertices[: len(v0), :, 3] = _unit_normals(v0, v1, v2)

    triangle_uvs = np.zeros((max(len(v0), 1), 3, 2), np.float32)
    triangle_uvs[: len(v0)] = uv

    # Only the triangles with vertex normals store them, so flat meshes take no memory and their hits read nothing
    # more (kernels/path_state.cl). A degenerate triangle has no face normal to stand in for a zero vertex normal:
    # it shades flat (it is never hit anyway).
    smooth = np.zeros(len(v0), bool)
    if corner_normals is not None:
        smooth = ~np.isnan(corner_normals).any(axis=(1, 2)) & (np.linalg.norm(corner_normals, axis=-1) > 0).all(axis=1)
    normal_slot, smooth_block = smooth_rows(corner_normals, tangents, smooth)
    triangle_normals = np.zeros((max(len(smooth_block), 1), 3, 4), np.float32)
    triangle_normals[: len(smooth_block)] = smooth_block

    # Each light writes its own rows (spectrace.lights); images shown by emitters and environment maps share one
    # texel buffer, each light knowing its offset.
    out = LightRows(table, scene_radius, DEVICE_LIGHTS.codes, texel_chunks, textures)
    areas = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    emitting = area_light.write_rows(emitters, tri_emitter, areas, out)
    shape_light_rows = area_light.write_shape_rows(
        [(emitters[e], k, surface) for k, (surface, _, e, _) in enumerate(analytic) if e >= 0], out
    )
    area_rows = len(out.rows)
    light_spans = []  # the rows each of the scene's lights wrote
    for light in scene.lights:
        start = len(out.rows)
        light_module(light).write_rows(light, out)
        light_spans.append((start, len(out.rows)))
    rows, power = out.rows, out.power

    lights, cdf = light_table(rows, power)
    light_index = np.full(len(v0), -1, np.int32)
    if rows:
        light_index[emitting] = np.arange(len(emitting), dtype=np.int32)
    triangle_info = np.zeros(max(len(v0) + len(analytic), 1), TRIANGLE_INFO_DTYPE)
    triangle_info["material"][: len(v0)] = tri_material
    triangle_info["light"][: len(v0)] = light_index
    triangle_info["interior"] = -1
    triangle_info["interior"][: len(v0)] = tri_interior
    triangle_info["normals"] = -1
    triangle_info["normals"][: len(v0)] = normal_slot
    # The analytic shapes' entries follow the triangles' (kernels/scene.cl: a shape hit is slot triangle_count + k).
    shape_lights = iter(shape_light_rows)
    for k, (_, material, emitter, interior) in enumerate(analytic):
        info = triangle_info[len(v0) + k]
        info["material"], info["interior"] = material, interior
        info["light"] = next(shape_lights) if emitter >= 0 else -1
    if objects.count or objects.shape_count:
        # The objects' shapes' slots follow the scene's own shapes', their triangles' slots follow all the shapes':
        # the triangle arrays keep unused entries for the shapes.
        own = len(v0) + len(analytic)
        shapes = len(analytic) + objects.shape_count
        world_smooth = len(smooth_block)
        vertices = np.concatenate([vertices[: len(v0)], np.zeros((shapes, 3, 4), np.float32), objects.vertices])
        triangle_uvs = np.concatenate([triangle_uvs[: len(v0)], np.zeros((shapes, 3, 2), np.float32), objects.uvs])
        object_info = objects.info.copy()
        object_info["normals"][object_info["normals"] >= 0] += world_smooth
        triangle_info = np.concatenate([triangle_info[:own], objects.shape_info, object_info])
        if len(objects.normals):
            triangle_normals = np.concatenate([triangle_normals[:world_smooth], objects.normals])
    shape_rows = np.zeros(max(len(analytic) + objects.shape_count, 1), ANALYTIC_SHAPE_DTYPE)
    for k, (surface, *_) in enumerate(analytic):
        shape_rows[k] = surface.device_row()
    if objects.shape_rows is not None:
        shape_rows[len(analytic) : len(analytic) + objects.shape_count] = objects.shape_rows
    # SDF grids' samples follow the rows (geometry/sdf_grid.py).
    shape_rows = append_grid_blocks(shape_rows, [surface for surface, *_ in analytic] + objects.shape_surfaces)

    write_attribute_tables(
        textures,
        out.texel_chunks,
        meshed,
        bvh.prim_order,
        len(triangle_info),
        [s for s in scene.shapes if s.analytic is not None]
        + [s for instance in scene.instances for s in instance.object.shapes],
    )
    glow = glow_table(scene, table, list(power))
    cmf = np.zeros((cmf_table_normalised().shape[0], 4), np.float32)
    cmf[:, :3] = cmf_table_normalised()
    materials = np.array(material_rows, MATERIAL_DTYPE) if material_rows else np.zeros(1, MATERIAL_DTYPE)
    if not material_rows:
        write_detail(materials[0], None, None)  # the dummy row asks for no surface detail
    if len(table) == 0:
        table.add(Spectrum.zeros())
    nodes, nodes_seconds, nodes_peak = _measured(lambda: device_nodes(bvh, vertices.reshape(-1, 4)))
    instance_rows, instance_nodes = objects.device_buffers(vertices.reshape(-1, 4))
    texels = np.concatenate(out.texel_chunks)
    packing = None
    if keep_packing:
        out.texel_chunks[:] = [texels]  # one chunk from here on: what an edit appends follows it
        objects.drop_triangles()
        packing = ScenePacking(
            table=table,
            textures=textures,
            scene_radius=scene_radius,
            own_radius=own_radius,
            own_box=own_box,
            triangle_emitter=tri_emitter,
            triangle_areas=areas,
            emitting=emitting,
            shape_emitters=[(e, k, surface) for k, (surface, _, e, _) in enumerate(analytic) if e >= 0],
            area_rows=area_rows,
            light_spans=light_spans,
            light_power=list(power),
            objects=objects,
        )
    return SceneBuffers(
        bvh=bvh,
        nodes=nodes,
        triangle_vertices=vertices.reshape(-1, 4),
        triangle_info=triangle_info,
        triangle_count=len(v0),
        materials=materials,
        lights=lights,
        light_count=len(rows),
        environment_light=out.environment_light,
        light_cdf=cdf.astype(np.float32),
        texels=texels,
        triangle_uvs=triangle_uvs.reshape(-1, 2),
        triangle_normals=triangle_normals.reshape(-1, 4),
        map_cdf=out.map_cdf,
        spectra=table.data,
        cmf=cmf,
        media=np.array(medium_rows, MEDIUM_DTYPE) if medium_rows else np.zeros(1, MEDIUM_DTYPE),
        medium_count=len(medium_rows),
        null_surfaces=any(shape.material is None and shape.interior is None for shape in scene.shapes),
        textures=textures.array(),
        texture_count=len(textures.rows),
        shapes=shape_rows,
        shape_count=len(analytic),
        shape_nodes=shape_bvh.nodes,
        bvh_seconds=bvh_seconds + nodes_seconds + objects.seconds,
        bvh_peak_bytes=None if bvh_peak is None or nodes_peak is None else max(bvh_peak, nodes_peak),
        instances=instance_rows,
        instance_count=len(scene.instances),
        instance_nodes=instance_nodes,
        instanced_triangle_count=objects.count,
        instanced_shape_count=objects.shape_count,
        glow_table=glow,
        packing=packing,
    )


class _ObjectTriangles:
    """The instanced objects' analytic shapes, each object's once, as AnalyticShape rows from `first_shape` on
    (TriangleInfo slots from `first_slot` on); then their triangles, each object's once, at the slots after those,
    each under a BVH of its own; and the instances' world boxes. Materials and media join the scene's tables
    (shared with its own shapes)."""

    def __init__(
        self,
        instances: list[Instance],
        first_slot: int,
        first_shape: int,
        material_index: dict[int, int],
        material_rows: list[np.ndarray],
        medium_index: dict[int, int],
        medium_rows: list[tuple[int, int, float, int, int]],
        table: SpectrumTable,
        textures: TextureRows,
    ) -> None:
        self.instances = instances
        self.objects: list[InstancedObject] = []
        object_number: dict[int, int] = {}
        for instance in instances:
            if id(instance.object) not in object_number:
                object_number[id(instance.object)] = len(self.objects)
                self.objects.append(instance.object)
        self.object_of = [object_number[id(instance.object)] for instance in instances]
        self.bvhs: list[BVH | None] = []  # None: the object has analytic shapes only
        self.first: list[int] = []
        self.shapes_of: list[tuple[int, int]] = []  # (first AnalyticShape row, count) of each object
        self.seconds = 0.0  # building the objects' BVHs and the top level, for the acceleration structure's cost
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ("vertices", "uvs", "normals", "info")}
        shape_rows: list[np.ndarray] = []
        self.shape_surfaces: list[AnalyticSurface] = []  # each of shape_rows' surfaces
        shape_info: list[np.ndarray] = []
        self.shape_count = sum(shape.analytic is not None for obj in self.objects for shape in obj.shapes)
        slot, smooth_slot = first_slot + self.shape_count, 0
        boxes = []
        for obj in self.objects:
            v0s, v1s, v2s, uvs, normals, info = [], [], [], [], [], []
            tangent_parts: list[np.ndarray | None] = []
            analytic_boxes = []
            self.shapes_of.append((first_shape + len(shape_rows), 0))
            for shape in obj.shapes:
                where = f"object '{obj.name}', shape '{shape.name}'"
                if shape.emitter is not None:
                    raise SpectraceError(f"{where}: emitters cannot be instanced (place the emitting shape itself)")
                if isinstance(shape.analytic, CurveSurface):  # an object's shapes are tested one by one, not by a BVH
                    raise SpectraceError(f"{where}: curves cannot be instanced (place the curve shape itself)")
                interior = -1
                if shape.interior is not None:
                    interior = medium_index.setdefault(id(shape.interior), len(medium_rows))
                    if interior == len(medium_rows):
                        if shape.interior.density is not None:  # its grid is placed in the world, not per instance
                            raise SpectraceError(f"{where}: a medium with a density grid cannot be instanced")
                        medium_rows.append(medium_row(shape.interior, table))
                key = id(shape.material)
                if shape.material is None:
                    if shape.interior is None:
                        raise SpectraceError(f"{where} has neither a material nor an interior")
                    material_index[key] = TRIANGLE_NO_MATERIAL
                else:
                    append_material_rows(shape.material, material_rows, table, textures, material_index)
                if (problem := cut_out_problem(shape.material, False, shape.interior is not None)) is not None:
                    raise SpectraceError(f"{where}: {problem}")
                if shape.material is not None and shape.mesh.uvs is None and uv_material_textures(shape.material):
                    raise SpectraceError(f"{where} has no texture coordinates, but its material has a texture")
                if shape.analytic is not None:
                    shape_rows.append(shape.analytic.device_row())
                    self.shape_surfaces.append(shape.analytic)
                    row = np.zeros((), TRIANGLE_INFO_DTYPE)
                    row["material"], row["interior"] = material_index[key], interior
                    row["light"] = row["normals"] = -1
                    shape_info.append(row)
                    analytic_boxes.append(shape.analytic.bounds())
                    continue
                a, b, c, corner_uvs, corner_normals = shape.mesh.corners()
                v0s.append(a)
                v1s.append(b)
                v2s.append(c)
                uvs.append(corner_uvs)
                normals.append(corner_normals)
                tangent_parts.append(shape.mesh.corner_tangents())
                rows = np.zeros(len(a), TRIANGLE_INFO_DTYPE)
                rows["material"], rows["light"], rows["interior"] = material_index[key], -1, interior
                info.append(rows)
            self.shapes_of[-1] = (self.shapes_of[-1][0], len(analytic_boxes))
            box = [np.array(b, np.float64) for b in analytic_boxes]
            if not v0s or not sum(len(v) for v in v0s):
                if not analytic_boxes:
                    raise SpectraceError(f"object '{obj.name}' has no triangles")
                self.bvhs.append(None)
                self.first.append(slot)
                boxes.append((np.min([b[0] for b in box], axis=0), np.max([b[1] for b in box], axis=0)))
                continue
            v0, v1, v2, uv = (np.concatenate(x) for x in (v0s, v1s, v2s, uvs))
            corner = _corner_normals(normals, [len(v) for v in v0s])
            started = perf_counter()
            bvh = build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE, leaf_block=LEAF_BLOCK)
            self.seconds += perf_counter() - started
            order = bvh.prim_order
            v0, v1, v2, uv = v0[order], v1[order], v2[order], uv[order]
            rows = np.concatenate(info)[order]
            block = np.zeros((len(v0), 3, 4), np.float32)
            block[:, 0, :3], block[:, 1, :3], block[:, 2, :3] = v0, v1, v2
            block[:, :, 3] = _unit_normals(v0, v1, v2)
            smooth = np.zeros(len(v0), bool)
            tangents = corner_tangents(tangent_parts, [len(v) for v in v0s])
            if corner is not None:
                corner = corner[order]
                smooth = ~np.isnan(corner).any(axis=(1, 2)) & (np.linalg.norm(corner, axis=-1) > 0).all(axis=1)
            slots, block_rows = smooth_rows(corner, None if tangents is None else tangents[order], smooth)
            if len(block_rows):
                parts["normals"].append(block_rows)
            rows["normals"] = np.where(slots >= 0, slots + smooth_slot, -1)
            smooth_slot += len(block_rows)
            parts["vertices"].append(block)
            parts["uvs"].append(uv.astype(np.float32))
            parts["info"].append(rows)
            self.bvhs.append(bvh)
            self.first.append(slot)
            slot += len(v0)
            lo, hi = bvh.nodes[0]["bmin"].astype(np.float64), bvh.nodes[0]["bmax"].astype(np.float64)
            for b in box:
                lo, hi = np.minimum(lo, b[0]), np.maximum(hi, b[1])
            boxes.append((lo, hi))
        self.count = slot - first_slot - self.shape_count
        self.shape_rows = np.concatenate([r.reshape(1) for r in shape_rows]) if shape_rows else None
        self.shape_info = (
            np.concatenate([r.reshape(1) for r in shape_info]) if shape_info else np.zeros(0, TRIANGLE_INFO_DTYPE)
        )
        self.vertices = np.concatenate(parts["vertices"]) if parts["vertices"] else np.zeros((0, 3, 4), np.float32)
        self.uvs = np.concatenate(parts["uvs"]) if parts["uvs"] else np.zeros((0, 3, 2), np.float32)
        self.normals = np.concatenate(parts["normals"]) if parts["normals"] else np.zeros((0, 3, 4), np.float32)
        self.info = np.concatenate(parts["info"]) if parts["info"] else np.zeros(0, TRIANGLE_INFO_DTYPE)
        self.object_boxes = boxes
        # Each object's node buffer, its leaves pointing at its triangles' slots, and its offset in float4s after
        # the top level (-1: no triangles); built once, as a new placement of the instances leaves them as they are.
        self._object_nodes: tuple[list[np.ndarray], list[int]] | None = None
        self.place(instances)

    def drop_triangles(self) -> None:
        """Let the objects' triangles and BVHs go once they are in the scene's buffers: a new placement needs only
        their boxes and node buffers."""
        empty = np.zeros((0, 3, 4), np.float32)
        self.vertices, self.normals, self.uvs = empty, empty, np.zeros((0, 3, 2), np.float32)
        self.info = np.zeros(0, TRIANGLE_INFO_DTYPE)
        if self._object_nodes is not None:
            self.bvhs = [None] * len(self.bvhs)

    def place(self, instances: list[Instance]) -> None:
        """Take `instances` (the same objects as before, in the same order, each with its own map) as the
        placements: their maps and world boxes."""
        self.instances = instances
        self.instance_boxes: np.ndarray | None = None
        self.matrices = np.zeros((0, 4, 4))
        if instances:
            # Each instance's world box: the hull of its object's box corners under its map.
            boxes = self.object_boxes
            matrices = np.array([np.asarray(instance.to_world, np.float64) for instance in instances])
            lo, hi = (np.array([boxes[k][side] for k in self.object_of]) for side in (0, 1))
            choose = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], bool)  # (8, 3)
            corners = np.where(choose[None], hi[:, None, :], lo[:, None, :])  # (N, 8, 3)
            placed = np.einsum("nij,nkj->nki", matrices[:, :3, :3], corners) + matrices[:, None, :3, 3]
            self.instance_boxes = np.stack([placed.min(axis=1), placed.max(axis=1)], axis=1)
            self.matrices = matrices

    def device_buffers(self, triangle_vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(Instance rows in the top-level BVH's leaf order, the instance node buffer): the top-level binary BVH's
        nodes, then each object's node buffer with its leaves' slots moved to where its triangles are stored."""
        if not self.instances:
            return np.zeros(1, INSTANCE_DTYPE), _empty_bvh().nodes.view(np.float32).copy()
        started = perf_counter()
        boxes = self.instance_boxes
        assert boxes is not None
        top = build_bvh(boxes[:, 0], boxes[:, 1], boxes[:, 0], max_leaf_size=2)
        chunks = [top.nodes.view(np.float32).reshape(-1)]
        top_float4s = len(chunks[0]) // 4
        if self._object_nodes is None:
            object_chunks, object_offsets, float4s = [], [], 0
            for bvh, first in zip(self.bvhs, self.first):
                if bvh is None:
                    object_offsets.append(-1)  # no triangles: the kernels meet its shapes only
                    continue
                placed = bvh.nodes.copy()
                leaves = placed["count"] > 0
                placed["left_first"][leaves] += first
                shifted = BVH(placed, bvh.prim_order, bvh.depth, bvh.sah_cost, bvh.build_seconds)
                buffer = np.ascontiguousarray(device_nodes(shifted, triangle_vertices)).view(np.float32).reshape(-1)
                object_offsets.append(float4s)
                object_chunks.append(buffer)
                float4s += len(buffer) // 4
            self._object_nodes = (object_chunks, object_offsets)
        object_chunks, object_offsets = self._object_nodes
        chunks += object_chunks
        offsets = [offset if offset < 0 else offset + top_float4s for offset in object_offsets]
        float4s = sum(len(chunk) for chunk in chunks) // 4
        if float4s > np.iinfo(np.int32).max:
            raise SpectraceError("the instanced objects' BVHs are too large for 32-bit offsets")
        self.seconds += perf_counter() - started
        order = top.prim_order
        matrices = self.matrices[order]
        rows = np.zeros(len(self.instances), INSTANCE_DTYPE)
        rows["to_world"] = matrices[:, :3]
        rows["to_object"] = np.linalg.inv(matrices)[:, :3]
        objects = np.asarray(self.object_of)[order]
        rows["nodes"] = np.asarray(offsets)[objects]
        rows["object"] = objects
        rows["first_shape"] = np.array([first for first, _ in self.shapes_of])[objects]
        rows["shape_count"] = np.array([count for _, count in self.shapes_of])[objects]
        return rows, np.concatenate(chunks)


T = TypeVar("T")


def _measured(work: Callable[[], T]) -> tuple[T, float, int | None]:
    """(result, wall seconds, peak bytes allocated during the work): numpy reports its arrays to tracemalloc, which
    costs the BVH build nothing measurable (2 M triangles: within 2 %)."""
    if tracemalloc.is_tracing():
        started = perf_counter()
        return work(), perf_counter() - started, None
    tracemalloc.start()
    try:
        started = perf_counter()
        result = work()
        seconds = perf_counter() - started
        return result, seconds, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _empty_bvh() -> BVH:
    """A root whose box is inverted, so every ray misses it (the kernels also skip tracing entirely)."""
    nodes = np.zeros(1, BVH_NODE_DTYPE)
    nodes[0] = ((1.0, 1.0, 1.0), 0, (-1.0, -1.0, -1.0), 1)
    return BVH(nodes=nodes, prim_order=np.zeros(0, np.int32), depth=0, sah_cost=0.0, build_seconds=0.0)


def render_params(scene: Scene, buffers: SceneBuffers, sample_begin: int, sample_count: int) -> np.ndarray:
    origin, forward, right, up = scene.camera.basis(scene.width / scene.height)
    params = np.zeros(1, RENDER_PARAMS_DTYPE)
    params["camera_origin"][0, :3] = origin
    params["camera_origin"][0, 3] = scene.camera.near_clip
    params["camera_forward"][0, :3] = forward
    params["camera_forward"][0, 3] = scene.camera.far_clip or 0.0  # 0: none (kernels/camera.cl)
    params["camera_right"][0, :3] = right
    params["camera_up"][0, :3] = up
    params["width"], params["height"] = scene.width, scene.height
    params["max_depth"], params["rr_depth"] = scene.max_depth, scene.rr_depth
    params["light_count"] = buffers.light_count
    params["environment_light"] = buffers.environment_light
    params["triangle_count"] = buffers.triangle_count
    params["seed"] = scene.seed
    params["sample_begin"], params["sample_count"] = sample_begin, sample_count
    params["medium_count"] = buffers.medium_count
    params["null_surfaces"] = int(buffers.null_surfaces)
    params["glow_table"] = buffers.glow_table
    params["hide_emitters"] = (HIDE_ENVIRONMENT if scene.hide_environment or scene.hide_emitters else 0) | (
        HIDE_AREA_EMITTERS if scene.hide_emitters else 0
    )
    params["shape_count"] = buffers.shape_count
    from spectrace.cameras import CAMERAS

    camera = CAMERAS[scene.camera.type]
    params["camera_type"] = CAMERAS.codes[scene.camera.type]
    params["lens"][0, :2] = camera.lens(scene.camera)
    if hasattr(camera, "device_lens"):  # a lens system's surfaces and exit pupil (kernels/camera_realistic.cl)
        aspect = scene.width / scene.height
        params["lens_elements"][0], params["lens_pupils"][0] = camera.device_lens(scene.camera, aspect)
    if scene.camera.polarizer_angle is not None:  # kernels/polarized_path.cl: the camera's polariser
        params["lens"][0, 2:] = (np.radians(scene.camera.polarizer_angle), 1.0)
    pixel_filter = scene.pixel_filter
    params["pixel_filter"] = pixel_filter.code
    params["filter_shape"][0] = pixel_filter.device_shape()
    params["filter_cdf"][0] = pixel_filter.device_cdf()
    params["instance_count"] = buffers.instance_count
    params["instanced_shape_count"] = buffers.instanced_shape_count
    params["count_thin_passes"] = int(getattr(scene, "count_thin_passes", True))
    for name, value in INTEGRATORS[scene.integrator].params(scene).items():
        params[name] = value
    return params
