"""Glowing media as a source of light paths (kernels/light_glowing_media.cl): the boxes around the shapes whose
interior glows, where the light tracer starts a share of its paths, and how likely each box and that share are.
A shape of a placed object glows once per placement: its box is the world-space box around its object-space box
taken through the instance's map, and the kernel finds the medium at a point in it as for any shape (a probe ray
to the boundary around it, which the instance's map places).

The table, a block of the scene's float table (RenderParams.glow_table its offset, -1 without glowing media):
  [0] n, the boxes; [1] the probability that a light path starts in a glowing medium rather than on a light;
  then per box, 8 floats: its lower corner xyz, the probability of picking it, its upper corner xyz, 1 / volume.
The probabilities follow an estimate of the power each source emits (pbrt-v4's power light sampler): a box's
4π V max(σa) max(Le), the lights' their own estimates. Any positive choice is unbiased, as the kernels divide by the
density they sampled with; the estimates only put paths where the light is."""

import math
from collections.abc import Iterator

import numpy as np

from spectrace.scene.model import Scene, Shape
from spectrace.spectral.table import SpectrumTable

# Neither kind of source is starved where the estimates are crude (a box much larger than its glowing part).
_LEAST_SHARE = 0.1


def _box(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
    if shape.analytic is not None:
        lo, hi = shape.analytic.bounds()
        return np.asarray(lo, float), np.asarray(hi, float)
    return shape.mesh.vertices.min(axis=0), shape.mesh.vertices.max(axis=0)


def _placed_box(lo: np.ndarray, hi: np.ndarray, to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The world-space box around the box [lo, hi] taken through the affine map `to_world`: its 8 corners mapped."""
    corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    placed = corners @ np.asarray(to_world, float).T
    return placed[:, :3].min(axis=0), placed[:, :3].max(axis=0)


def _glowing_boxes(scene: Scene) -> Iterator[tuple[np.ndarray, np.ndarray, Shape]]:
    """Each glowing shape's world-space box: the scene's own shapes, then each placement of an object's."""
    for shape in scene.shapes:
        if shape.glows_inside:
            yield (*_box(shape), shape)
    for instance in scene.instances:
        for shape in instance.object.shapes:
            if shape.glows_inside:
                yield (*_placed_box(*_box(shape), instance.to_world), shape)


def _power(shape: Shape, volume: float) -> float:
    """4π V times the most σa Le the medium reaches (its grid's largest density and emission scale)."""
    medium = shape.interior
    assert medium is not None and medium.emission is not None
    glow = float(np.max(np.asarray(medium.sigma_a.values) * np.asarray(medium.emission.values)))
    grid = medium.density
    if grid is not None:
        glow *= float(np.max(grid.density)) if grid.density.size else 0.0
        if grid.emission is not None:
            glow *= float(np.max(grid.emission)) if grid.emission.size else 0.0
    return 4.0 * math.pi * volume * max(glow, 0.0)


def glow_table(scene: Scene, table: SpectrumTable, light_power: list[float]) -> int:
    """Adds the glowing media's table to `table`; its offset, or -1 when no shape of the scene glows inside."""
    boxes = []
    for lo, hi, shape in _glowing_boxes(scene):
        volume = float(np.prod(hi - lo))
        if not (volume > 0.0 and math.isfinite(volume)):
            continue  # a flat shape holds no volume to glow in
        boxes.append((lo, hi, _power(shape, volume), volume))
    if not boxes:
        return -1
    powers = np.array([b[2] for b in boxes])
    pmf = powers / powers.sum() if powers.sum() > 0 else np.full(len(boxes), 1.0 / len(boxes))
    lights = float(np.sum(np.maximum(light_power, 0.0))) if light_power else 0.0
    if not light_power:
        share = 1.0
    elif lights > 0 and powers.sum() > 0:
        share = float(np.clip(powers.sum() / (powers.sum() + lights), _LEAST_SHARE, 1.0 - _LEAST_SHARE))
    else:
        share = 0.5
    block = np.zeros(4 + 8 * len(boxes), np.float32)
    block[0], block[1] = len(boxes), share
    for k, ((lo, hi, _, volume), p) in enumerate(zip(boxes, pmf, strict=True)):
        block[4 + 8 * k : 12 + 8 * k] = (*lo, p, *hi, 1.0 / volume)
    return table.add_block(block)
