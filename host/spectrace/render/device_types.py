"""numpy mirrors of the structs in kernels/types.h, with explicit offsets.

tests/device/test_struct_layout.py compiles a kernel that reports each struct's sizeof and offsetof on the device and
compares them with these dtypes.
"""

import numpy as np

from spectrace.geometry.bvh import BVH_NODE_DTYPE
from spectrace.geometry.bvh4 import BVH4_NODE_DTYPE

# Material.type and Material.ior_model values (kernels/types.h).
MATERIAL_DIFFUSE = 0
MATERIAL_CONDUCTOR = 1
MATERIAL_MIRROR = 2
MATERIAL_PLASTIC = 3
MATERIAL_DIELECTRIC = 4
MATERIAL_RETROREFLECTOR = 5

IOR_CONSTANT = 0
IOR_SELLMEIER = 1
IOR_CAUCHY = 2

MATERIAL_NO_SPECTRUM = -1


def _struct(fields: list[tuple[str, object]], itemsize: int) -> np.dtype:
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


TRIANGLE_NO_MATERIAL = -1  # TriangleInfo.material of an index-matched medium boundary

TRIANGLE_INFO_DTYPE = _struct([("material", "<i4"), ("light", "<i4"), ("interior", "<i4"), ("pad0", "<i4")], 16)

MEDIUM_DTYPE = _struct([("sigma_a_offset", "<i4"), ("sigma_s_offset", "<i4"), ("g", "<f4"), ("pad0", "<i4")], 16)

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
        ("pad0", "<i4"),
    ],
    64,
)

LIGHT_TRIANGLE, LIGHT_POINT, LIGHT_SPOT, LIGHT_DISTANT, LIGHT_ENVIRONMENT, LIGHT_ENVIRONMENT_MAP = range(6)

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
        ("pad1", "<i4"),
        ("pad2", "<i4"),
    ],
    96,
)

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
        ("pad1", "<i4"),
    ],
    112,
)

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

# struct name in types.h -> dtype; the layout test walks this table.
DEVICE_STRUCTS: dict[str, np.dtype] = {
    "BVHNode": BVH_NODE_DTYPE,
    "BVH4Node": BVH4_NODE_DTYPE,
    "TriangleInfo": TRIANGLE_INFO_DTYPE,
    "Material": MATERIAL_DTYPE,
    "Medium": MEDIUM_DTYPE,
    "Light": LIGHT_DTYPE,
    "RenderParams": RENDER_PARAMS_DTYPE,
    "MeterParams": METER_PARAMS_DTYPE,
}
