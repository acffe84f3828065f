"""Small glTF 2.0 files built in code for the importer's tests: arrays appended to one binary buffer as accessors,
written as a `.gltf` with a base64 data: URI or as a `.glb` with a BIN chunk (glTF 2.0, sections 3.6 and 4.4)."""

from __future__ import annotations

import base64
import io
import json
import struct
from pathlib import Path

import numpy as np

FLOAT, UINT8, UINT16, UINT32 = 5126, 5121, 5123, 5125
TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
DTYPES = {FLOAT: "<f4", UINT8: "<u1", UINT16: "<u2", UINT32: "<u4"}


class Gltf:
    def __init__(self) -> None:
        self.json: dict = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}]}
        self.data = bytearray()

    def _list(self, name: str) -> list:
        return self.json.setdefault(name, [])

    def view(self, raw: bytes, stride: int | None = None) -> int:
        self.data += b"\0" * (-len(self.data) % 4)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)}
        if stride:
            view["byteStride"] = stride
        self.data += raw
        self._list("bufferViews").append(view)
        return len(self.json["bufferViews"]) - 1

    def accessor(self, values, component: int = FLOAT, normalized: bool = False) -> int:
        array = np.asarray(values)
        array = array.reshape(len(array), -1)
        entry = {
            "bufferView": self.view(array.astype(DTYPES[component]).tobytes()),
            "componentType": component,
            "count": len(array),
            "type": TYPES[array.shape[1]],
        }
        if normalized:
            entry["normalized"] = True
        if component == FLOAT and array.shape[1] == 3:
            entry["min"], entry["max"] = array.min(0).tolist(), array.max(0).tolist()
        self._list("accessors").append(entry)
        return len(self.json["accessors"]) - 1

    def mesh(self, positions, indices=None, normals=None, uvs=None, material=None, name=None, **extra) -> int:
        attributes = {"POSITION": self.accessor(positions)}
        if normals is not None:
            attributes["NORMAL"] = self.accessor(normals)
        if uvs is not None:
            attributes["TEXCOORD_0"] = self.accessor(uvs)
        primitive: dict = {"attributes": attributes, **extra}
        if indices is not None:
            primitive["indices"] = self.accessor(np.asarray(indices).reshape(-1), UINT16)
        if material is not None:
            primitive["material"] = material
        mesh: dict = {"primitives": [primitive]}
        if name:
            mesh["name"] = name
        self._list("meshes").append(mesh)
        return len(self.json["meshes"]) - 1

    def quad(self, size: float = 1.0, material=None, name=None) -> int:
        """A square [−size, size]² in z = 0 facing +z, with texture coordinates (0, 0) at its top-left corner."""
        s = size
        positions = [[-s, -s, 0], [s, -s, 0], [s, s, 0], [-s, s, 0]]
        uvs = [[0, 1], [1, 1], [1, 0], [0, 0]]
        normals = [[0, 0, 1]] * 4
        return self.mesh(positions, [0, 1, 2, 0, 2, 3], normals, uvs, material, name)

    def node(self, root: bool = True, **entry) -> int:
        self._list("nodes").append(entry)
        index = len(self.json["nodes"]) - 1
        if root:
            self.json["scenes"][0]["nodes"].append(index)
        return index

    def material(self, **entry) -> int:
        self._list("materials").append(entry)
        return len(self.json["materials"]) - 1

    def image_texture(self, pixels: np.ndarray, sampler: dict | None = None) -> int:
        """A PNG of (h, w, c) 8-bit pixels stored in the buffer; returns the texture's index."""
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(np.asarray(pixels, dtype=np.uint8)).save(buffer, format="PNG")
        self._list("images").append({"bufferView": self.view(buffer.getvalue()), "mimeType": "image/png"})
        texture: dict = {"source": len(self.json["images"]) - 1}
        if sampler is not None:
            self._list("samplers").append(sampler)
            texture["sampler"] = len(self.json["samplers"]) - 1
        self._list("textures").append(texture)
        return len(self.json["textures"]) - 1

    def light(self, **entry) -> int:
        lights = self.json.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})["lights"]
        lights.append(entry)
        used = self._list("extensionsUsed")
        if "KHR_lights_punctual" not in used:
            used.append("KHR_lights_punctual")
        return len(lights) - 1

    def camera(self, **entry) -> int:
        self._list("cameras").append(entry)
        return len(self.json["cameras"]) - 1

    def write(self, path: Path) -> Path:
        """A .glb (binary chunk) or a .gltf (the buffer as a data: URI), by the path's suffix."""
        document = json.loads(json.dumps(self.json))
        data = bytes(self.data) + b"\0" * (-len(self.data) % 4)
        if data:
            document["buffers"] = [{"byteLength": len(data)}]
        if path.suffix == ".glb":
            text = json.dumps(document).encode()
            text += b" " * (-len(text) % 4)
            chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
            if data:
                chunks += struct.pack("<II", len(data), 0x004E4942) + data
            path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)
        else:
            if data:
                document["buffers"][0]["uri"] = (
                    "data:application/octet-stream;base64," + base64.b64encode(data).decode()
                )
            path.write_text(json.dumps(document))
        return path
