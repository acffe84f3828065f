"""Indexed triangle meshes, and reading them from any file format trimesh understands."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError


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


def load_mesh(path: Path, where: str) -> TriangleMesh:
    """Read a mesh file (OBJ, PLY, STL, GLB, OFF, ...); a file holding several meshes is merged into one.

    Vertex order and face winding are kept as stored. Every failure raises SpectraceError naming `where`.
    """
    path = Path(path)
    if not path.exists():
        raise SpectraceError(f"mesh file '{path}' does not exist", where=where)
    if not path.is_file():
        raise SpectraceError(f"mesh file '{path}' is not a file", where=where)
    if path.suffix.lower() == ".obj" and (simple := _plain_triangle_obj(path)) is not None:
        return _validated_mesh(*simple, path, where)
    import trimesh  # deferred: importing trimesh (and with it SciPy) costs about half a second

    try:
        # process=False and maintain_order=True: no merging, reordering or re-winding behind our back.
        scene = trimesh.load_scene(path, process=False, maintain_order=True)
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


def _plain_triangle_obj(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and faces of an OBJ file holding only `v x y z` and `f i j k` lines (positive indices, no
    texture coordinates or normals) and comments, read directly, as trimesh reads them with process=False and
    maintain_order=True (a test checks the bundled meshes both ways); None for anything else, which trimesh
    reads. Importing trimesh costs more than a small render."""
    vertices, faces = [], []
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeError):
        return None
    try:
        for line in text.splitlines():
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] == "v" and len(fields) == 4:
                vertices.append([float(x) for x in fields[1:]])
            elif fields[0] == "f" and len(fields) == 4 and all(field.isdigit() for field in fields[1:]):
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
