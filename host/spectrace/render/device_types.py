"""numpy mirrors of the structs in kernels/types.h, with explicit offsets.

tests/test_struct_layout.py compiles a kernel that reports each struct's sizeof and offsetof on the device and
compares them with these dtypes.
"""

import numpy as np

from spectrace.geometry.bvh import BVH_NODE_DTYPE

MATERIAL_DIFFUSE = 0


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


TRIANGLE_INFO_DTYPE = _struct([("material", "<i4"), ("light", "<i4")], 8)

MATERIAL_DTYPE = _struct(
    [("type", "<i4"), ("reflectance_offset", "<i4"), ("pad0", "<i4"), ("pad1", "<i4")], 16
)

LIGHT_DTYPE = _struct(
    [
        ("triangle", "<i4"),
        ("radiance_offset", "<i4"),
        ("scale", "<f4"),
        ("pmf", "<f4"),
        ("area", "<f4"),
        ("two_sided", "<i4"),
        ("pad0", "<i4"),
        ("pad1", "<i4"),
    ],
    32,
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
        ("seed", "<i4"),
        ("sample_begin", "<i4"),
        ("sample_count", "<i4"),
    ],
    96,
)

# struct name in types.h -> dtype; the layout test walks this table.
DEVICE_STRUCTS: dict[str, np.dtype] = {
    "BVHNode": BVH_NODE_DTYPE,
    "TriangleInfo": TRIANGLE_INFO_DTYPE,
    "Material": MATERIAL_DTYPE,
    "Light": LIGHT_DTYPE,
    "RenderParams": RENDER_PARAMS_DTYPE,
}
