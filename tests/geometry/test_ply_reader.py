"""The direct binary PLY reader gives the same mesh, to the bit, as trimesh's general reader (the independent
reference) on the files it takes, and hands every other kind of PLY file on to trimesh."""

from pathlib import Path

import numpy as np
import pytest

from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import _mesh_through_trimesh, load_mesh
from spectrace.geometry.ply import read_binary_ply

RNG = np.random.default_rng(7)


def ply_bytes(
    vertex_columns: dict[str, np.ndarray],
    faces: np.ndarray,
    order: str = "<",
    vertex_type: str = "float",
    count_type: str = "uchar",
    index_type: str = "int",
    extra: str = "",
) -> bytes:
    numpy_types = {"float": "f4", "double": "f8", "uchar": "u1", "int": "i4", "uint": "u4", "ushort": "u2"}
    names = list(vertex_columns)
    vertices = np.zeros(len(vertex_columns["x"]), [(n, order + numpy_types[vertex_type]) for n in names])
    for name in names:
        vertices[name] = vertex_columns[name]
    counts = [len(face) for face in faces]
    header = [
        "ply",
        f"format binary_{'little' if order == '<' else 'big'}_endian 1.0",
        "comment written by a test",
        f"element vertex {len(vertices)}",
        *(f"property {vertex_type} {name}" for name in names),
        f"element face {len(faces)}",
        f"property list {count_type} {index_type} vertex_indices",
        *([extra] if extra else []),
        "end_header",
    ]
    body = b"".join(
        np.array([count], order + numpy_types[count_type]).tobytes()
        + np.array(face, order + numpy_types[index_type]).tobytes()
        for count, face in zip(counts, faces)
    )
    return ("\n".join(header) + "\n").encode("ascii") + vertices.tobytes() + body


def grid(n: int = 5) -> tuple[dict[str, np.ndarray], list[list[int]]]:
    """A bumpy n x n vertex grid with normals (some with negative zeros) and texture coordinates."""
    u, v = (a.ravel() for a in np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij"))
    z = 0.1 * RNG.standard_normal(n * n)
    normal = np.column_stack([-0.3 * z, np.where(z > 0, 0.0, -0.0), np.ones(n * n)])
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1
            faces += [[a, b, c], [a, c, d]]
    columns = {"x": u, "y": v, "z": z, "nx": normal[:, 0], "ny": normal[:, 1], "nz": normal[:, 2], "u": u, "v": v}
    return columns, faces


def same_bits(a, b) -> bool:
    return (a is None and b is None) or (
        a is not None and b is not None and a.dtype == b.dtype and a.tobytes() == b.tobytes()
    )


def assert_as_trimesh_reads(path: Path) -> None:
    assert read_binary_ply(path.read_bytes()) is not None, "the direct reader should take this file"
    direct, reference = load_mesh(path, "test"), _mesh_through_trimesh(path, "test")
    for key in ("vertices", "faces", "normals", "uvs"):
        assert same_bits(getattr(direct, key), getattr(reference, key)), key


@pytest.mark.parametrize(
    "keys",
    [
        ("x", "y", "z"),
        ("x", "y", "z", "nx", "ny", "nz"),
        ("x", "y", "z", "u", "v"),
        ("x", "nx", "y", "ny", "z", "nz", "u", "v"),
    ],
)
@pytest.mark.parametrize("order", ["<", ">"])
def test_binary_triangle_files_read_as_trimesh_reads_them(tmp_path, keys, order):
    columns, faces = grid()
    path = tmp_path / "grid.ply"
    path.write_bytes(ply_bytes({k: columns[k] for k in keys}, np.array(faces), order))
    assert_as_trimesh_reads(path)


@pytest.mark.parametrize(
    ("vertex_type", "count_type", "index_type"), [("double", "uchar", "uint"), ("float", "ushort", "int")]
)
def test_other_number_types_read_as_trimesh_reads_them(tmp_path, vertex_type, count_type, index_type):
    columns, faces = grid()
    path = tmp_path / "grid.ply"
    path.write_bytes(
        ply_bytes(columns, np.array(faces), vertex_type=vertex_type, count_type=count_type, index_type=index_type)
    )
    assert_as_trimesh_reads(path)


def test_other_texture_coordinate_names_are_found(tmp_path):
    columns, faces = grid()
    named = {k: columns[k] for k in "xyz"} | {"s": columns["u"], "t": columns["v"]}
    path = tmp_path / "grid.ply"
    path.write_bytes(ply_bytes(named, np.array(faces)))
    assert_as_trimesh_reads(path)
    assert load_mesh(path, "test").uvs is not None


def test_files_of_other_kinds_go_to_trimesh(tmp_path):
    columns, faces = grid()
    quads = [[0, 5, 6, 1]]
    # Quads, an extra face property, and texture coordinates with a vertex no face uses (trimesh drops it).
    unreferenced = np.array(faces)
    unreferenced = np.where(unreferenced == 24, 23, unreferenced)
    for name, data in {
        "quad": ply_bytes(columns, np.array(quads)),
        "extra": ply_bytes(columns, np.array(faces), extra="property uchar flags"),
        "unused": ply_bytes(columns, unreferenced),
        "ascii": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    }.items():
        assert read_binary_ply(data) is None, name
    path = tmp_path / "ascii.ply"
    path.write_bytes(data)
    assert load_mesh(path, "test").faces.tolist() == [[0, 1, 2]]


def test_bad_indices_still_raise_one_clean_error(tmp_path):
    columns, faces = grid()
    broken = np.array(faces)
    broken[3, 1] = 99
    path = tmp_path / "broken.ply"
    path.write_bytes(ply_bytes(columns, broken))
    with pytest.raises(SpectraceError):
        load_mesh(path, "test")
