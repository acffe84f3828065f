"""Indexed triangle meshes, and reading them from any file format trimesh understands."""

import io
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from spectrace.core.equality import fields_equal
from spectrace.errors import SpectraceError
from spectrace.io.compressed import COMPRESSED_SUFFIXES, file_inflater
from spectrace.io.input_files import regular_file


def faces_problem(faces: np.ndarray, vertex_count: int) -> str | None:
    """Why (M, 3) `faces` do not all index one of `vertex_count` vertices, or None. numpy would read a negative
    index from the end of the vertices, a wrong triangle drawn without a word, and fail on one past it only when
    the triangles are gathered."""
    if faces.size == 0:
        return None
    low, high = int(faces.min()), int(faces.max())
    if low >= 0 and high < vertex_count:
        return None
    return (
        f"faces index vertex {low if low < 0 else high}, outside the {vertex_count} vertices "
        f"(indices 0..{vertex_count - 1})"
    )


@dataclass
class TriangleMesh:
    """Triangles in scene units. The front side is the one the vertex normals point to where the mesh has them,
    else the one its winding shows counter-clockwise (corners() makes the two agree for the renderer).

    The geometric normal of face i is (v1 - v0) x (v2 - v0), normalised, with vk = vertices[faces[i, k]].
    """

    vertices: np.ndarray  # (N, 3) float64
    faces: np.ndarray  # (M, 3) int64 indices into vertices
    uvs: np.ndarray | None = None  # (N, 2) texture coordinates per vertex: u to the right, v down the image
    # (N, 3) shading normals per vertex, interpolated across each face (smooth shading); None: every face shades
    # with its geometric normal. Any length; a zero one stands for the face normal at that corner.
    normals: np.ndarray | None = None
    # (N, 4) tangents per vertex as glTF 2.0 stores them (3.7.2.1): xyz along +u in the surface, w = ±1 the
    # handedness, the bitangent being cross(normal, xyz) · w. Used with the vertex normals only (a flat face has no
    # normal to make them orthogonal to); None: the frame follows each triangle's dp/du.
    tangents: np.ndarray | None = None
    # Named per-vertex and per-face values, as Mitsuba 3 names a mesh's attributes: "vertex_<name>" (N, C) values
    # interpolated across each face, "face_<name>" (M, C) one value per face; C is 1 or 3. What a
    # `mesh_attribute` texture reads (textures/mesh_attribute.py).
    attributes: dict[str, np.ndarray] | None = None

    __eq__ = fields_equal  # arrays compared by value: two meshes (and the shapes holding them) compare as equal

    def __repr__(self) -> str:
        # The dataclass's own repr would print the arrays.
        extras = "".join(f", {name}" for name in ("uvs", "normals", "tangents") if getattr(self, name) is not None)
        extras += "".join(f", {name}" for name in self.attributes or {})
        return f"TriangleMesh({len(self.vertices)} vertices, {len(self.faces)} faces{extras})"

    def __post_init__(self) -> None:
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int64)
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float64)
            if self.uvs.shape != (len(self.vertices), 2):
                raise ValueError(f"uvs must be (N, 2) like the vertices, got {self.uvs.shape}")
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=np.float64)
            if self.normals.shape != (len(self.vertices), 3):
                raise ValueError(f"normals must be (N, 3) like the vertices, got {self.normals.shape}")
            if not np.all(np.isfinite(self.normals)):
                raise ValueError("normals must be finite")
        if self.tangents is not None:
            self.tangents = np.ascontiguousarray(self.tangents, dtype=np.float64)
            if self.tangents.shape != (len(self.vertices), 4):
                raise ValueError(f"tangents must be (N, 4) like the vertices, got {self.tangents.shape}")
            if not np.all(np.isfinite(self.tangents)):
                raise ValueError("tangents must be finite")
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            raise ValueError(f"vertices must be (N, 3), got {self.vertices.shape}")
        if self.attributes is not None:
            self.attributes = {name: self._checked_attribute(name, values) for name, values in self.attributes.items()}
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise ValueError(f"faces must be (M, 3), got {self.faces.shape}")
        if problem := faces_problem(self.faces, len(self.vertices)):
            raise ValueError(problem)

    def _checked_attribute(self, name: str, values: np.ndarray) -> np.ndarray:
        values = np.asarray(values, dtype=np.float64)
        if values.ndim == 1:
            values = values[:, None]
        count = {"vertex": len(self.vertices), "face": len(self.faces)}.get(name.split("_", 1)[0])
        if count is None or "_" not in name:
            raise ValueError(f"attribute '{name}': an attribute's name starts with vertex_ or face_")
        if values.shape not in ((count, 1), (count, 3)):
            raise ValueError(f"attribute '{name}' must be ({count},), ({count}, 1) or ({count}, 3), got {values.shape}")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"attribute '{name}' must be finite")
        return np.ascontiguousarray(values)

    def corner_attribute(self, name: str) -> np.ndarray:
        """(M, 3, C) values of attribute `name` at each triangle's corners, in the order corners() gives them (a
        face attribute's value at all three): what the renderer interpolates with the hit's barycentrics."""
        values = (self.attributes or {})[name]
        if name.startswith("face_"):
            return np.repeat(values[:, None, :], 3, axis=1)
        corners = values[self.faces]
        normals = self.triangle_normals()
        if normals is not None:
            back = winding_against_normals(*self.triangles(), normals)
            corners[back] = corners[back][:, [0, 2, 1]]
        return corners

    def triangles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Corner positions (v0, v1, v2), each (M, 3) float64."""
        return tuple(self.vertices[self.faces[:, k]] for k in range(3))

    def triangle_uvs(self) -> np.ndarray:
        """(M, 3, 2) texture coordinates of each triangle's corners (zeros when the mesh has none)."""
        if self.uvs is None:
            return np.zeros((len(self.faces), 3, 2))
        return self.uvs[self.faces]

    def triangle_normals(self) -> np.ndarray | None:
        """(M, 3, 3) unit shading normals of each triangle's corners; None when the mesh has no vertex normals.
        A zero normal becomes the face's geometric normal (a degenerate face's corners keep zero)."""
        if self.normals is None:
            return None
        corners = self.normals[self.faces]
        length = np.linalg.norm(corners, axis=-1, keepdims=True)
        np.divide(corners, length, out=corners, where=length > 0)
        # Face normals only for the few triangles with a zero corner: a million-triangle mesh would otherwise
        # gather all its corners and take their cross products again for nothing.
        missing = np.flatnonzero(~(length > 0).all(axis=(1, 2)))
        if len(missing):
            v0, v1, v2 = (self.vertices[self.faces[missing, k]] for k in range(3))
            face = np.cross(v1 - v0, v2 - v0)
            face_length = np.linalg.norm(face, axis=-1, keepdims=True)
            face = np.divide(face, face_length, out=np.zeros_like(face), where=face_length > 0)
            corners[missing] = np.where(length[missing] > 0, corners[missing], face[:, None, :])
        return corners

    def corners(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """Each triangle's corners as the renderer takes them: positions v0, v1, v2 (each (M, 3)), texture
        coordinates (M, 3, 2) and unit shading normals (M, 3, 3; None without vertex normals), with corners 1 and 2
        swapped on the triangles wound against their normals (winding_against_normals), so that every decision
        the renderer takes by the winding (one-sided materials and lights, a dielectric's or a medium's inside)
        follows the normals, as the shading does."""
        v0, v1, v2 = self.triangles()
        uvs, normals = self.triangle_uvs(), self.triangle_normals()
        if normals is not None:
            back = winding_against_normals(v0, v1, v2, normals)
            if back.any():
                v1, v2 = np.where(back[:, None], v2, v1), np.where(back[:, None], v1, v2)
                uvs[back] = uvs[back][:, [0, 2, 1]]
                normals[back] = normals[back][:, [0, 2, 1]]
        return v0, v1, v2, uvs, normals

    def corner_tangents(self) -> np.ndarray | None:
        """(M, 3, 4) tangents of each triangle's corners in the order corners() gives them (corners 1 and 2 swapped
        where it swaps them); None when the mesh has no tangents or no vertex normals to go with them."""
        if self.tangents is None or self.normals is None:
            return None
        tangents = self.tangents[self.faces]
        normals = self.triangle_normals()
        assert normals is not None  # checked above
        back = winding_against_normals(*self.triangles(), normals)
        tangents[back] = tangents[back][:, [0, 2, 1]]
        return tangents

    def flipped(self) -> "TriangleMesh":
        """The same surface with its front on the other side: the winding reversed and the vertex normals turned
        (a shape's `flip_normals`, Mitsuba 3's alike: both its normals change sign). The tangents keep their
        direction and change handedness, so the bitangent cross(normal, tangent) · w keeps pointing where the
        texture's v does."""
        normals = None if self.normals is None else -self.normals
        tangents = None if self.tangents is None else self.tangents * [1.0, 1.0, 1.0, -1.0]
        return TriangleMesh(
            self.vertices,
            self.faces[:, ::-1].copy(),
            uvs=self.uvs,
            normals=normals,
            tangents=tangents,
            attributes=self.attributes,
        )

    def with_normals(self, normals: np.ndarray | None) -> "TriangleMesh":
        """The same mesh with other vertex normals (None: flat shading, which leaves no use for the tangents)."""
        tangents = None if normals is None else self.tangents
        return TriangleMesh(
            vertices=self.vertices,
            faces=self.faces,
            uvs=self.uvs,
            normals=normals,
            tangents=tangents,
            attributes=self.attributes,
        )

    def smooth_normals(self) -> np.ndarray:
        """(N, 3) vertex normals computed from the faces: each face's unit normal weighted by the angle of its corner
        at the vertex (Thürrner & Wüthrich 1998), so a vertex's normal does not depend on how its neighbourhood is
        split into triangles. Only faces sharing a vertex index are averaged: a file that repeats a vertex per
        face keeps its facets. Zero for a vertex that only degenerate faces use."""
        v = self.triangles()
        normals = np.zeros_like(self.vertices)
        face = np.cross(v[1] - v[0], v[2] - v[0])
        face_length = np.linalg.norm(face, axis=-1, keepdims=True)
        face = np.divide(face, face_length, out=np.zeros_like(face), where=face_length > 0)
        for k in range(3):
            a = v[(k + 1) % 3] - v[k]
            b = v[(k + 2) % 3] - v[k]
            angle = np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("ij,ij->i", a, b))
            np.add.at(normals, self.faces[:, k], face * angle[:, None])
        length = np.linalg.norm(normals, axis=-1, keepdims=True)
        return np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)

    def triangle_areas(self) -> np.ndarray:
        """(M,) area of each triangle, in scene units squared."""
        v0, v1, v2 = self.triangles()
        return 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)

    def area(self) -> float:
        """Total surface area, in scene units squared."""
        return float(self.triangle_areas().sum())


def winding_against_normals(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, corner_normals: np.ndarray) -> np.ndarray:
    """(M,) True for the triangles (corners v0, v1, v2, each (M, 3)) whose winding's normal (v1 − v0) × (v2 − v0)
    points away from the side their corners' normals (M, 3, 3) point to, as their sum says (the interpolated normal
    at the centroid). Where a mesh has vertex normals, they say which side is the front: Mitsuba 3's one-sided
    BSDFs and area lights test cos θ in the shading frame, and pbrt-v4 turns the geometric normal toward the
    shading normal. Mitsuba decides at each hit, this once per triangle: the two differ only on a triangle whose
    interpolated normal crosses its plane, which no smooth surface's tessellation has."""
    face = np.cross(v1 - v0, v2 - v0)
    return np.einsum("ij,ij->i", face, corner_normals.sum(axis=1)) < 0.0


def shading_normals(mesh: TriangleMesh, face_normals: bool | None, computed: bool = True) -> TriangleMesh:
    """`mesh` with the normals a shape's `face_normals` setting asks for: True drops any (flat facets); False keeps
    the mesh's own or, when it has none and `computed`, makes smooth ones (Mitsuba 3's default for its mesh
    shapes); None keeps what the mesh has and makes none up."""
    if face_normals:
        return mesh.with_normals(None) if mesh.normals is not None else mesh
    if face_normals is False and computed and mesh.normals is None:
        return mesh.with_normals(mesh.smooth_normals())
    return mesh


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
    (vt) or normals (vn), either of which may give one position several values. Scanned in chunks of whole lines,
    so that numpy's temporary arrays stay small."""
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
    return any(data.startswith(tag) or b"\n" + tag in data for tag in (b"vt ", b"vt\t", b"vn ", b"vn\t"))


_PLAIN_OBJ_MAX_BYTES = 4_000_000
# Archives trimesh would open and inflate whole, member by member: refused (spectrace.io.compressed).
_ARCHIVE_SUFFIXES = (".zip", ".tar", ".tgz", ".tar.gz", ".tar.bz2", ".tar.xz")


def _progress_min_bytes() -> float:
    text = os.environ.get(PROGRESS_ENVIRONMENT)
    try:
        return float(text) * 1e6 if text else PROGRESS_MIN_BYTES
    except ValueError:
        return PROGRESS_MIN_BYTES


def load_mesh(path: Path, where: str, shape_index: int = 0) -> TriangleMesh:
    """Read a mesh file (OBJ, PLY, STL, GLB, OFF, ..., or Mitsuba's `.serialized`, whose mesh number `shape_index`
    is read: spectrace.geometry.serialized); a file holding several meshes is merged into one.

    Vertex order and face winding are kept as stored, except that an OBJ vertex used with several texture
    coordinates or normals becomes one vertex per coordinate or normal. The file's vertex normals come along
    (none are made up when it has none). Every failure raises SpectraceError naming `where`.
    """
    if Path(path).name.lower().endswith(_ARCHIVE_SUFFIXES):
        raise SpectraceError(
            f"mesh file '{path}' is an archive, which is not read (its members could inflate to any size): "
            "extract the mesh; single compressed files (.gz, .bz2, .xz) are read",
            where=where,
        )
    if Path(path).suffix.lower() in COMPRESSED_SUFFIXES:
        return _load_compressed(Path(path), where, shape_index)
    if Path(path).suffix.lower() == ".serialized":
        from spectrace.geometry.serialized import read_serialized

        vertices, faces, uvs, normals = read_serialized(path, shape_index, where)
        return TriangleMesh(vertices=vertices, faces=faces, uvs=uvs, normals=normals)
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
        mesh = _validated_mesh(simple[0], simple[1], path, where, normals=simple[2])
    elif path.suffix.lower() == ".ply" and (ply := _direct_ply(path, where)) is not None:
        mesh = ply
    else:
        mesh = _mesh_through_trimesh(path, where, data)
    if announce:
        print(
            f"loaded mesh '{path}': {len(mesh.faces):,} triangles in {time.perf_counter() - started:.1f} s",
            file=sys.stderr,
            flush=True,
        )
    return mesh


def _load_compressed(path: Path, where: str, shape_index: int) -> TriangleMesh:
    """A gzip, bzip2 or xz compressed mesh file (`bunny.ply.gz`), inflated to a temporary file within the limit its
    header declares where it is a binary PLY, else the overall limit (spectrace.io.compressed), then read as the
    file it holds. Messages name the compressed file."""
    from spectrace.geometry.ply import HEADER_MAX_BYTES, declared_size

    path = regular_file(path, where, what="mesh file")
    with tempfile.TemporaryDirectory(prefix="spectrace-mesh-") as folder:
        plain = Path(folder) / path.stem
        try:
            with open(path, "rb") as source, open(plain, "wb") as target:
                inflater = file_inflater(path, source, where, "mesh file")
                if Path(path.stem).suffix.lower() == ".ply":
                    head = inflater.read(HEADER_MAX_BYTES)
                    if (size := declared_size(head)) is not None:
                        inflater.declare(size, "its PLY header declares")
                    target.write(head)
                inflater.copy_to(target)
        except OSError as error:
            raise SpectraceError(f"cannot read mesh file '{path}' ({error.strerror or error})", where=where) from None
        try:
            return load_mesh(plain, where, shape_index)
        except SpectraceError as error:
            raise SpectraceError(error.message.replace(str(plain), str(path)), where=error.where) from None


def _direct_ply(path: Path, where: str) -> TriangleMesh | None:
    """A binary PLY triangle mesh read directly (spectrace.geometry.ply), as the trimesh path would read it; None
    for a PLY file of another kind."""
    from spectrace.geometry.ply import read_binary_ply

    read = read_binary_ply(_read_bytes(path, where))
    if read is None:
        return None
    mesh = _validated_mesh(read.vertices, read.faces, path, where, read.normals)
    if read.uvs is not None and np.all(np.isfinite(read.uvs)):
        mesh.uvs = np.column_stack([read.uvs[:, 0], 1.0 - read.uvs[:, 1]])  # v up in the file, down in spectrace
    if read.tangents is not None and mesh.normals is not None:
        _refuse_non_finite(read.tangents, "vertex tangents with NaN or infinite components", path, where)
        mesh.tangents = read.tangents
    if read.attributes:
        for name, values in read.attributes.items():
            if not np.all(np.isfinite(values)):
                raise SpectraceError(f"mesh file '{path}' has NaN or infinite values in its {name} attribute", where)
        mesh.attributes = read.attributes
    return mesh


def _read_bytes(path: Path, where: str) -> bytes:
    try:
        return path.read_bytes()
    except OSError as error:
        raise SpectraceError(f"cannot read mesh file '{path}' ({error.strerror or error})", where=where) from None


def _mesh_through_trimesh(path: Path, where: str, obj_data: bytes | None = None) -> TriangleMesh:
    """The mesh trimesh reads from `path`; an OBJ file from its bytes, `obj_data` when already read."""
    import trimesh  # deferred: importing trimesh (and with it SciPy) costs about half a second

    if obj_data is None and path.suffix.lower() == ".obj":
        obj_data = _read_bytes(path, where)

    # process=False and maintain_order=True: no merging, reordering or re-winding behind our back.
    options: dict[str, Any] = {"process": False, "maintain_order": True}
    source: Any = path
    if obj_data is not None:
        # With vt or vn, trimesh keeps the stored order only by giving a vertex one of its texture coordinates or
        # normals (at a seam or crease the others are lost); splitting such vertices keeps every corner's own.
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
    mesh = _validated_mesh(
        np.asarray(loaded.vertices), np.asarray(loaded.faces), path, where, _trimesh_scene_normals(scene)
    )
    uv = getattr(getattr(loaded, "visual", None), "uv", None)
    if uv is not None and len(uv) == len(mesh.vertices) and np.all(np.isfinite(uv)):
        # Mesh files store v upward (OpenGL); spectrace's v runs down the image.
        mesh.uvs = np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float64)
    return mesh


def _trimesh_scene_normals(scene: Any) -> np.ndarray | None:
    """The vertex normals a trimesh Scene's file stored, in the order Scene.to_mesh concatenates its vertices and
    turned by each node's transform (inverse transpose); None unless every part stored some. trimesh computes
    normals on demand, so whether the file had them shows only in its cache; to_mesh drops them."""
    import trimesh

    parts = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not isinstance(geometry, trimesh.Trimesh):
            continue
        if "vertex_normals" not in geometry._cache:
            return None
        normals = np.asarray(geometry.vertex_normals, np.float64)
        turned = normals @ np.linalg.inv(np.asarray(transform, np.float64)[:3, :3])
        length = np.linalg.norm(turned, axis=-1, keepdims=True)
        parts.append(np.divide(turned, length, out=np.zeros_like(turned), where=length > 0))
    return np.concatenate(parts) if parts else None


def _plain_triangle_obj(
    path: Path, data: bytes | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None] | None:
    """Vertices, faces and vertex normals (or None) of an OBJ file holding only `v x y z` and `f i j k` lines
    (positive indices), or `v`, `vn x y z` and `f i//n j//n k//n` lines, and comments, read directly, as trimesh
    reads them with process=False (a test checks the bundled meshes both ways); None for anything else, which
    trimesh reads. Importing trimesh costs more than a small render. A position used with several normals becomes
    one vertex per normal, the extra ones after the stored vertices. `data`: the file's bytes, when already read."""
    vertices: list[list[float]] = []
    normals: list[list[float]] = []
    faces: list[list[int]] = []
    face_normals: list[list[int] | None] = []
    try:
        text = (data if data is not None else path.read_bytes()).decode("utf-8")
    except (OSError, UnicodeError):
        return None
    try:
        for line in text.splitlines():
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] in ("v", "vn") and len(fields) == 4:
                (vertices if fields[0] == "v" else normals).append([float(x) for x in fields[1:]])
            elif fields[0] == "f" and len(fields) == 4:
                corners = [corner.split("//") for corner in fields[1:]]
                if not all(len(c) == len(corners[0]) and all(i.isdigit() and int(i) > 0 for i in c) for c in corners):
                    return None
                faces.append([int(c[0]) - 1 for c in corners])
                face_normals.append([int(c[1]) - 1 for c in corners] if len(corners[0]) == 2 else None)
            else:
                return None
    except ValueError:
        return None
    if not vertices or not faces:
        return None
    positions, face_array = np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)
    with_normals = [n is not None for n in face_normals]
    if not any(with_normals):
        return positions, face_array, None
    if not all(with_normals) or not normals or face_array.max() >= len(positions):
        return None
    normal_index = np.array(face_normals, dtype=np.int64)
    if normal_index.max() >= len(normals):
        return None
    # Each (position, normal) pair is one vertex: a position's first pair keeps its index.
    pairs: dict[tuple[int, int], int] = {}
    first_normal = np.full(len(positions), -1, np.int64)
    extra: list[int] = []
    for corner, (p, n) in enumerate(zip(face_array.ravel().tolist(), normal_index.ravel().tolist())):
        if first_normal[p] < 0:
            first_normal[p] = n
        if first_normal[p] != n:
            if (p, n) not in pairs:
                pairs[p, n] = len(positions) + len(extra)
                extra.append(p)
            face_array.reshape(-1)[corner] = pairs[p, n]
    extra_normals = [n for (_, n) in pairs]
    vertex_normals = np.zeros((len(positions) + len(extra), 3))
    file_normals = np.array(normals, dtype=np.float64)
    used = first_normal >= 0
    vertex_normals[: len(positions)][used] = file_normals[first_normal[used]]
    vertex_normals[len(positions) :] = file_normals[np.array(extra_normals, np.int64)].reshape(-1, 3)
    return np.concatenate([positions, positions[np.array(extra, np.int64)].reshape(-1, 3)]), face_array, vertex_normals


def _validated_mesh(
    vertices: np.ndarray, faces: np.ndarray, path: Path, where: str, normals: np.ndarray | None = None
) -> TriangleMesh:
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise SpectraceError(f"mesh file '{path}' contains no triangles", where=where)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise SpectraceError(f"mesh file '{path}' has faces that index missing vertices", where=where)
    _refuse_non_finite(vertices, "vertices with NaN or infinite coordinates", path, where)
    if normals is not None:
        if normals.shape != vertices.shape:
            raise SpectraceError(
                f"mesh file '{path}' has {len(normals)} vertex normals for {len(vertices)} vertices", where=where
            )
        _refuse_non_finite(normals, "vertex normals with NaN or infinite components", path, where)
    return TriangleMesh(vertices=vertices, faces=faces, normals=normals)


def _refuse_non_finite(rows: np.ndarray, what: str, path: Path, where: str) -> None:
    bad = ~np.isfinite(rows).all(axis=1)
    if bad.any():
        raise SpectraceError(
            f"mesh file '{path}' has {int(bad.sum())} {what} (first: vertex {int(np.flatnonzero(bad)[0])})",
            where=where,
        )
