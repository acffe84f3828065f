"""A glTF 2.0 file read as the specification lays it out (Khronos, glTF 2.0, sections 3.6-3.7 and 4.4): the JSON
of a `.gltf` or the JSON chunk of a `.glb`, its buffers (the `.glb`'s binary chunk, `data:` URIs, files beside it),
buffer views and accessors (strided, normalized integers, sparse). Every problem is one error naming the file and
the JSON pointer of what holds it (`model.glb: /accessors/3/count`)."""

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from spectrace.errors import SpectraceError

GLB_MAGIC = b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942

COMPONENT_TYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
# Divisors of normalized integer components (glTF 2.0, 3.11: "Animations", the same rule for every accessor).
NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
COMPONENT_COUNTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}

# Extensions whose data spectrace cannot decode: a file that needs them is refused naming the extension.
COMPRESSION_EXTENSIONS = ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression")
MAX_FILE_BYTES = 2**31  # a buffer or image beyond this is refused before it is read
MAX_ZERO_ELEMENTS = 2**24  # an accessor without a bufferView: its elements are zeros (or a sparse accessor's base)
FLOAT32_MAX = float(np.finfo(np.float32).max)  # the renderer's numbers are single precision


def _finite(value: object) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(float(value)) and abs(float(value)) <= FLOAT32_MAX
    except OverflowError:  # an integer beyond a double's range
        return False


def _shown(value: object) -> str:
    try:
        text = json.dumps(value)
    except (ValueError, TypeError):
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _chunk_at(data: bytes, offset: int, length: int) -> bool:
    """Whether a JSON or BIN chunk's header lies at offset."""
    return offset + 8 <= length and struct.unpack_from("<I", data, offset + 4)[0] in (CHUNK_JSON, CHUNK_BIN)


class GltfDocument:
    """The file's JSON and its buffers; `fail(pointer, message)` makes the error naming the file and pointer."""

    def __init__(self, path: Path):
        self.path = path
        self.folder = path.parent
        self.binary_chunk: bytes | None = None
        document = self._read(path)
        if not isinstance(document, dict):
            raise self.fail("", "the JSON is not an object (a glTF file holds one JSON object)")
        self.json: dict = document
        self._buffers: dict[int, bytes] = {}

    # -------------------------------------------------- errors and JSON access

    def fail(self, pointer: str, message: str) -> SpectraceError:
        return SpectraceError(message, where=f"{self.path}: {pointer or '/'}")

    def array(self, name: str) -> list:
        value = self.json.get(name, [])
        if not isinstance(value, list):
            raise self.fail(f"/{name}", "must be an array")
        return value

    def item(self, name: str, index: object, pointer: str) -> dict:
        """Entry `index` of the top-level array `name`, referred to at `pointer`."""
        items = self.array(name)
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(items):
            raise self.fail(pointer, f"refers to {name}[{index}], which does not exist ({len(items)} defined)")
        entry = items[index]
        if not isinstance(entry, dict):
            raise self.fail(f"/{name}/{index}", "must be an object")
        return entry

    def obj(self, table: object, key: str, pointer: str) -> dict:
        """table[key], which must be a JSON object ({} where absent)."""
        value = self._table(table, pointer).get(key, {})
        if not isinstance(value, dict):
            raise self.fail(f"{pointer}/{key}", f"must be an object, got {_shown(value)}")
        return value

    def extension(self, table: object, name: str, pointer: str) -> dict | None:
        """The object of extension `name` in table's `extensions`, or None where it has none."""
        extensions = self.obj(table, "extensions", pointer)
        if name not in extensions:
            return None
        return self.obj(extensions, name, f"{pointer}/extensions")

    def _table(self, table: object, pointer: str) -> dict:
        if not isinstance(table, dict):
            raise self.fail(pointer, f"must be an object, got {_shown(table)}")
        return table

    def number(self, table: object, key: str, pointer: str, default: float | None = None) -> float:
        value = self._table(table, pointer).get(key, default)
        if not _finite(value):
            raise self.fail(f"{pointer}/{key}", f"expected a finite number, got {_shown(value)}")
        return float(value)  # type: ignore[arg-type]

    def numbers(self, table: object, key: str, pointer: str, count: int, default: list[float]) -> list[float]:
        value = self._table(table, pointer).get(key, default)
        if not isinstance(value, list) or len(value) != count or not all(_finite(v) for v in value):
            raise self.fail(f"{pointer}/{key}", f"expected {count} finite numbers, got {_shown(value)}")
        return [float(v) for v in value]

    def index(self, table: object, key: str, pointer: str) -> int | None:
        value = self._table(table, pointer).get(key)
        if value is None and key not in self._table(table, pointer):
            return None
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**53:
            raise self.fail(f"{pointer}/{key}", f"expected an index (an integer >= 0), got {_shown(value)}")
        return value

    def choice(self, table: object, key: str, pointer: str, options: dict, default: object) -> object:
        """options[table[key]] for a value among the options' keys (enums: component types, wraps, modes)."""
        value = self._table(table, pointer).get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, str)) or value not in options:
            raise self.fail(
                f"{pointer}/{key}", f"unknown value {_shown(value)} (expected one of {', '.join(map(str, options))})"
            )
        return options[value]

    # -------------------------------------------------- files

    def _read(self, path: Path) -> object:
        try:
            if path.stat().st_size > MAX_FILE_BYTES:
                raise SpectraceError("is larger than 2 GiB; spectrace reads glTF files up to that", where=str(path))
            data = path.read_bytes()
        except OSError as error:
            raise SpectraceError(f"cannot read the glTF file ({error.strerror or error})", where=str(path)) from None
        if data[:4] == GLB_MAGIC:
            text = self._glb_json(data)
        else:
            text = data
        try:
            return json.loads(text.decode("utf-8-sig"))
        except UnicodeDecodeError as error:
            raise SpectraceError(f"the JSON is not UTF-8 (byte {error.start})", where=str(path)) from None
        except json.JSONDecodeError as error:
            raise SpectraceError(
                f"not a glTF file: JSON syntax error at line {error.lineno}, column {error.colno} ({error.msg})",
                where=str(path),
            ) from None
        except RecursionError:
            raise SpectraceError("JSON nested too deep to parse", where=str(path)) from None

    def _glb_json(self, data: bytes) -> bytes:
        """The JSON chunk of a binary glTF; its BIN chunk is kept as buffer 0's data (glTF 2.0, 4.4)."""
        if len(data) < 20:
            raise SpectraceError("binary glTF shorter than its 12-byte header and first chunk", where=str(self.path))
        _, version, length = struct.unpack_from("<4sII", data, 0)
        if version != 2:
            raise SpectraceError(f"binary glTF version {version}; spectrace reads version 2", where=str(self.path))
        if length > len(data):
            raise SpectraceError(
                f"binary glTF truncated: the header says {length} bytes, the file has {len(data)}", where=str(self.path)
            )
        offset, chunks = 12, []
        while offset + 8 <= length:
            size, kind = struct.unpack_from("<II", data, offset)
            if offset + 8 + size > length:
                raise SpectraceError(
                    f"binary glTF chunk at byte {offset} runs past the end of the file", where=str(self.path)
                )
            chunks.append((kind, data[offset + 8 : offset + 8 + size]))
            # A chunk's length includes its padding to 4 bytes (4.4.3), so the next begins right after it; some
            # writers leave the padding out of the length, or out of the file, and a next chunk found only
            # after the padding is read there.
            offset += 8 + size
            padded = offset + (-size % 4)
            if padded != offset and not _chunk_at(data, offset, length) and _chunk_at(data, padded, length):
                offset = padded
        if not chunks or chunks[0][0] != CHUNK_JSON:
            raise SpectraceError("binary glTF whose first chunk is not JSON", where=str(self.path))
        if len(chunks) > 1 and chunks[1][0] == CHUNK_BIN:
            self.binary_chunk = chunks[1][1]
        return chunks[0][1]

    def uri_bytes(self, uri: object, pointer: str, what: str) -> bytes:
        """The bytes a `uri` names: a base64 `data:` URI, or a file relative to the glTF file (percent-decoded)."""
        if not isinstance(uri, str):
            raise self.fail(pointer, "must be a string (a data: URI or a relative path)")
        if uri.startswith("data:"):
            header, comma, payload = uri.partition(",")
            if not comma or not header.endswith(";base64"):
                raise self.fail(pointer, "a data: URI must be base64 (data:<type>;base64,...)")
            try:
                return base64.b64decode(payload, validate=True)
            except ValueError:
                raise self.fail(pointer, "the data: URI's base64 is malformed") from None
        if "://" in uri:
            raise self.fail(pointer, f"{what} '{uri[:100]}' is remote; spectrace reads only files beside the glTF")
        path = self.folder / unquote(uri)
        try:
            if not path.is_file():
                raise self.fail(pointer, f"{what} '{path}' does not exist or is not a file")
            if path.stat().st_size > MAX_FILE_BYTES:
                raise self.fail(pointer, f"{what} '{path}' is larger than 2 GiB")
            return path.read_bytes()
        except OSError as error:
            raise self.fail(pointer, f"cannot read {what} '{path}' ({error.strerror or error})") from None

    def buffer(self, index: int, pointer: str) -> bytes:
        if index in self._buffers:
            return self._buffers[index]
        entry = self.item("buffers", index, pointer)
        where = f"/buffers/{index}"
        if "uri" in entry:
            data = self.uri_bytes(entry["uri"], f"{where}/uri", "buffer")
        elif index == 0 and self.binary_chunk is not None:
            data = self.binary_chunk
        else:
            for name in COMPRESSION_EXTENSIONS:
                if self.extension(entry, name, where) is not None:
                    raise self.fail(where, f"a fallback buffer of {name}, which spectrace does not decode")
            raise self.fail(where, "has no uri and is not the binary chunk of a .glb")
        length = self.index(entry, "byteLength", where)
        if length is None:
            raise self.fail(f"{where}/byteLength", "is required")
        if len(data) < length:
            raise self.fail(f"{where}/byteLength", f"is {length} but the buffer holds {len(data)} bytes")
        self._buffers[index] = data
        return data

    def buffer_view(self, index: int, pointer: str) -> tuple[bytes, int | None]:
        """(the bytes of a buffer view, its byteStride or None)."""
        view = self.item("bufferViews", index, pointer)
        where = f"/bufferViews/{index}"
        for name in COMPRESSION_EXTENSIONS:
            if self.extension(view, name, where) is not None:
                raise self.fail(
                    f"{where}/extensions/{name}", f"compressed with {name}, which spectrace does not decode"
                )
        buffer_index = self.index(view, "buffer", where)
        if buffer_index is None:
            raise self.fail(f"{where}/buffer", "is required")
        data = self.buffer(buffer_index, f"{where}/buffer")
        offset = self.index(view, "byteOffset", where) or 0
        length = self.index(view, "byteLength", where)
        if length is None:
            raise self.fail(f"{where}/byteLength", "is required")
        if offset + length > len(data):
            raise self.fail(where, f"bytes {offset}..{offset + length} lie beyond its buffer ({len(data)} bytes)")
        stride = self.index(view, "byteStride", where)
        return data[offset : offset + length], stride

    # -------------------------------------------------- accessors

    def accessor(self, index: int, pointer: str) -> np.ndarray:
        """An accessor's elements as float64 (normalized integers divided out) or, for unnormalized integers, as
        int64: shape (count, components)."""
        entry = self.item("accessors", index, pointer)
        where = f"/accessors/{index}"
        component = entry.get("componentType")
        dtype = np.dtype(str(self.choice(entry, "componentType", where, COMPONENT_TYPES, None)))
        components = int(str(self.choice(entry, "type", where, COMPONENT_COUNTS, None)))
        count = self.index(entry, "count", where)
        if count is None:
            raise self.fail(f"{where}/count", "is required")
        if count * components > MAX_FILE_BYTES:
            raise self.fail(f"{where}/count", f"{count} elements are more than a glTF buffer holds")
        if "bufferView" in entry:
            values = self._strided(entry, where, dtype, components, count)
        elif count > MAX_ZERO_ELEMENTS:
            # zeros that no byte of the file backs: a few bytes of JSON could ask for gigabytes
            raise self.fail(
                f"{where}/count",
                f"{count} elements without a bufferView (zeros) are more than spectrace reads ({MAX_ZERO_ELEMENTS})",
            )
        else:
            values = np.zeros((count, components), dtype=dtype)
        if "sparse" in entry:
            values = self._sparse(entry["sparse"], f"{where}/sparse", values, dtype, components)
        normalized = entry.get("normalized", False)
        if not isinstance(normalized, bool):
            raise self.fail(f"{where}/normalized", "must be true or false")
        if normalized and component in NORMALIZED_DIVISORS:
            return np.maximum(values.astype(np.float64) / NORMALIZED_DIVISORS[component], -1.0)
        if dtype.kind == "f":
            result = values.astype(np.float64)
            if not np.all(np.isfinite(result)):
                raise self.fail(where, "holds NaN or infinite numbers")
            return result
        return values.astype(np.int64)

    def _strided(self, entry: dict, where: str, dtype: np.dtype, components: int, count: int) -> np.ndarray:
        view_index = self.index(entry, "bufferView", where)
        if view_index is None:
            raise self.fail(f"{where}/bufferView", "must be an index")
        data, stride = self.buffer_view(view_index, f"{where}/bufferView")
        offset = self.index(entry, "byteOffset", where) or 0
        element = dtype.itemsize * components
        stride = stride or element
        if count and offset + (count - 1) * stride + element > len(data):
            raise self.fail(where, f"{count} elements from byte {offset} run past its buffer view ({len(data)} bytes)")
        if count == 0:
            return np.zeros((0, components), dtype=dtype)
        return np.ndarray(
            (count, components), dtype=dtype, buffer=data, offset=offset, strides=(stride, dtype.itemsize)
        ).copy()

    def _sparse(self, sparse: object, where: str, values: np.ndarray, dtype: np.dtype, components: int):
        count = self.index(sparse, "count", where) or 0
        if count > len(values):
            raise self.fail(f"{where}/count", f"{count} replacements for an accessor of {len(values)} elements")
        indices_entry, values_entry = self.obj(sparse, "indices", where), self.obj(sparse, "values", where)
        unsigned = {k: v for k, v in COMPONENT_TYPES.items() if k in (5121, 5123, 5125)}
        index_dtype = np.dtype(str(self.choice(indices_entry, "componentType", f"{where}/indices", unsigned, None)))
        indices = self._packed(indices_entry, f"{where}/indices", index_dtype, 1, count)[:, 0].astype(np.int64)
        replacements = self._packed(values_entry, f"{where}/values", dtype, components, count)
        if len(indices) and (indices.max() >= len(values)):
            raise self.fail(f"{where}/indices", f"index {int(indices.max())} beyond the accessor's {len(values)}")
        values = values.copy()
        values[indices] = replacements
        return values

    def _packed(self, entry: dict, where: str, dtype: np.dtype, components: int, count: int) -> np.ndarray:
        view_index = self.index(entry, "bufferView", where)
        if view_index is None:
            raise self.fail(f"{where}/bufferView", "is required")
        data, _ = self.buffer_view(view_index, f"{where}/bufferView")
        offset = self.index(entry, "byteOffset", where) or 0
        size = dtype.itemsize * components * count
        if offset + size > len(data):
            raise self.fail(where, f"{count} elements from byte {offset} run past its buffer view")
        return np.frombuffer(data, dtype=dtype, count=components * count, offset=offset).reshape(count, components)

    def image_bytes(self, index: int, pointer: str) -> tuple[bytes, str]:
        """(the encoded bytes of images[index], a name for messages)."""
        image = self.item("images", index, pointer)
        where = f"/images/{index}"
        if "uri" in image:
            uri = image["uri"]
            name = "embedded image" if isinstance(uri, str) and uri.startswith("data:") else str(uri)
            return self.uri_bytes(uri, f"{where}/uri", "image"), name
        view = self.index(image, "bufferView", where)
        if view is None:
            raise self.fail(where, "has neither a uri nor a bufferView")
        data, _ = self.buffer_view(view, f"{where}/bufferView")
        return data, f"image {index}"
