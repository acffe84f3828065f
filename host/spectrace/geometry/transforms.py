"""Affine transforms of shapes, from the scene file's list of steps.

Steps apply to the object in list order: for steps M1, M2, ..., Mk the matrix is Mk ... M2 M1, acting on
column vectors (x, y, z, 1). Rotation angles are in degrees, counter-clockwise looking down the axis toward
the origin (right-handed), as in Mitsuba 3.
"""

from collections.abc import Callable
from numbers import Real
from typing import TypeGuard

import numpy as np

from spectrace.core.limits import linear_map_problem
from spectrace.errors import SpectraceError
from spectrace.geometry.mesh import TriangleMesh


def transform_matrix(ops: list[dict], where: str) -> np.ndarray:
    """(4, 4) matrix of a list of steps, each one of {"translate": [x, y, z]}, {"scale": s or [sx, sy, sz]},
    {"rotate": {"axis": [x, y, z], "angle": degrees}}, {"matrix": 4x4 rows}. `where` names the list in errors."""
    if not isinstance(ops, (list, tuple)):
        raise SpectraceError("must be a list of transform steps", where=where)
    matrix = np.eye(4)
    for i, step in enumerate(ops):
        step_where = f"{where}[{i}]"
        if not isinstance(step, dict) or len(step) != 1:
            raise SpectraceError(
                f"each transform step must be a table with exactly one of {', '.join(_STEP_BUILDERS)}",
                where=step_where,
            )
        ((kind, value),) = step.items()
        if kind not in _STEP_BUILDERS:
            raise SpectraceError(
                f"unknown transform step '{kind}'; expected one of {', '.join(_STEP_BUILDERS)}", where=step_where
            )
        matrix = _STEP_BUILDERS[kind](value, f"{step_where}.{kind}") @ matrix
    # Each step is checked alone; their product can still overflow or collapse (two scales of 1e-200 make 0).
    if problem := linear_map_problem(matrix[:3, :3]):
        raise SpectraceError(f"the transform {problem}", where=where)
    return matrix


def apply_transform(mesh: TriangleMesh, matrix: np.ndarray) -> TriangleMesh:
    """Transformed copy of mesh; a mirroring matrix (det < 0) also reverses the winding, keeping fronts outward.
    Vertex normals are turned by the inverse transpose of the linear part, which keeps them perpendicular to the
    transformed surface under non-uniform scales and shears, and normalised again."""
    matrix = np.asarray(matrix, dtype=np.float64)
    if matrix.shape != (4, 4):
        raise ValueError(f"transform must be 4x4, got {matrix.shape}")
    linear, offset = matrix[:3, :3], matrix[:3, 3]
    vertices = mesh.vertices @ linear.T + offset
    faces = mesh.faces[:, ::-1] if np.linalg.det(linear) < 0 else mesh.faces
    normals = None
    if mesh.normals is not None:
        normals = mesh.normals @ np.linalg.inv(linear)  # rows: (L⁻ᵀ n)ᵀ = nᵀ L⁻¹
        length = np.linalg.norm(normals, axis=-1, keepdims=True)
        normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    tangents = None
    if mesh.tangents is not None:
        # A tangent lies in the surface and moves with it (the linear part, not the normals' inverse transpose); a
        # mirror reverses the handedness that cross(normal, tangent) · w must keep.
        tangents = mesh.tangents.copy()
        tangents[:, :3] = mesh.tangents[:, :3] @ linear.T
        if np.linalg.det(linear) < 0:
            tangents[:, 3] = -tangents[:, 3]
    return TriangleMesh(
        vertices=vertices,
        faces=faces.copy(),
        uvs=mesh.uvs,
        normals=normals,
        tangents=tangents,
        attributes=mesh.attributes,
    )


def _translate(value: object, where: str) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = _vector3(value, where)
    return matrix


def _scale(value: object, where: str) -> np.ndarray:
    factors = np.full(3, _number(value, where)) if _is_number(value) else _vector3(value, where)
    if np.any(factors == 0.0):
        raise SpectraceError("scale factors must be non-zero (a zero scale flattens the shape)", where=where)
    return np.diag([*factors, 1.0])


def _rotate(value: object, where: str) -> np.ndarray:
    if not isinstance(value, dict) or set(value) != {"axis", "angle"}:
        raise SpectraceError("rotate must be a table with exactly the keys 'axis' and 'angle' (degrees)", where=where)
    axis = _vector3(value["axis"], f"{where}.axis")
    length = np.linalg.norm(axis)
    if length == 0.0:
        raise SpectraceError("rotation axis must not be the zero vector", where=f"{where}.axis")
    angle = np.radians(_number(value["angle"], f"{where}.angle"))
    x, y, z = axis / length
    # Rodrigues' rotation formula: R = cos θ I + sin θ [k]x + (1 - cos θ) k kᵀ.
    cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    unit = np.array([x, y, z])
    matrix = np.eye(4)
    matrix[:3, :3] = np.cos(angle) * np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * np.outer(unit, unit)
    return matrix


def _matrix(value: object, where: str) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) != 4:
        raise SpectraceError("matrix must be 4 rows of 4 numbers (row-major)", where=where)
    rows = []
    for r, row in enumerate(value):
        if not isinstance(row, (list, tuple)) or len(row) != 4:
            raise SpectraceError("matrix must be 4 rows of 4 numbers (row-major)", where=f"{where}[{r}]")
        rows.append([_number(entry, f"{where}[{r}][{c}]") for c, entry in enumerate(row)])
    matrix = np.array(rows)
    if not np.array_equal(matrix[3], [0.0, 0.0, 0.0, 1.0]):
        raise SpectraceError(
            "the last matrix row must be [0, 0, 0, 1]: only affine transforms are supported", where=f"{where}[3]"
        )
    if problem := linear_map_problem(matrix[:3, :3]):
        raise SpectraceError(f"matrix {problem}", where=where)
    return matrix


_STEP_BUILDERS: dict[str, Callable[[object, str], np.ndarray]] = {
    "translate": _translate,
    "scale": _scale,
    "rotate": _rotate,
    "matrix": _matrix,
}


def _is_number(value: object) -> TypeGuard[Real]:
    return isinstance(value, Real) and not isinstance(value, bool)


def _number(value: object, where: str) -> float:
    if not _is_number(value) or not np.isfinite(float(value)):
        raise SpectraceError(f"expected a finite number, got {value!r}", where=where)
    return float(value)


def _vector3(value: object, where: str) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise SpectraceError(f"expected a list of 3 numbers, got {value!r}", where=where)
    return np.array([_number(entry, f"{where}[{i}]") for i, entry in enumerate(value)])
