"""Curves among the analytic shapes' device rows: a curve shape (geometry/curves.py CurveSurface) enters the shapes'
BVH as one primitive per segment, each an AnalyticShape row of its own (kernels/shape_curve.cl) with its shape's
material and interior."""

from dataclasses import dataclass

import numpy as np

from spectrace.geometry.curves import CurveSurface


@dataclass(frozen=True, eq=False)
class CurveSegment:
    """One segment of a curve shape, as the shapes' BVH and row table take a primitive: its box and its row."""

    row: np.ndarray  # a 0-d ANALYTIC_SHAPE_DTYPE row
    box: np.ndarray  # (2, 3)
    kind: str = "curve"

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.box[0], self.box[1]

    def device_row(self) -> np.ndarray:
        return self.row


def curve_segments(entries: list[tuple]) -> list[tuple]:
    """The (surface, material, emitter, interior) entries with each curve's replaced by one per segment."""
    if not any(isinstance(entry[0], CurveSurface) for entry in entries):
        return entries
    expanded: list[tuple] = []
    for surface, *rest in entries:
        if not isinstance(surface, CurveSurface):
            expanded.append((surface, *rest))
            continue
        rows, boxes = surface.device_rows(), surface.bounds_array()
        expanded.extend((CurveSegment(rows[k], boxes[k]), *rest) for k in range(surface.count))
    return expanded
