"""A scene file's curve shape (`type = "curve"`, docs/scene-format.md "Curves") resolved: its control points from
`points` or a Mitsuba 3 curve file, placed by `transform` (points moved, radii kept), as the segments the kernels
intersect (geometry/curves.py)."""

import difflib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.curves import (
    MINIMUM_POINTS,
    checked_curve_type,
    checked_curves,
    curve_surface,
    read_curve_file,
)
from spectrace.geometry.transforms import transform_matrix
from spectrace.scene.model import Material, Shape


def curve_shape(
    spec, folder: Path, where: Callable[[str], str], key: str, materials: dict[str, Material], index: int
) -> Shape:
    """The Shape of a curve's ShapeSpec `spec` at key path `key` (errors name the file and key)."""
    basis = spec.basis or "linear"
    if spec.file is not None:
        curves = read_curve_file(folder / spec.file, where(f"{key}.file"), MINIMUM_POINTS[basis])
    else:
        curves = checked_curves(spec.points, basis, where(f"{key}.points"))
    curve_type = spec.curve_type or "tube"
    uv_convention = spec.uv_convention or "pbrt"
    normals = checked_curve_type(
        curve_type, curves, spec.curve_normals, basis, uv_convention, lambda name: where(f"{key}.{name}")
    )
    matrix = None
    if spec.transform:
        steps = [step.model_dump(exclude_none=True) for step in spec.transform]
        matrix = transform_matrix(steps, where=where(f"{key}.transform"))
    with np.errstate(over="ignore", invalid="ignore"):
        surface = curve_surface(
            curves,
            basis,
            matrix,
            open_ends=spec.open_ends,
            uv_convention=uv_convention,
            curve_type=curve_type,
            normals=normals,
        )
    if not (np.all(np.isfinite(surface.a)) and np.all(np.isfinite(surface.b))):
        raise SpectraceError("the transform takes control points beyond float range", where=where(f"{key}.transform"))
    culprit = "file" if spec.file is not None else "points"
    if surface.count == 0:
        raise SpectraceError("the curves have no segment of any length", where=where(f"{key}.{culprit}"))
    material = None
    if spec.material is not None:
        if spec.material not in materials:
            close = difflib.get_close_matches(spec.material, list(materials), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f"; defined: {', '.join(sorted(materials))}"
            raise SpectraceError(f"undefined material '{spec.material}'{hint}", where=where(f"{key}.material"))
        material = materials[spec.material]
    return Shape(mesh=surface.tessellation(), material=material, name=spec.name or f"curve{index}", analytic=surface)
