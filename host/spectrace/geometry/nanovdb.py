"""NanoVDB files (.nvdb, pbrt-v4's `nanovdb` medium): their float grids read into the dense voxel grids spectrace's
media render (grid_volume.GridVolume).

The format is NanoVDB's (Museth 2021, "NanoVDB: A GPU-Friendly and Portable VDB Data Structure"; read in its
public headers, NanoVDB.h and PNanoVDB.h, to learn the layout): a file header (magic, version, grid count, codec),
then per grid a fixed metadata record, its name and its buffer, uncompressed or zlib-compressed (codec ZIP; Blosc
is refused). A grid's buffer holds the grid record (its index → world map), the tree record (offsets of the node
arrays), the root (background value and tiles, each a constant or an upper node of 4096³ voxels), upper nodes of
32³ children (lower nodes or constant tiles of 128³ voxels), lower nodes of 16³ children (leaves or tiles of 8³),
and leaves of 8³ values, z fastest. Child offsets are relative to the parent node. Only float grids (grid type 1)
of NanoVDB 32.x are read.

A grid's values sit at integer index coordinates and NanoVDB's trilinear sampler (pbrt-v4's) interpolates between
them, reading the background beyond the stored voxels: the dense grid spans the stored index box grown by one voxel
of background on each side, its voxel centres on the integer coordinates, so spectrace's lookups (voxel centres,
clamped at the box's faces, nothing outside) read the same values everywhere.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import MAX_VOXELS, box_matrix

_MAGICS = (0x304244566F6E614E, 0x314244566F6E614E, 0x324244566F6E614E)  # "NanoVDB0", "NanoVDB1", "NanoVDB2"
_FILE_HEADER = struct.Struct("<QIHH")  # magic, version, grid count, codec
# gridSize, fileSize, nameKey, voxelCount, gridType, gridClass, worldBBox[6], indexBBox[6], voxelSize[3],
# nameSize, nodeCount[4], tileCount[3], codec, padding, version
_GRID_METADATA = struct.Struct("<QQQQII6d6i3dI4I3IHHI")
_CODECS = {0: "none", 1: "ZIP", 2: "BLOSC"}
_FLOAT = 1
_GRID_TYPES = {0: "unknown", 1: "float", 2: "double", 3: "int16", 4: "int32", 5: "int64", 6: "vec3f", 7: "vec3d"}
_MAJOR = 32

# Byte offsets within a float grid's buffer (the grid record, the tree record, and each node kind).
_GRID_OFF_VERSION, _GRID_OFF_MAP_MATD, _GRID_OFF_MAP_VECD, _GRID_OFF_TYPE = 16, 296 + 88, 296 + 232, 636
_TREE = 672
_ROOT_OFF_TABLE_SIZE, _ROOT_OFF_BACKGROUND, _ROOT_SIZE, _ROOT_TILE_SIZE = 24, 28, 64, 32
_UPPER_OFF_CHILD_MASK, _UPPER_OFF_TABLE = 4128, 8256
_LOWER_OFF_CHILD_MASK, _LOWER_OFF_TABLE = 544, 1088
_LEAF_OFF_VALUES = 96


@dataclass(frozen=True)
class NanoGrid:
    """One float grid: its name, index → world map (4×4), background value and stored index box (inclusive), and
    the buffer it came from (for `dense`)."""

    name: str
    index_to_world: np.ndarray
    background: float
    index_min: tuple[int, int, int]
    index_max: tuple[int, int, int]
    buffer: bytes

    def dense(self, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """The values over index box [low, high] (inclusive), shaped (nz, ny, nx), x fastest: the background where
        nothing is stored, tiles' constants, leaves' values."""
        low, high = np.asarray(low, np.int64), np.asarray(high, np.int64)
        out = np.full(tuple((high - low + 1)[::-1]), self.background, np.float32)
        data = self.buffer

        def fill(origin: np.ndarray, size: int, value) -> None:
            """Write `value` (a number, or an (x, y, z)-indexed block of `size`³) over the cube at `origin`."""
            a = np.maximum(origin, low)
            b = np.minimum(origin + size - 1, high)
            if np.any(a > b):
                return
            lo, hi = a - low, b - low + 1
            target = out[lo[2] : hi[2], lo[1] : hi[1], lo[0] : hi[0]]
            if np.isscalar(value):
                target[...] = value
            else:
                s, e = a - origin, b - origin + 1
                target[...] = value[s[0] : e[0], s[1] : e[1], s[2] : e[2]].transpose(2, 1, 0)

        def mask(address: int, count: int) -> np.ndarray:
            words = np.frombuffer(data, "<u8", count // 64, address)
            return np.unpackbits(words.view(np.uint8), bitorder="little").astype(bool)

        def node(address: int, origin: np.ndarray, log2dim: int, child_span: int, level: int) -> None:
            """An upper (level 2) or lower (level 1) node: its tiles, then its children."""
            count = 1 << (3 * log2dim)
            child_offset, table_offset = (
                (_UPPER_OFF_CHILD_MASK, _UPPER_OFF_TABLE) if level == 2 else (_LOWER_OFF_CHILD_MASK, _LOWER_OFF_TABLE)
            )
            children = mask(address + child_offset, count)
            table = np.frombuffer(data, "<i8", count, address + table_offset)
            values = np.frombuffer(data, "<f4", 2 * count, address + table_offset)[::2]
            n = np.arange(count)
            dim = 1 << log2dim
            offsets = np.stack([n >> (2 * log2dim), (n >> log2dim) & (dim - 1), n & (dim - 1)], axis=1) * child_span
            for i in np.flatnonzero(~children):
                if values[i] != self.background:
                    fill(origin + offsets[i], child_span, float(values[i]))
            for i in np.flatnonzero(children):
                child_origin = origin + offsets[i]
                if np.any(child_origin > high) or np.any(child_origin + child_span - 1 < low):
                    continue
                if level == 2:
                    node(address + int(table[i]), child_origin, 4, 8, 1)
                else:
                    leaf = np.frombuffer(data, "<f4", 512, address + int(table[i]) + _LEAF_OFF_VALUES)
                    fill(child_origin, 8, leaf.reshape(8, 8, 8))

        tree = np.frombuffer(data, "<u8", 4, _TREE)
        root = _TREE + int(tree[3])
        tile_count = struct.unpack_from("<I", data, root + _ROOT_OFF_TABLE_SIZE)[0]
        for t in range(tile_count):
            tile = root + _ROOT_SIZE + t * _ROOT_TILE_SIZE
            key, child, _state, value = struct.unpack_from("<QqIf", data, tile)
            origin = np.array([(key >> 42) & 0x1FFFFF, (key >> 21) & 0x1FFFFF, key & 0x1FFFFF], np.int64) << 12
            origin = np.where(origin >= 1 << 31, origin - (1 << 32), origin)  # the coordinates' int32 bits
            if child:
                if not (np.any(origin > high) or np.any(origin + 4095 < low)):
                    node(root + child, origin, 5, 128, 2)
            elif value != self.background:
                fill(origin, 4096, float(value))
        return out

    def dense_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The stored voxels and one voxel of background around them, shaped (nz, ny, nx), and the 4×4 map of the
        unit box onto them in world space (voxel centres on the integer index coordinates)."""
        low = np.array(self.index_min) - 1
        high = np.array(self.index_max) + 1
        values = self.dense(low, high)
        return values, self.index_to_world @ box_matrix(low - 0.5, high + 0.5)


def read_nanovdb(path: Path, where: str) -> dict[str, NanoGrid]:
    """The float grids of a NanoVDB file by name (uncompressed or ZIP); `where` names the file and key in the
    one-line errors. Grids of other value types are left out; Blosc compression and other NanoVDB versions are
    refused."""
    name = Path(path).name
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise SpectraceError(f"cannot read the NanoVDB file '{name}': {exc.strerror or exc}", where=where) from None
    if len(data) < _FILE_HEADER.size or _FILE_HEADER.unpack_from(data)[0] not in _MAGICS:
        raise SpectraceError(f"'{name}' is not a NanoVDB file (it does not start with NanoVDB's magic)", where=where)
    _, version, grid_count, _codec = _FILE_HEADER.unpack_from(data)
    if version >> 21 != _MAJOR:
        raise SpectraceError(
            f"'{name}' is NanoVDB version {version >> 21}.{(version >> 10) & 0x7FF} (spectrace reads {_MAJOR}.x)",
            where=where,
        )
    grids: dict[str, NanoGrid] = {}
    offset = _FILE_HEADER.size
    for _ in range(grid_count):
        if offset + _GRID_METADATA.size > len(data):
            raise SpectraceError(f"the NanoVDB file '{name}' ends inside a grid's record", where=where)
        meta = _GRID_METADATA.unpack_from(data, offset)
        grid_size, file_size, grid_type, name_size, codec = meta[0], meta[1], meta[4], meta[21], meta[-3]
        offset += _GRID_METADATA.size
        grid_name = data[offset : offset + name_size].split(b"\0")[0].decode("utf-8", "replace")
        offset += name_size
        if codec == 1:
            # a ZIP grid is its compressed size, then the zlib stream (writers differ on whether the record's
            # fileSize counts the size itself: the size read here says where the next grid starts)
            if offset + 8 > len(data):
                raise SpectraceError(f"the NanoVDB file '{name}' ends inside grid '{grid_name}'", where=where)
            file_size = 8 + struct.unpack_from("<Q", data, offset)[0]
        stored = data[offset : offset + file_size]
        offset += file_size
        if len(stored) != file_size:
            raise SpectraceError(f"the NanoVDB file '{name}' ends inside grid '{grid_name}'", where=where)
        if grid_type != _FLOAT:
            continue
        if codec == 1:
            try:
                buffer = zlib.decompress(stored[8:])
            except zlib.error as exc:
                raise SpectraceError(
                    f"grid '{grid_name}' of '{name}' does not decompress: {exc}", where=where
                ) from None
        elif codec == 0:
            buffer = stored
        else:
            raise SpectraceError(
                f"grid '{grid_name}' of '{name}' is compressed with {_CODECS.get(codec, codec)} (spectrace reads"
                " uncompressed and ZIP NanoVDB files; rewrite it with nanovdb_convert or NanoVDB's tools)",
                where=where,
            )
        if len(buffer) != grid_size or len(buffer) < _TREE + 64:
            raise SpectraceError(
                f"grid '{grid_name}' of '{name}' has {len(buffer)} bytes, not {grid_size}", where=where
            )
        matrix = np.eye(4)
        matrix[:3, :3] = np.frombuffer(buffer, "<f8", 9, _GRID_OFF_MAP_MATD).reshape(3, 3)
        matrix[:3, 3] = np.frombuffer(buffer, "<f8", 3, _GRID_OFF_MAP_VECD)
        # the root's own box of stored values (the file's record of it may be left unset by some writers)
        root = _TREE + int(np.frombuffer(buffer, "<u8", 1, _TREE + 24)[0])
        index_box = struct.unpack_from("<6i", buffer, root)
        background = struct.unpack_from("<f", buffer, root + _ROOT_OFF_BACKGROUND)[0]
        low, high = np.array(index_box[:3]), np.array(index_box[3:])
        if np.any(low > high):  # no stored value: one voxel of background
            low = high = np.zeros(3, np.int64)
        voxels = int(np.prod(high - low + 3))
        if voxels > MAX_VOXELS:
            raise SpectraceError(
                f"grid '{grid_name}' of '{name}' spans {voxels} voxels densely, more than the {MAX_VOXELS} a grid may"
                " have",
                where=where,
            )
        corners = ((int(low[0]), int(low[1]), int(low[2])), (int(high[0]), int(high[1]), int(high[2])))
        grids[grid_name] = NanoGrid(grid_name, matrix, float(background), *corners, buffer)
    return grids


def nanovdb_grid(path: Path, grid: str, where: str) -> NanoGrid:
    """The float grid named `grid` of a NanoVDB file (or its only float grid when it has one and none is named
    so)."""
    grids = read_nanovdb(path, where)
    if grid in grids:
        return grids[grid]
    if len(grids) == 1 and grid == "density":
        return next(iter(grids.values()))
    held = ", ".join(f"'{g}'" for g in grids) or "none"
    raise SpectraceError(f"'{Path(path).name}' has no float grid '{grid}' (its float grids: {held})", where=where)
