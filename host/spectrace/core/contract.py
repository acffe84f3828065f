"""The host/device contract: numpy mirrors of the structs in kernels/types.h (explicit offsets), and the one home
of every number both sides must agree on (the type codes of those structs, the wavelength grid, buffer layouts)
but the plugins' type codes (materials, lights, textures, cameras, pixel filters), which are their positions in
their registries (spectrace.core.registry; the lights' device types in spectrace.lights.DEVICE_LIGHTS) and reach a
build as `GeneratedSources`.

The kernels hold no copy of those numbers: every kernel build gets them as defines (`device_contract_defines`,
added by spectrace.device's program builds). tests/device/test_struct_layout.py compiles a kernel that reports each
struct's sizeof and offsetof, and every contract value as the kernels see it, and compares them with this module.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import DTypeLike

from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_SIZE

# Material.type: which BSDF. The codes (MATERIAL_<NAME>, MATERIAL_TYPE_COUNT) are each BSDF's position in
# spectrace.materials.MATERIALS, which spectrace.device adds to every build with this contract.

# Material.ior_model: how a dielectric's interior index of refraction depends on the wavelength (kernels/ior.cl).
IOR_CONSTANT = 0  # Material.ior
IOR_SELLMEIER = 1  # n² = 1 + Σ B_i λ² / (λ² − C_i), λ in µm: coefficients B1 B2 B3 C1 C2 C3 (C in µm²)
IOR_CAUCHY = 2  # n = a + b / λ², λ in µm: coefficients a, b (b in µm²)

# Material.distribution: the microfacet distribution of a rough material's lobe (kernels/microfacet.cl).
MICROFACET_DISTRIBUTIONS = ("ggx", "beckmann")
MICROFACET_GGX, MICROFACET_BECKMANN = range(len(MICROFACET_DISTRIBUTIONS))

# An offset that names no spectrum (only offsets documented as optional in types.h may hold it).
MATERIAL_NO_SPECTRUM = -1


@dataclass(frozen=True)
class GeneratedSources:
    """What the plugin registries add to a kernel build beyond the kernels folder and `device_contract_defines`:
    their type codes as defines and their dispatch lists as headers (file name -> text). Whoever builds a program
    that dispatches over a registry hands it to spectrace.device, which does not read the registries itself."""

    defines: Mapping[str, int] = field(default_factory=dict)
    headers: Mapping[str, str] = field(default_factory=dict)

    def __or__(self, other: "GeneratedSources") -> "GeneratedSources":
        """Both registries' codes and headers, for a build that dispatches over both; a name given twice is a
        clash of two registries."""
        for mine, theirs in ((self.defines, other.defines), (self.headers, other.headers)):
            if clash := sorted(set(mine) & set(theirs)):
                raise ValueError(f"two registries generate {clash[0]}")
        return GeneratedSources({**self.defines, **other.defines}, {**self.headers, **other.headers})


def _struct(fields: Sequence[tuple[str, DTypeLike]], itemsize: int) -> np.dtype:
    names, formats, offsets = [], [], []
    offset = 0
    for name, fmt in fields:
        dt = np.dtype(fmt)
        names.append(name)
        formats.append(dt)
        offsets.append(offset)
        offset += dt.itemsize
    if offset != itemsize:
        raise AssertionError(f"struct fields add up to {offset} bytes, expected {itemsize}")
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize})


# The BVH nodes the kernels traverse (kernels/bvh.cl), which spectrace.geometry builds.
BVH_NODE_DTYPE = np.dtype(
    {
        "names": ["bmin", "left_first", "bmax", "count"],
        "formats": [("<f4", (3,)), "<i4", ("<f4", (3,)), "<i4"],
        "offsets": [0, 12, 16, 28],
        "itemsize": 32,
    }
)


def _wide_node_dtype(width: int) -> np.dtype:
    """SoA node of `width` children: 24·width bytes of boxes, then the child and count vectors."""
    boxes = 12 * width
    return np.dtype(
        {
            "names": ["child_min", "child_max", "child", "count"],
            "formats": [("<f4", (3, width)), ("<f4", (3, width)), ("<i4", (width,)), ("<i4", (width,))],
            "offsets": [0, boxes, 2 * boxes, 2 * boxes + 4 * width],
            "itemsize": 2 * boxes + 8 * width,
        }
    )


BVH4_NODE_DTYPE = _wide_node_dtype(4)  # 128 bytes
BVH8_NODE_DTYPE = _wide_node_dtype(8)  # 256 bytes

# Deepest root-to-leaf path, in edges, that the kernel's fixed traversal stack can hold.
MAX_DEPTH = 64
# Entries of the 4-wide kernel's stack (kernels/bvh.cl BVH4_STACK_SIZE): a visit pushes at most three, and the
# collapse never makes a path longer than the binary tree's (<= MAX_DEPTH), so the stack cannot overflow.
BVH4_STACK_SIZE = 3 * MAX_DEPTH + 1
# Entries of the 8-wide kernel's stack (kernels/bvh.cl BVH8_STACK_SIZE, 8 bytes each): the collapse gives a node
# fewer children where more could overflow it (collapse, stack_size). 96 leaves every node of the living room
# (295k triangles, stack need 65) its full width; any tree the builder makes (depth <= MAX_DEPTH) fits.
BVH8_STACK_SIZE = 96
LEAF_BLOCK_FLOAT4S = 10  # a 4-lane leaf block of triangles in float4s (spectrace.geometry.triangle_blocks)


TRIANGLE_NO_MATERIAL = -1  # TriangleInfo.material of an index-matched medium boundary
# RenderParams.hide_emitters bits: camera rays that leave the scene see black; camera rays pass through area lights
# (what Mitsuba 3's hide_emitters does, measured with its path and direct integrators).
HIDE_ENVIRONMENT, HIDE_AREA_EMITTERS = 1, 2

TRIANGLE_INFO_DTYPE = _struct([("material", "<i4"), ("light", "<i4"), ("interior", "<i4"), ("normals", "<i4")], 16)

MEDIUM_DTYPE = _struct(
    [("sigma_a_offset", "<i4"), ("sigma_s_offset", "<i4"), ("g", "<f4"), ("grid", "<i4"), ("emission", "<i4")], 20
)

MATERIAL_DTYPE = _struct(
    [
        ("ior_coefficients_b", ("<f4", (4,))),
        ("ior_coefficients_c", ("<f4", (4,))),
        ("type", "<i4"),
        ("reflectance_offset", "<i4"),
        ("eta_offset", "<i4"),
        ("k_offset", "<i4"),
        ("alpha", "<f4"),
        ("ior_model", "<i4"),
        ("ior", "<f4"),
        ("reflectance_texture", "<i4"),
        ("roughness_texture", "<i4"),
        ("distribution", "<i4"),
        ("nonlinear", "<i4"),
        ("transmittance_offset", "<i4"),
        ("coat_table_offset", "<i4"),
        ("coat_internal_reflectance", "<f4"),
        # Surface detail (spectrace.materials.surface), last so that new parameters go before it.
        ("normal_map", "<i4"),
        ("bump_map", "<i4"),
        ("bump_scale", "<f4"),
        ("opacity", "<f4"),
        ("opacity_texture", "<i4"),
        ("one_sided", "<i4"),
        ("shadowing", "<i4"),
        ("tangent_frame", "<i4"),
        ("normal_map_handedness", "<i4"),
        ("tangent_rotation", "<f4"),
    ],
    128,
)

# Texture.type: TEXTURE_<NAME>, each texture's position in spectrace.textures.TEXTURES (kernels/texture.cl).
# Texture.texel_format: what one texel holds. SIGMOID: the 3 coefficients (c0, c1, c2) of a reflectance
# S(c0 λ² + c1 λ + c2), λ in nm; SCALAR: one value (a data texture, returned at every wavelength); BANDS: one value
# per band, at band centres band_first_nm + i·band_step_nm; VECTOR: three values read as they are (a normal map);
# RGB: linear (r, g, b), the weights of three basis spectra (an emission: r·R(λ) + g·G(λ) + b·B(λ), the lights'
# images).
TEXEL_SIGMOID, TEXEL_SCALAR, TEXEL_BANDS, TEXEL_VECTOR, TEXEL_RGB = range(5)
# Texture.storage: how each stored value is held (spectrace.textures.storage). FLOAT: float32; HALF: IEEE half
# (sigmoid coefficients then in their dimensionless form); UNORM8, UNORM16: unsigned integers k standing for
# k / 255 and k / 65535.
STORAGE_FLOAT, STORAGE_HALF, STORAGE_UNORM8, STORAGE_UNORM16 = range(4)
# The dimensionless variable of half-stored sigmoid coefficients, t = (λ − centre) / half span: the grid's middle
# and half width, as the fits of spectrace.spectral.uplift use (t in [−1, 1]).
SIGMOID_CENTRE_NM = 0.5 * (GRID_MIN_NM + GRID_MAX_NM)
SIGMOID_HALF_SPAN_NM = 0.5 * (GRID_MAX_NM - GRID_MIN_NM)
# Texture.wrap: where st outside [0, 1)² looks.
WRAP_REPEAT, WRAP_MIRROR, WRAP_CLAMP = range(3)
# Texture.filter: NEAREST: the texel containing st at the finest level; BILINEAR: the four nearest texels of one
# level; TRILINEAR: bilinear on the two levels around the footprint, blended.
FILTER_NEAREST, FILTER_BILINEAR, FILTER_TRILINEAR = range(3)
# A material parameter without a texture (Material.reflectance_texture, roughness_texture), a checkerboard side
# without one, and an area light without an emission texture (Light.texture).
NO_TEXTURE = -1

TEXTURE_DTYPE = _struct(
    [
        ("uv_transform", ("<f4", (4,))),
        ("type", "<i4"),
        ("texel_format", "<i4"),
        ("channels", "<i4"),
        ("width", "<i4"),
        ("height", "<i4"),
        ("levels", "<i4"),
        ("data_offset", "<i4"),
        ("wrap", "<i4"),
        ("filter", "<i4"),
        ("band_first_nm", "<f4"),
        ("band_step_nm", "<f4"),
        ("side_spectrum", ("<i4", (2,))),
        ("side_texture", ("<i4", (2,))),
        ("basis_offset", ("<i4", (3,))),
        ("storage", "<i4"),
        ("factor", "<f4"),
        ("factor_texture", "<i4"),
        ("mapping", "<i4"),
        ("mapping_offset", "<i4"),
        ("pad", ("<i4", (1,))),
    ],
    112,
)

# AnalyticShape.type (kernels/shapes.cl): Mitsuba 3's sphere, disk and cylinder in their object space, an SDF grid
# (kernels/shape_sdf_grid.cl) and one linear curve segment (kernels/shape_curve.cl, geometry/curves.py).
SHAPE_TYPES = ("sphere", "disk", "cylinder", "sdfgrid", "curve")
SHAPE_SPHERE, SHAPE_DISK, SHAPE_CYLINDER, SHAPE_SDFGRID, SHAPE_CURVE = range(len(SHAPE_TYPES))
# A curve segment's row (kernels/shape_curve.cl): a round tube, or pbrt-v4's flat and ribbon strips
# (kernels/curve_ribbon.cl); the code is kept in the row's cut_min.
CURVE_TYPES = ("tube", "flat", "ribbon")
CURVE_TYPE_TUBE, CURVE_TYPE_FLAT, CURVE_TYPE_RIBBON = range(len(CURVE_TYPES))

ANALYTIC_SHAPE_DTYPE = _struct(
    [
        ("to_world", ("<f4", (3, 4))),
        ("to_object", ("<f4", (3, 4))),
        ("sphere", ("<f4", (4,))),
        ("type", "<i4"),
        ("abs_det", "<f4"),
        ("object_area", "<f4"),
        ("flip_normals", "<i4"),
        ("pbrt_uv", "<i4"),
        ("phi_max", "<f4"),
        ("cut_min", "<f4"),
        ("cut_max", "<f4"),
    ],
    144,
)

INSTANCE_DTYPE = _struct(
    [
        ("to_world", ("<f4", (3, 4))),
        ("to_object", ("<f4", (3, 4))),
        ("nodes", "<i4"),
        ("object", "<i4"),
        ("first_shape", "<i4"),
        ("shape_count", "<i4"),
    ],
    112,
)

LIGHT_DTYPE = _struct(
    [
        ("position", ("<f4", (4,))),
        ("direction", ("<f4", (4,))),
        ("type", "<i4"),
        ("triangle", "<i4"),
        ("spectrum_offset", "<i4"),
        ("scale", "<f4"),
        ("pmf", "<f4"),
        ("area", "<f4"),
        ("two_sided", "<i4"),
        ("cos_falloff_start", "<f4"),
        ("cos_cutoff", "<f4"),
        ("basis_green_offset", "<i4"),
        ("basis_blue_offset", "<i4"),
        ("map_width", "<i4"),
        ("map_height", "<i4"),
        ("texel_offset", "<i4"),
        ("texture", "<i4"),
        ("linear_falloff", "<i4"),
    ],
    96,
)

# RenderParams.camera_type: how a film position becomes a ray, CAMERA_<NAME>, each camera's position in
# spectrace.cameras.CAMERAS (kernels/camera.cl).
# RenderParams.pixel_filter: the pixel's reconstruction filter, importance-sampled, PIXEL_FILTER_<NAME>, each
# filter's position in spectrace.pixel_filters.PIXEL_FILTERS (kernels/pixel_filter.cl). Those the kernel draws from
# a table (TABULATED) use PIXEL_FILTER_BINS piecewise-constant bins of |f| over [0, radius] (RenderParams.filter_cdf).
PIXEL_FILTER_BINS = 32
# RenderParams.lens_elements: CAMERA_REALISTIC's header row and lens surfaces (spectrace.cameras.realistic).
LENS_ELEMENT_ROWS = 32
LENS_PUPIL_BINS = 32  # RenderParams.lens_pupils: its exit pupil's bounds per ring of film radius

RENDER_PARAMS_DTYPE = _struct(
    [
        ("camera_origin", ("<f4", (4,))),
        ("camera_forward", ("<f4", (4,))),
        ("camera_right", ("<f4", (4,))),
        ("camera_up", ("<f4", (4,))),
        ("width", "<i4"),
        ("height", "<i4"),
        ("max_depth", "<i4"),
        ("rr_depth", "<i4"),
        ("light_count", "<i4"),
        ("environment_light", "<i4"),
        ("triangle_count", "<i4"),
        ("seed", "<i4"),
        ("sample_begin", "<i4"),
        ("sample_count", "<i4"),
        ("medium_count", "<i4"),
        ("hide_emitters", "<i4"),
        ("shape_count", "<i4"),
        ("camera_type", "<i4"),
        ("pixel_filter", "<i4"),
        ("instance_count", "<i4"),
        ("count_thin_passes", "<i4"),
        ("instanced_shape_count", "<i4"),
        ("null_surfaces", "<i4"),
        ("spectral_bins", "<i4"),
        ("film_responses", "<i4"),
        ("spectral_min_nm", "<f4"),
        ("spectral_max_nm", "<f4"),
        ("bdpt_only_s", "<i4"),
        ("bdpt_only_t", "<i4"),
        ("bdpt_pixels_per_light_path", "<i4"),
        ("glow_table", "<i4"),
        ("pad_params", ("<i4", (1,))),
        ("lens", ("<f4", (4,))),
        ("filter_shape", ("<f4", (4,))),
        ("filter_cdf", ("<f4", (PIXEL_FILTER_BINS,))),
        ("lens_elements", ("<f4", (LENS_ELEMENT_ROWS, 4))),
        ("lens_pupils", ("<f4", (LENS_PUPIL_BINS, 4))),
    ],
    208 + 4 * PIXEL_FILTER_BINS + 16 * (LENS_ELEMENT_ROWS + LENS_PUPIL_BINS),
)

# MeterParams.type (kernels/meters.cl). IRRADIANCE: W/(m² nm) on a one-sided surface at `point` facing
# `direction`; RADIANCE: W/(m² sr nm) arriving at `point` from `-direction`; FLUX: W/nm leaving the sphere centred
# at point.xyz with radius point.w, from inside.
METER_IRRADIANCE, METER_RADIANCE, METER_FLUX = range(3)

METER_PARAMS_DTYPE = _struct(
    [
        ("point", ("<f4", (4,))),
        ("direction", ("<f4", (4,))),
        ("type", "<i4"),
        ("samples_per_item", "<i4"),
        ("seed", "<i4"),
        ("pad0", "<i4"),
    ],
    48,
)

# The scene buffers every scene kernel takes after the RenderParams buffer, in order: the SceneBuffers fields that
# kernels/scene.cl's SCENE_KERNEL_PARAMS declares (spectrace.engine.renderer.upload_scene uploads them so).
SCENE_KERNEL_BUFFERS = (
    "nodes",
    "triangle_vertices",
    "triangle_uvs",
    "triangle_normals",
    "triangle_info",
    "materials",
    "lights",
    "light_cdf",
    "spectra",
    "texels",
    "map_cdf",
    "media",
    "textures",
    "shapes",
    "shape_nodes",
    "instances",
    "instance_nodes",
)

# struct name in types.h -> dtype; the layout test walks this table.
DEVICE_STRUCTS: dict[str, np.dtype] = {
    "BVHNode": BVH_NODE_DTYPE,
    "BVH4Node": BVH4_NODE_DTYPE,
    "BVH8Node": BVH8_NODE_DTYPE,
    "TriangleInfo": TRIANGLE_INFO_DTYPE,
    "Material": MATERIAL_DTYPE,
    "Medium": MEDIUM_DTYPE,
    "Texture": TEXTURE_DTYPE,
    "Light": LIGHT_DTYPE,
    "AnalyticShape": ANALYTIC_SHAPE_DTYPE,
    "Instance": INSTANCE_DTYPE,
    "RenderParams": RENDER_PARAMS_DTYPE,
    "MeterParams": METER_PARAMS_DTYPE,
}


def _c_value(value: int | float) -> int | float | str:
    # A negative number is parenthesised so the define expands safely anywhere (x-MATERIAL_NO_SPECTRUM).
    return f"({value})" if isinstance(value, int) and value < 0 else value


def device_contract_defines() -> dict[str, int | float | str]:
    """Every number the kernels share with the host, as build defines: each kernel build gets all of them, and the
    kernels define none of them themselves."""
    values: dict[str, int | float] = {
        # The wavelength grid of every tabulated spectrum (nm): spectrace.spectral.grid.
        "GRID_MIN_NM": float(GRID_MIN_NM),
        "GRID_MAX_NM": float(GRID_MAX_NM),
        "GRID_SAMPLES": int(GRID_SIZE),
        "MATERIAL_NO_SPECTRUM": MATERIAL_NO_SPECTRUM,
        "TRIANGLE_NO_MATERIAL": TRIANGLE_NO_MATERIAL,
        "HIDE_ENVIRONMENT": HIDE_ENVIRONMENT,
        "HIDE_AREA_EMITTERS": HIDE_AREA_EMITTERS,
        "IOR_CONSTANT": IOR_CONSTANT,
        "IOR_SELLMEIER": IOR_SELLMEIER,
        "IOR_CAUCHY": IOR_CAUCHY,
        "MICROFACET_GGX": MICROFACET_GGX,
        "MICROFACET_BECKMANN": MICROFACET_BECKMANN,
        "METER_IRRADIANCE": METER_IRRADIANCE,
        "METER_RADIANCE": METER_RADIANCE,
        "METER_FLUX": METER_FLUX,
        "NO_TEXTURE": NO_TEXTURE,
        "TEXEL_SIGMOID": TEXEL_SIGMOID,
        "TEXEL_SCALAR": TEXEL_SCALAR,
        "TEXEL_BANDS": TEXEL_BANDS,
        "TEXEL_VECTOR": TEXEL_VECTOR,
        "TEXEL_RGB": TEXEL_RGB,
        "STORAGE_FLOAT": STORAGE_FLOAT,
        "STORAGE_HALF": STORAGE_HALF,
        "STORAGE_UNORM8": STORAGE_UNORM8,
        "STORAGE_UNORM16": STORAGE_UNORM16,
        # The dimensionless variable of sigmoid coefficients, t = (λ − centre) / half span (spectrace.spectral.uplift).
        "SIGMOID_CENTRE_NM": float(SIGMOID_CENTRE_NM),
        "SIGMOID_HALF_SPAN_NM": float(SIGMOID_HALF_SPAN_NM),
        "WRAP_REPEAT": WRAP_REPEAT,
        "WRAP_MIRROR": WRAP_MIRROR,
        "WRAP_CLAMP": WRAP_CLAMP,
        "FILTER_NEAREST": FILTER_NEAREST,
        "FILTER_BILINEAR": FILTER_BILINEAR,
        "FILTER_TRILINEAR": FILTER_TRILINEAR,
        "PIXEL_FILTER_BINS": PIXEL_FILTER_BINS,
        "LENS_ELEMENT_ROWS": LENS_ELEMENT_ROWS,
        "LENS_PUPIL_BINS": LENS_PUPIL_BINS,
        # Buffer layouts and bounds the geometry builders guarantee (spectrace.geometry).
        "LEAF_BLOCK_FLOAT4S": LEAF_BLOCK_FLOAT4S,
        "BVH_STACK_SIZE": MAX_DEPTH,
        "BVH4_STACK_SIZE": BVH4_STACK_SIZE,
        "BVH8_STACK_SIZE": BVH8_STACK_SIZE,
    }
    values |= {f"SHAPE_{name.upper()}": code for code, name in enumerate(SHAPE_TYPES)}
    values |= {f"CURVE_TYPE_{name.upper()}": code for code, name in enumerate(CURVE_TYPES)}
    return {name: _c_value(value) for name, value in values.items()}
