"""The grouping of a Blender mesh's face corners into shared vertices (spectrace.interop.blender.meshes), without
Blender: against the plain definition, one vertex per distinct (Blender vertex, normal, UV) row found by sorting."""

from __future__ import annotations

import numpy as np
import pytest

from spectrace.interop.blender.meshes import shared_corners


def _reference(corner_vertex: np.ndarray, values: np.ndarray | None) -> np.ndarray:
    """Each corner's group as the index of the first corner holding the same key."""
    columns = [corner_vertex[:, None].astype(np.int64)]
    if values is not None:
        columns.append(np.ascontiguousarray(values).view(np.uint32).astype(np.int64))
    _, first, inverse = np.unique(np.hstack(columns), axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()]


@pytest.mark.parametrize(
    ("corners", "vertices", "distinct"),
    [
        (2000, 300, 1),  # smooth, one UV island: every corner of a vertex alike
        (2000, 300, 3),  # seams and sharp edges: a few kinds per vertex
        (3000, 100, 12),  # more kinds per vertex than the matching rounds: the sorted remainder
    ],
)
def test_corners_share_a_vertex_exactly_when_vertex_normal_and_uv_agree(corners, vertices, distinct):
    rng = np.random.default_rng(7)
    corner_vertex = rng.integers(0, vertices, corners).astype(np.int32)
    kinds = rng.integers(0, distinct, corners)
    table = rng.random((vertices, distinct, 5)).astype(np.float32)
    values = table[corner_vertex, kinds]
    label, first = shared_corners(corner_vertex, values, vertices)
    reference = _reference(corner_vertex, values)
    # the same partition: corners grouped together there are grouped together here, and the other way round
    assert np.array_equal(first[label], reference[first[label]])
    assert len(np.unique(label)) == len(np.unique(reference)) == len(first)
    assert np.array_equal(corner_vertex[first[label]], corner_vertex)
    assert np.array_equal(values[first[label]], values)


def test_without_normals_or_uvs_each_used_blender_vertex_is_one():
    corner_vertex = np.array([4, 2, 4, 0, 2, 0], dtype=np.int32)
    label, first = shared_corners(corner_vertex, None, 6)
    assert first.tolist() == [3, 1, 0]  # vertices 0, 2, 4 (1, 3 and 5 unused), each at its first corner
    assert label.tolist() == [2, 1, 2, 0, 1, 0]
