"""Flatten a resolved Scene into the arrays the kernels read (layouts in kernels/types.h)."""

from dataclasses import dataclass

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.bvh import BVH, BVH_NODE_DTYPE, build_bvh
from spectrace.geometry.bvh4 import LEAF_SIZE, device_nodes
from spectrace.render.device_types import (
    LIGHT_DISTANT,
    LIGHT_DTYPE,
    LIGHT_ENVIRONMENT,
    LIGHT_ENVIRONMENT_MAP,
    LIGHT_POINT,
    LIGHT_SPOT,
    LIGHT_TRIANGLE,
    MATERIAL_DTYPE,
    MATERIAL_NO_SPECTRUM,
    MEDIUM_DTYPE,
    RENDER_PARAMS_DTYPE,
    TRIANGLE_INFO_DTYPE,
    TRIANGLE_NO_MATERIAL,
)
from spectrace.render.material_rows import material_row
from spectrace.scene.model import ConstantEnvironment, DistantLight, EnvironmentMap, PointLight, Scene, SpotLight
from spectrace.spectral.colorimetry import LINEAR_SRGB_TO_XYZ, cmf_table_normalised
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.spectral.uplift import uplift_illuminant


@dataclass
class SceneBuffers:
    bvh: BVH
    nodes: np.ndarray  # what the traversal reads: bvh.nodes, or their 4-wide collapse and leaf blocks (geometry/bvh4.py)
    triangle_vertices: np.ndarray  # (3·M, 4) float32, BVH leaf order
    triangle_info: np.ndarray  # (M,) TRIANGLE_INFO_DTYPE
    triangle_count: int  # arrays hold one dummy entry when there are no triangles
    materials: np.ndarray  # MATERIAL_DTYPE
    lights: np.ndarray  # LIGHT_DTYPE
    light_count: int
    environment_light: int  # index into lights, or -1
    light_cdf: np.ndarray  # (L + 1,) float32
    triangle_uvs: np.ndarray  # (3·M, 2) float32 texture coordinates, BVH leaf order
    texels: np.ndarray  # (n, 4) float32: images of environment maps and textured emitters, after one dummy texel
    map_cdf: np.ndarray  # marginal CDF over rows (H + 1), then each row's CDF (W + 1): see kernels/environment.cl
    spectra: np.ndarray  # float32 table
    cmf: np.ndarray  # (471, 4) float32: x̄, ȳ, z̄ / ∫ȳ
    media: np.ndarray  # MEDIUM_DTYPE (one dummy entry when there are none)
    medium_count: int

    def device_bytes(self) -> int:
        arrays = (self.nodes, self.triangle_vertices, self.triangle_info, self.materials, self.lights,
                  self.light_cdf, self.spectra, self.cmf, self.media)
        return sum(a.nbytes for a in arrays)


def _unit_normals(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """(M, 3) unit normals of the winding (v0, v1, v2), computed in float64; zero for a degenerate triangle."""
    n = np.cross(np.asarray(v1, np.float64) - v0, np.asarray(v2, np.float64) - v0)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def build_scene_buffers(scene: Scene) -> SceneBuffers:
    table = SpectrumTable()
    material_index: dict[int, int] = {}
    material_rows = []
    v0s, v1s, v2s, uvs, tri_material, tri_emitter, tri_interior = [], [], [], [], [], [], []
    emitters = []
    medium_index: dict[int, int] = {}
    medium_rows = []
    for shape in scene.shapes:
        interior = -1
        if shape.interior is not None:
            interior = medium_index.setdefault(id(shape.interior), len(medium_rows))
            if interior == len(medium_rows):
                medium_rows.append((table.add(shape.interior.sigma_a), table.add(shape.interior.sigma_s),
                                    float(shape.interior.g), 0))
        key = id(shape.material)
        if shape.material is None:
            if shape.interior is None:
                raise SpectraceError(f"shape '{shape.name}' has neither a material nor an interior")
            material_index[key] = TRIANGLE_NO_MATERIAL
        elif key not in material_index:
            material_index[key] = len(material_rows)
            material_rows.append(material_row(shape.material, table))
        v0, v1, v2 = shape.mesh.triangles()
        v0s.append(v0), v1s.append(v1), v2s.append(v2), uvs.append(shape.mesh.triangle_uvs())
        tri_material.append(np.full(len(v0), material_index[key], np.int32))
        tri_interior.append(np.full(len(v0), interior, np.int32))
        emitter_id = -1
        if shape.emitter is not None:
            emitter_id = len(emitters)
            emitters.append(shape.emitter)
        tri_emitter.append(np.full(len(v0), emitter_id, np.int32))

    if v0s and sum(len(v) for v in v0s):
        v0, v1, v2, uv = (np.concatenate(a) for a in (v0s, v1s, v2s, uvs))
        tri_material, tri_emitter = np.concatenate(tri_material), np.concatenate(tri_emitter)
        tri_interior = np.concatenate(tri_interior)
        bvh = build_bvh(v0, v1, v2, max_leaf_size=LEAF_SIZE)
        order = bvh.prim_order
        v0, v1, v2, uv = v0[order], v1[order], v2[order], uv[order]
        tri_material, tri_emitter, tri_interior = tri_material[order], tri_emitter[order], tri_interior[order]
        scene_radius = 0.5 * float(np.linalg.norm(bvh.nodes[0]["bmax"] - bvh.nodes[0]["bmin"]))
    else:
        v0 = v1 = v2 = np.zeros((0, 3))
        uv = np.zeros((0, 3, 2))
        tri_material = tri_emitter = tri_interior = np.zeros(0, np.int32)
        bvh = _empty_bvh()
        scene_radius = 1.0
    scene_radius = max(scene_radius, 1e-6)

    vertices = np.zeros((max(len(v0), 1), 3, 4), np.float32)
    vertices[: len(v0), 0, :3], vertices[: len(v0), 1, :3], vertices[: len(v0), 2, :3] = v0, v1, v2
    # The spare w of each triangle's three vertices holds its unit geometric normal (x, y, z), so shading reads it
    # with the vertices instead of computing cross and normalize at every hit and light sample (kernels/lights.cl).
    vertices[: len(v0), :, 3] = _unit_normals(v0, v1, v2)

    triangle_uvs = np.zeros((max(len(v0), 1), 3, 2), np.float32)
    triangle_uvs[: len(v0)] = uv

    # Images shown by emitters and environment maps share one texel buffer; each light knows its offset.
    texel_chunks = [np.zeros((1, 4), np.float32)]
    def add_texels(rgb: np.ndarray) -> int:
        offset = sum(len(c) for c in texel_chunks)
        chunk = np.zeros((rgb.shape[0] * rgb.shape[1], 4), np.float32)
        chunk[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
        texel_chunks.append(chunk)
        return offset

    rows, power = [], []
    areas = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    emitting = np.flatnonzero((tri_emitter >= 0) & (areas > 0))
    emitter_rows = []
    for e in emitters:
        if e.image is None:
            emitter_rows.append({"spectrum_offset": table.add(e.radiance)})
        else:
            basis = [table.add(p) for p in e.image.primaries]
            height, width = e.image.drive.shape[:2]
            emitter_rows.append({"spectrum_offset": basis[0], "texel_offset": add_texels(e.image.drive),
                                 "map_fields": (basis[1], basis[2], width, height)})
    for t in emitting:
        e = emitters[tri_emitter[t]]
        fields = emitter_rows[tri_emitter[t]]
        rows.append(_light_row(LIGHT_TRIANGLE, fields["spectrum_offset"], triangle=t, area=areas[t],
                               two_sided=e.two_sided, map_fields=fields.get("map_fields", (0, 0, 0, 0)),
                               texel_offset=fields.get("texel_offset", 0)))
        power.append(np.pi * areas[t] * e.radiance.mean() * (2.0 if e.two_sided else 1.0))
    environment_light = -1
    map_cdf = np.zeros(2, np.float32)
    for light in scene.lights:
        if isinstance(light, PointLight):
            rows.append(_light_row(LIGHT_POINT, table.add(light.intensity), position=light.position))
            power.append(4.0 * np.pi * light.intensity.mean())
        elif isinstance(light, SpotLight):
            rows.append(_light_row(LIGHT_SPOT, table.add(light.intensity), position=light.position,
                                   direction=light.direction,
                                   cos_falloff_start=np.cos(np.radians(light.falloff_start_degrees)),
                                   cos_cutoff=np.cos(np.radians(light.cutoff_degrees))))
            power.append(light.effective_solid_angle() * light.intensity.mean())
        elif isinstance(light, DistantLight):
            rows.append(_light_row(LIGHT_DISTANT, table.add(light.irradiance), direction=light.direction))
            power.append(np.pi * scene_radius**2 * light.irradiance.mean())
        elif isinstance(light, ConstantEnvironment):
            environment_light = len(rows)
            rows.append(_light_row(LIGHT_ENVIRONMENT, table.add(light.radiance)))
            power.append(4.0 * np.pi**2 * scene_radius**2 * light.radiance.mean())
        elif isinstance(light, EnvironmentMap):
            environment_light = len(rows)
            map_texels, map_cdf, mean_luminance = environment_map_tables(light.rgb)
            basis = [table.add(uplift_illuminant(primary)) for primary in np.eye(3)]
            height, width = light.rgb.shape[:2]
            row = _light_row(LIGHT_ENVIRONMENT_MAP, basis[0], map_fields=(basis[1], basis[2], width, height),
                             texel_offset=add_texels(map_texels[:, :3].reshape(height, width, 3)))
            rows.append(row[:5] + (light.scale,) + row[6:])
            power.append(4.0 * np.pi**2 * scene_radius**2 * light.scale * mean_luminance)
        else:
            raise SpectraceError(f"unsupported light {type(light).__name__}")

    # Next-event estimation picks a light in proportion to an estimate of the power it emits (pbrt-v4's
    # power light sampler); any positive weights would be unbiased, these put samples where the light is.
    lights = np.array(rows, LIGHT_DTYPE) if rows else np.zeros(1, LIGHT_DTYPE)
    light_index = np.full(len(v0), -1, np.int32)
    if rows:
        weights = np.maximum(np.array(power, float), 0.0)
        if weights.sum() <= 0:
            weights[:] = 1.0
        pmf = weights / weights.sum()
        lights["pmf"][: len(rows)] = pmf
        light_index[emitting] = np.arange(len(emitting), dtype=np.int32)
        cdf = np.concatenate([[0.0], np.cumsum(pmf)])
        cdf[-1] = 1.0
    else:
        cdf = np.array([0.0, 1.0])
    triangle_info = np.zeros(max(len(v0), 1), TRIANGLE_INFO_DTYPE)
    triangle_info["material"][: len(v0)] = tri_material
    triangle_info["light"][: len(v0)] = light_index
    triangle_info["interior"] = -1
    triangle_info["interior"][: len(v0)] = tri_interior

    cmf = np.zeros((cmf_table_normalised().shape[0], 4), np.float32)
    cmf[:, :3] = cmf_table_normalised()
    materials = np.array(material_rows, MATERIAL_DTYPE) if material_rows else np.zeros(1, MATERIAL_DTYPE)
    if len(table) == 0:
        table.add(Spectrum.zeros())
    return SceneBuffers(
        bvh=bvh,
        nodes=device_nodes(bvh, vertices.reshape(-1, 4)),
        triangle_vertices=vertices.reshape(-1, 4),
        triangle_info=triangle_info,
        triangle_count=len(v0),
        materials=materials,
        lights=lights,
        light_count=len(rows),
        environment_light=environment_light,
        light_cdf=cdf.astype(np.float32),
        texels=np.concatenate(texel_chunks),
        triangle_uvs=triangle_uvs.reshape(-1, 2),
        map_cdf=map_cdf,
        spectra=table.data,
        cmf=cmf,
        media=np.array(medium_rows, MEDIUM_DTYPE) if medium_rows else np.zeros(1, MEDIUM_DTYPE),
        medium_count=len(medium_rows),
    )


def environment_map_tables(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Texels, sampling CDFs and mean luminance of a latitude-longitude map: the sampling density is ∝ luminance ×
    sin θ of the row's centre, so directions are drawn where light arrives and the poles' small texels are not
    oversampled."""
    height, width = rgb.shape[:2]
    texels = np.zeros((height * width, 4), np.float32)
    texels[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
    luminance = (texels[:, :3] @ LINEAR_SRGB_TO_XYZ[1]).reshape(height, width).astype(np.float64)
    sin_theta = np.sin(np.pi * (np.arange(height) + 0.5) / height)[:, None]
    weights = luminance * sin_theta
    if weights.sum() <= 0:
        weights = np.broadcast_to(sin_theta, (height, width)).copy()
    row_mass = weights.sum(axis=1)
    row_cdf = np.zeros((height, width + 1))
    row_cdf[:, 1:] = np.cumsum(weights, axis=1)
    row_cdf = np.divide(row_cdf, row_cdf[:, -1:], out=np.tile(np.linspace(0, 1, width + 1), (height, 1)),
                        where=row_cdf[:, -1:] > 0)
    marginal = np.concatenate([[0.0], np.cumsum(row_mass)]) / row_mass.sum()
    marginal[-1] = 1.0
    row_cdf[:, -1] = 1.0
    return texels, np.concatenate([marginal, row_cdf.ravel()]).astype(np.float32), float(luminance.mean())


def _light_row(light_type: int, spectrum_offset: int, *, triangle: int = -1, area: float = 0.0,
               two_sided: bool = False, position=(0.0, 0.0, 0.0), direction=(0.0, 0.0, 1.0),
               cos_falloff_start: float = 1.0, cos_cutoff: float = 1.0, map_fields=(0, 0, 0, 0),
               texel_offset: int = 0) -> tuple:
    return ((*position, 1.0), (*direction, 0.0), light_type, triangle, spectrum_offset, 1.0, 0.0, area,
            int(two_sided), cos_falloff_start, cos_cutoff, *map_fields, texel_offset, 0, 0)


def _empty_bvh() -> BVH:
    """A root whose box is inverted, so every ray misses it (the kernels also skip tracing entirely)."""
    nodes = np.zeros(1, BVH_NODE_DTYPE)
    nodes[0] = ((1.0, 1.0, 1.0), 0, (-1.0, -1.0, -1.0), 1)
    return BVH(nodes=nodes, prim_order=np.zeros(0, np.int32), depth=0, sah_cost=0.0, build_seconds=0.0)


def render_params(scene: Scene, buffers: SceneBuffers, sample_begin: int, sample_count: int) -> np.ndarray:
    origin, forward, right, up = scene.camera.basis(scene.width / scene.height)
    params = np.zeros(1, RENDER_PARAMS_DTYPE)
    params["camera_origin"][0, :3] = origin
    params["camera_forward"][0, :3] = forward
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
    return params
