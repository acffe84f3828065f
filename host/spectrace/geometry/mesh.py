"""Indexed triangle meshes, and reading them from any file format trimesh understands."""

import io
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.io.input_files import regular_file


@dataclass
class TriangleMesh:
    """Triangles in scene units; face winding (counter-clockwise seen from the front) defines the front side.

    The geometric normal of face i is (v1 - v0) x (v2 - v0), normalised, with vk = vertices[faces[i, k]].
    """

    vertices: np.ndarray  # (N, 3) float64
    faces: np.ndarray  # (M, 3) int64 indices into vertices
    uvs: np.ndarray | None = None  # (N, 2) texture coordinates per vertex: u to the right, v down the image

    def __post_init__(self) -> None:
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int64)
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float64)
            if self.uvs.shape != (len(self.vertices), 2):
                raise ValueError(f"uvs must be (N, 2) like the vertices, got {self.uvs.shape}")
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            raise ValueError(f"vertices must be (N, 3), got {self.vertices.shape}")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise ValueError(f"faces must be (M, 3), got {self.faces.shape}")

    def triangles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Corner positions (v0, v1, v2), each (M, 3) float64."""
        return tuple(self.vertices[self.faces[:, k]] for k in range(3))

    def triangle_uvs(self) -> np.ndarray:
        """(M, 3, 2) texture coordinates of each triangle's corners (zeros when the mesh has none)."""
        if self.uvs is None:
            return np.zeros((len(self.faces), 3, 2))
        return self.uvs[self.faces]

    def triangle_areas(self) -> np.ndarray:
        """(M,) area of each triangle, in scene units squared."""
        v0, v1, v2 = self.triangles()
        return 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)

    def area(self) -> float:
        """Total surface area, in scene units squared."""
        return float(self.triangle_areas().sum())


# Files at least this large announce themselves on stderr with their size, then say how long they took: a
# mesh of some million triangles takes seconds to parse, which should not look like a hang.
PROGRESS_MIN_BYTES = 50 * 2**20
PROGRESS_ENVIRONMENT = "SPECTRACE_MESH_PROGRESS_MB"  # overrides the threshold, in MB (0: always)

# OBJ indices start at 1; trimesh silently reads a face index 0 as the first vertex, making a degenerate
# triangle. The file is scanned for it in chunks with numpy (Python's re takes seconds per 50 MB).
_OBJ_SCAN_CHUNK = 32 * 2**20


def _is_any(values: np.ndarray, characters: bytes) -> np.ndarray:
    result = values == characters[0]
    for character in characters[1:]:
        result |= values == character
    return result


def _zero_index_in_face_line(chunk: np.ndarray) -> int | None:
    """Offset in `chunk` (whole lines) of the first face-line field that reads 0, or None. Fields of a face
    line are separated by blanks (corners) and '/' (v/vt/vn of a corner)."""
    if len(chunk) < 2:
        return None
    starts_field = chunk[1:] == ord("0")
    starts_field &= _is_any(chunk[:-1], b" \t/")
    zeros = np.flatnonzero(starts_field) + 1
    after = np.append(chunk, np.uint8(ord("\n")))[zeros + 1]
    zeros = zeros[_is_any(after, b" \t/\r\n")]
    if len(zeros) == 0:
        return None
    newlines = np.flatnonzero(chunk == ord("\n"))
    previous = np.searchsorted(newlines, zeros) - 1
    line_starts = np.where(previous >= 0, newlines[np.maximum(previous, 0)] + 1, 0)
    padded = np.append(chunk, np.zeros(2, np.uint8))
    in_face = (padded[line_starts] == ord("f")) & _is_any(padded[line_starts + 1], b" \t")
    return int(zeros[in_face][0]) if in_face.any() else None


def _scan_obj(data: bytes, path: Path, where: str) -> bool:
    """Refuses a face index 0 in the OBJ text `data` (naming its line); says whether it has texture coordinates
    (vt). Scanned in chunks of whole lines, so that numpy's temporary arrays stay small."""
    start, lines_before = 0, 0
    while start < len(data):
        end = min(start + _OBJ_SCAN_CHUNK, len(data))
        if end < len(data):  # whole lines only: up to the chunk's last line break (or past a longer line)
            last = data.rfind(b"\n", start, end)
            end = last + 1 if last >= start else (data.find(b"\n", end) + 1 or len(data))
        chunk = np.frombuffer(data, np.uint8, count=end - start, offset=start)
        if (offset := _zero_index_in_face_line(chunk)) is not None:
            line = lines_before + data.count(b"\n", start, start + offset) + 1
            raise SpectraceError(f"mesh file '{path}' line {line}: face index 0 (OBJ indices start at 1)", where=where)
        lines_before += data.count(b"\n", start, end)
        start = end
    return data.startswith((b"vt ", b"vt\t")) or b"\nvt " in data or b"\nvt\t" in data


_PLAIN_OBJ_MAX_BYTES = 4_000_000


def _progress_min_bytes() -> float:
    text = os.environ.get(PROGRESS_ENVIRONMENT)
    try:
        return float(text) * 1e6 if text else PROGRESS_MIN_BYTES
    except ValueError:
        return PROGRESS_MIN_BYTES


def load_mesh(path: Path, where: str) -> TriangleMesh:
    """Read a mesh file (OBJ, PLY, STL, GLB, OFF, ...); a file holding several meshes is merged into one.

    Vertex order and face winding are kept as stored, except that an OBJ vertex used with several texture
    coordinates becomes one vertex per coordinate. Every failure raises SpectraceError naming `where`.
    """
    path = regular_file(path, where, what="mesh file")
    size = path.stat().st_size
    announce = size >= _progress_min_bytes()
    if announce:
        print(f"loading mesh '{path}' ({size / 1e6:.1f} MB)...", file=sys.stderr, flush=True)
    started = time.perf_counter()
    # An OBJ file is read once, here: its checks (_scan_obj), the plain reader and trimesh all parse these bytes.
    data = _read_bytes(path, where) if path.suffix.lower() == ".obj" else None
    # Small plain OBJ files are read here: importing trimesh costs more than a small render. Large ones go to
    # trimesh, whose vectorised reader beats a Python loop over millions of lines.
    if data is not None and size <= _PLAIN_OBJ_MAX_BYTES and (simple := _plain_triangle_obj(path, data)) is not None:
        mesh = _validated_mesh(*simple, path, where)
    else:
        mesh = _mesh_through_trimesh(path, where, data)
    if announce:
        print(
            f"loaded mesh '{path}': {len(mesh.faces):,} triangles in {time.perf_counter() - started:.1f} s",
            file=sys.stderr,
            flush=True,
        )
    return mesh


def _read_bytes(path: Path, where: str) -> bytes:
    try:
        return path.read_bytes()
    except OSError as error:
        raise SpectraceError(f"cannot read mesh file '{path}' ({error.strerror or error})", where=where) from None


def _mesh_through_trimesh(path: Path, where: str, obj_data: bytes | None = None) -> TriangleMesh:
    """The mesh trimesh reads from `path`, or, for an OBJ file, from its bytes `obj_data` already read."""
    import trimesh  # deferred: importing trimesh (and with it SciPy) costs about half a second

    # process=False and maintain_order=True: no merging, reordering or re-winding behind our back.
    options: dict[str, Any] = {"process": False, "maintain_order": True}
    source: Any = path
    if obj_data is not None:
        # With vt, trimesh keeps the stored order only by giving a vertex one of its texture coordinates (at a
        # texture seam the others are lost); splitting such vertices keeps every corner's own coordinate.
        # Materials are not used, and skipping them spares decoding the textures an .mtl names.
        options |= {"maintain_order": not _scan_obj(obj_data, path, where), "skip_materials": True}
        options |= {"file_type": "obj", "resolver": trimesh.resolvers.FilePathResolver(str(path))}
        source = io.BytesIO(obj_data)
    try:
        scene = trimesh.load_scene(source, **options)
        loaded = scene.to_mesh()
    except Exception as error:  # trimesh raises many unrelated types for unreadable files
        detail = " ".join(str(error).split()) or type(error).__name__
        if isinstance(error, (ImportError, UnicodeError)):  # trimesh guessing the text encoding of binary junk
            detail = f"its content is not a valid {path.suffix.lstrip('.').upper() or 'mesh'} file"
        raise SpectraceError(f"cannot read mesh file '{path}': {detail}", where=where) from None
    mesh = _validated_mesh(np.asarray(loaded.vertices), np.asarray(loaded.faces), path, where)
    uv = getattr(getattr(loaded, "visual", None), "uv", None)
    if uv is not None and len(uv) == len(mesh.vertices) and np.all(np.isfinite(uv)):
        # Mesh files store v upward (OpenGL); spectrace's v runs down the image.
        mesh.uvs = np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float64)
    return mesh


def _plain_triangle_obj(path: Path, data: bytes | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and faces of an OBJ file holding only `v x y z` and `f i j k` lines (positive indices, no
    texture coordinates or normals) and comments, read directly, as trimesh reads them with process=False and
    maintain_order=True (a test checks the bundled meshes both ways); None for anything else, which trimesh
    reads. Importing trimesh costs more than a small render. `data`: the file's bytes, when already read."""
    vertices, faces = [], []
    try:
        text = (data if data is not None else path.read_bytes()).decode("utf-8")
    except (OSError, UnicodeError):
        return None
    try:
        for line in text.splitlines():
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] == "v" and len(fields) == 4:
                vertices.append([float(x) for x in fields[1:]])
            elif fields[0] == "f" and len(fields) == 4 and all(f.isdigit() and int(f) > 0 for f in fields[1:]):
                faces.append([int(i) - 1 for i in fields[1:]])
            else:
                return None
    except ValueError:
        return None
    if not vertices or not faces:
        return None
    return np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)


def _validated_mesh(vertices: np.ndarray, faces: np.ndarray, path: Path, where: str) -> TriangleMesh:
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise SpectraceError(f"mesh file '{path}' contains no triangles", where=where)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise SpectraceError(f"mesh file '{path}' has faces that index missing vertices", where=where)
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        raise SpectraceError(
            f"mesh file '{path}' has {int(bad.sum())} vertices with NaN or infinite coordinates "
            f"(first: vertex {int(np.flatnonzero(bad)[0])})",
            where=where,
        )
    return TriangleMesh(vertices=vertices, faces=faces)
