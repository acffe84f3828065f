"""The perspective and thin-lens cameras' field of view against the pinhole projection: a rectangle perpendicular to
the view axis at distance d images as a rectangle whose edges sit at (W/2 + x·k, H/2 − y·k) pixels, with k the
pixels per scene unit at d, (N/2) / (d·tan(fov/2)) where N is the film's size along `fov_axis`
(docs/scene-format.md: `fov` is the full angle along that image axis, whatever the aspect ratio). With the box
filter a pixel records the fraction of its area the emitter covers, so each edge is measured to a fraction of a
pixel from the coverage summed along a row or a column."""

import math

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.scene.model import Scene

FOV = 40.0
DISTANCE = 5.0
# The rectangle in world units on the plane z = DISTANCE: centre (x, y), half-width, half-height. Off the axis, so
# the edges on either side differ and the image's orientation is checked too.
CENTRE, HALF_WIDTH, HALF_HEIGHT = (-0.15, 0.2), 0.7, 0.6
SPP = 16


def _pixels_per_unit(width: int, height: int, fov_axis: str) -> float:
    across = width if fov_axis == "x" else height
    return (across / 2.0) / (DISTANCE * math.tan(math.radians(FOV) / 2.0))


def _expected_edges(width: int, height: int, fov_axis: str) -> tuple[float, float, float, float]:
    """Film left, right, top, bottom edges in pixels. The camera looks along +z with +y up, so its image right,
    forward × up, is world −x, and rows run down the image."""
    k = _pixels_per_unit(width, height, fov_axis)
    x, y = CENTRE
    return (
        width / 2.0 - (x + HALF_WIDTH) * k,
        width / 2.0 - (x - HALF_WIDTH) * k,
        height / 2.0 - (y + HALF_HEIGHT) * k,
        height / 2.0 - (y - HALF_HEIGHT) * k,
    )


def _render(device, camera: spectrace.Camera, width: int, height: int) -> np.ndarray:
    rectangle = spectrace.shape(
        "rectangle",
        spectrace.diffuse(0.0),
        emitter=spectrace.area_emitter(1.0, two_sided=True),
        transform=[{"scale": [HALF_WIDTH, HALF_HEIGHT, 1.0]}, {"translate": [*CENTRE, DISTANCE]}],
    )
    scene = Scene(
        camera=camera,
        width=width,
        height=height,
        shapes=[rectangle],
        max_depth=1,
        spp=SPP,
        pixel_filter=spectrace.PixelFilter("box"),
    )
    renderer = Renderer(scene, device)
    renderer.render(spp=SPP)
    return renderer.image().xyz[..., 1].astype(np.float64)


def _edges(coverage: np.ndarray, near: float, far: float) -> tuple[np.ndarray, np.ndarray]:
    """Each line's near and far edge, measured from the coverage either side of a split inside the emitter: with
    every pixel between an edge and the split covered and none beyond the edge, the summed coverage is the distance
    from the split to the edge."""
    split = round((near + far) / 2.0)
    return split - coverage[:, :split].sum(axis=1), split + coverage[:, split:].sum(axis=1)


def _inner_lines(start: float, end: float) -> slice:
    """The pixel lines wholly inside [start, end], less one on each side."""
    return slice(math.ceil(start) + 1, math.floor(end) - 1)


def _assert_at(measured: np.ndarray, expected: float, what: str) -> None:
    """The lines are independent measurements of one edge: their mean is within 4 standard errors of the
    projection, the standard error at least that of one edge pixel's coverage estimated from SPP samples
    (√(¼/SPP) over √lines): with stratified samples the lines may agree more closely than that."""
    standard_error = math.hypot(measured.std(ddof=1), math.sqrt(0.25 / SPP)) / math.sqrt(measured.size)
    assert abs(measured.mean() - expected) <= 4.0 * standard_error, (what, measured.mean(), expected, standard_error)


CASES = [
    pytest.param("perspective", 64, 40, "x", id="perspective-landscape-x"),
    pytest.param("perspective", 64, 40, "y", id="perspective-landscape-y"),
    pytest.param("perspective", 40, 64, "x", id="perspective-portrait-x"),
    pytest.param("perspective", 40, 64, "y", id="perspective-portrait-y"),
    pytest.param("thinlens", 64, 40, "y", id="thinlens-landscape-y"),
]


@pytest.mark.parametrize(("camera_type", "width", "height", "fov_axis"), CASES)
def test_a_rectangle_images_where_the_pinhole_projection_puts_it(device, camera_type, width, height, fov_axis):
    """Square pixels whichever axis `fov` spans; the thin lens focused on the rectangle's plane images it sharply at
    the pinhole's place whatever its aperture. A field of view 5 % wide moves the edges by 0.2 to 0.9 pixel, 6 to 26
    standard errors."""
    extra = {"aperture_radius": 0.1, "focus_distance": DISTANCE} if camera_type == "thinlens" else {}
    camera = spectrace.Camera(
        origin=(0.0, 0.0, 0.0),
        target=(0.0, 0.0, 1.0),
        fov_degrees=FOV,
        fov_axis=fov_axis,
        type=camera_type,
        **extra,
    )
    image = _render(device, camera, width, height)
    left, right, top, bottom = _expected_edges(width, height, fov_axis)
    assert 1.0 < left < right < width - 1.0 and 1.0 < top < bottom < height - 1.0  # wholly in view
    rows, columns = _inner_lines(top, bottom), _inner_lines(left, right)
    assert rows.stop - rows.start >= 6 and columns.stop - columns.start >= 6

    measured_left, measured_right = _edges(image[rows], left, right)
    measured_top, measured_bottom = _edges(image[:, columns].T, top, bottom)
    _assert_at(measured_left, left, "left")
    _assert_at(measured_right, right, "right")
    _assert_at(measured_top, top, "top")
    _assert_at(measured_bottom, bottom, "bottom")
    # Nothing else in view: the rectangle's whole image is the area between its edges.
    area = (right - left) * (bottom - top)
    assert abs(image.sum() - area) <= 4.0 * math.sqrt(2.0 * (right - left + bottom - top) * 0.25 / SPP)
