"""Texture mappings: where a 2D texture (bitmap, checkerboard, dots) takes its (u, v) from. `uv` (the default) is the
surface's own texture coordinates; `spherical`, `cylindrical` and `planar` make them from the surface point taken
into the texture's space (the inverse of `transform`, placed in the scene as a shape is), as pbrt-v4's
TextureMapping2D (Pharr, Jakob & Humphreys, 4th ed., 10.2): spherical (θ/π, φ/2π) of the point's direction from
the origin, cylindrical ((π + atan2(y, x))/2π, z), planar (p · v1, p · v2). Like a mesh's coordinates these are then
scaled and offset by uv_scale and uv_offset; v runs up the image, as a mesh file's v does.

Device form (TextureRows.add): the row's `mapping` code and `mapping_offset`, which points at MAPPING_FLOATS floats of
the texel buffer laid out as kernels/texture_mapping.cl states."""

from collections.abc import Iterable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from spectrace.core.parameters import Parameter
from spectrace.errors import SpectraceError

# TEXTURE_MAPPING_* of kernels/texture_mapping.cl.
MAPPINGS = {"uv": 0, "spherical": 1, "cylindrical": 2, "planar": 3}
MAPPING_FLOATS = 12

PARAMETERS = (
    Parameter(
        "mapping",
        "mapping",
        default="uv",
        doc="where (u, v) come from: `uv` the surface's texture coordinates; `spherical` (θ/π, φ/2π) of the point's "
        "direction from the texture space's origin (θ from +z, φ from +x toward +y); `cylindrical` "
        "((π + atan2(y, x))/2π, z); `planar` (p · v1, p · v2); the point taken into the texture space by the "
        "inverse of `transform`",
        type_doc='`"uv"`, `"spherical"`, `"cylindrical"` or `"planar"`',
        default_doc='`"uv"`',
    ),
    Parameter(
        "transform",
        "transform",
        default=(),
        doc="with a mapping other than `uv`: places the texture's space in the scene, as a shape's transform places "
        "the shape",
        type_doc="list of transform steps",
        default_doc="`[]`",
    ),
    Parameter("v1", "vector", default=(1.0, 0.0, 0.0), doc="`planar`: u = p · v1 (p in the texture's space)"),
    Parameter("v2", "vector", default=(0.0, 1.0, 0.0), doc="`planar`: v = p · v2 (p in the texture's space)"),
)


def to_texture_matrix(steps: Iterable[Mapping[str, Any]], where: str | None) -> np.ndarray:
    """The inverse of the placement's matrix (steps as a scene file writes them, checked as a shape's are): a
    mapped or solid texture's world-to-texture matrix."""
    from spectrace.geometry.transforms import transform_matrix

    as_dicts = [dict(step) for step in steps]
    with np.errstate(over="ignore", invalid="ignore"):
        matrix = transform_matrix(as_dicts, where=where or "transform")
    return np.linalg.inv(matrix)


def mapping_rows(mapping: str, to_texture: np.ndarray, v1=(1.0, 0.0, 0.0), v2=(0.0, 1.0, 0.0)) -> tuple:
    """The 12 floats kernels/texture_mapping.cl reads: the world-to-texture matrix's three rows, for `planar` with
    v1ᵀ and v2ᵀ times it as its first two rows (s, t the first two coordinates)."""
    rows = np.asarray(to_texture, np.float64)[:3].copy()
    if mapping == "planar":
        rows[:2] = np.stack([np.asarray(v1, np.float64), np.asarray(v2, np.float64)]) @ rows
    if not np.all(np.isfinite(rows)):
        raise SpectraceError("the mapping's transform is not invertible")
    return tuple(float(v) for v in rows.ravel())


def with_mapping(placement, spec, where: str | None):
    """The placement of a validated scene table with its mapping (`mapping`, `transform`, `v1`, `v2`)."""
    mapping = getattr(spec, "mapping", "uv")
    steps = [step.model_dump(exclude_none=True) for step in getattr(spec, "transform", ())]
    if mapping == "uv":
        if steps:
            raise SpectraceError('a transform is read with a mapping other than "uv"', where and f"{where}.transform")
        return placement
    matrix = to_texture_matrix(steps, where and f"{where}.transform")
    try:
        rows = mapping_rows(mapping, matrix, spec.v1, spec.v2)
    except SpectraceError as failure:
        raise SpectraceError(failure.message, where and f"{where}.transform") from None
    return replace(placement, mapping=mapping, mapping_rows=rows)


def api_mapping(placement, mapping: str, transform, v1, v2):
    """The placement of an API constructor's texture with its mapping (the keyword arguments `mapping`,
    `transform`: transform steps as a scene file writes them, `v1`, `v2`)."""
    if mapping not in MAPPINGS:
        known = ", ".join(repr(m) for m in MAPPINGS)
        raise SpectraceError(f"mapping must be one of {known}, got {mapping!r}", "mapping")
    steps = [dict(step) for step in transform]
    if mapping == "uv":
        if steps:
            raise SpectraceError('a transform is read with a mapping other than "uv"', "transform")
        return placement
    vectors = [np.asarray(v, np.float64) for v in (v1, v2)]
    if any(v.shape != (3,) or not np.all(np.isfinite(v)) for v in vectors):
        raise SpectraceError("v1 and v2 are three finite numbers each", "v1")
    rows = mapping_rows(mapping, to_texture_matrix(steps, "transform"), *vectors)
    return replace(placement, mapping=mapping, mapping_rows=rows)


def device_floats(placement) -> np.ndarray:
    return np.asarray(placement.mapping_rows, np.float32)
