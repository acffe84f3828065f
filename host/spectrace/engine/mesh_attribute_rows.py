"""The device tables of a scene's mesh attribute textures (textures/mesh_attribute.py), written once the triangles'
slots are known: for each such texture's row, one entry per triangle slot (TriangleInfo's) holding where that
triangle's values lie in the texel buffer, or -1, then the values of every triangle of the meshes that wear the
texture, as kernels/texture_mesh_attribute.cl reads them. Each mesh is checked against the texture's uses here, where
its values are first at hand: a missing attribute, a colour where a number is needed, or values beyond a use's range
are refused naming the shape."""

from collections.abc import Iterator

import numpy as np

from spectrace.core.contract import STORAGE_FLOAT, TEXEL_SCALAR, TEXEL_SIGMOID
from spectrace.errors import SpectraceError


def _inner(texture) -> Iterator:
    """The texture and the textures it is made of (a composite's sides and operands)."""
    yield texture
    for name in ("operands", "sides"):
        parts = getattr(texture, name, None)
        if isinstance(parts, tuple):
            for part in parts:
                yield from _inner(part)
    for name in ("color0", "color1", "inside", "outside"):
        if hasattr(texture, name):
            yield from _inner(getattr(texture, name))


def material_wears(material, texture) -> bool:
    """Whether `material` (its parameters, surface detail, a mix's materials) reads `texture` anywhere."""
    from spectrace.materials import material_textures

    if material is None:
        return False
    return any(part is texture for used in material_textures(material).values() for part in _inner(used))


def _shape_where(shape) -> str:
    return f"shape '{shape.name}'" if shape.name else "a shape"


def write_attribute_tables(
    textures, texel_chunks: list[np.ndarray], meshed: list, order: np.ndarray, slot_count: int, others: list
) -> None:
    """Fills the rows `textures` (TextureRows) keeps in attribute_rows. `meshed`: the scene's own triangle meshes
    as (shape, first triangle, count) in the order their triangles were concatenated, `order` the BVH's permutation
    of those triangles (slot k holds triangle order[k]); `others`: the shapes without triangle slots of their own
    here (analytic shapes, instanced objects' shapes), which cannot wear a mesh attribute."""
    textures.attributes_written = True
    if not textures.attribute_rows:
        return
    from spectrace.spectral.rgb_texture import texture_reflectance_coefficients

    slot_of = np.empty(len(order), np.int64)
    slot_of[order] = np.arange(len(order))
    for row_index, texture, _kind in textures.attribute_rows:
        for shape in others:
            if material_wears(shape.material, texture):
                raise SpectraceError(
                    f"{_shape_where(shape)} wears mesh attribute '{texture.attribute}' but is not a triangle mesh of "
                    "the scene's own (an analytic or instanced shape has no mesh attributes)"
                )
        start = 4 * sum(len(chunk) for chunk in texel_chunks)  # in floats
        table = np.full((slot_count + 3) // 4 * 4, -1, np.int32)
        records, channels, at = [], None, start + len(table)
        for shape, first, count in meshed:
            if not material_wears(shape.material, texture):
                continue
            values = (shape.mesh.attributes or {}).get(texture.attribute)
            if values is None:
                names = ", ".join(shape.mesh.attributes or {}) or "none"
                raise SpectraceError(
                    f"{_shape_where(shape)}'s mesh has no attribute '{texture.attribute}' (it has: {names}), which "
                    "its material's mesh_attribute texture reads"
                )
            from spectrace.textures.mesh_attribute import use_problem

            if (problem := use_problem(texture, values)) is not None:
                where, why = problem
                raise SpectraceError(f"{_shape_where(shape)}'s attribute '{texture.attribute}' {why}", where=where)
            if channels is not None and values.shape[1] != channels:
                raise SpectraceError(
                    f"{_shape_where(shape)}'s attribute '{texture.attribute}' has {values.shape[1]} channels where "
                    f"another mesh wearing the same texture has {channels}"
                )
            channels = values.shape[1]
            corners = shape.mesh.corner_attribute(texture.attribute)  # (M, 3, C)
            if texture.face:
                corners = corners[:, :1]
            if channels == 3:
                corners = texture_reflectance_coefficients(np.clip(corners, 0.0, 1.0))
            block = np.asarray(corners, np.float32).reshape(count, -1)
            table[slot_of[first : first + count]] = at + block.shape[1] * np.arange(count)
            records.append(block.ravel())
            at += block.size
        stored = np.concatenate(records) if records else np.zeros(0, np.float32)
        chunk = np.zeros(((len(table) + len(stored) + 3) // 4, 4), np.float32)
        chunk.view(np.int32).ravel()[: len(table)] = table  # offsets as int bits
        chunk.ravel()[len(table) : len(table) + len(stored)] = stored
        texel_chunks.append(chunk)
        textures.bytes += chunk.nbytes
        row = textures.rows[row_index]
        row["data_offset"] = start
        row["texel_format"] = TEXEL_SIGMOID if channels == 3 else TEXEL_SCALAR
        row["channels"] = channels or 1
        row["width"] = 1 if texture.face else 3  # values per record: corners
        row["height"] = row["levels"] = 1
        row["storage"] = STORAGE_FLOAT
