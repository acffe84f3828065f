"""Objects and instances in scene files (docs/scene-format.md, "Objects and instances"): an object is resolved
once in its own space, each instance places it with its own transform, and mistakes are one line naming the key."""

import numpy as np
import pytest

from scene_text import camera_film, diffuse
from spectrace.errors import SpectraceError
from spectrace.geometry.transforms import transform_matrix
from spectrace.scene import load_scene

OBJECT = """
[objects.post]
shapes = [
  { type = "cube", material = "grey", transform = [{ scale = [0.1, 0.5, 0.1] }] },
  { type = "rectangle", material = "grey", name = "sign", transform = [{ translate = [0, 0.6, 0] }] },
]
"""


def _scene(tmp_path, objects=OBJECT, instances=""):
    path = tmp_path / "scene.toml"
    path.write_text(camera_film() + diffuse("grey", "value = 0.5") + objects + instances)
    return path


def test_analytic_shapes_in_objects_stay_analytic(tmp_path):
    objects = """
[objects.parts]
shapes = [
  { type = "sphere", material = "grey", transform = [{ scale = 0.5 }, { translate = [0, 1, 0] }] },
  { type = "cylinder", material = "grey", tessellated = true },
  { type = "disk", material = "grey", transform = [{ scale = [2, 1, 1] }] },
]
"""
    instances = '[[instances]]\nobject = "parts"\ntransform = [{ scale = [1, 3, 0.5] }]\n'
    scene = load_scene(_scene(tmp_path, objects, instances))
    sphere, cylinder, disk = scene.instances[0].object.shapes
    assert sphere.analytic is not None and sphere.analytic.kind == "sphere"
    np.testing.assert_allclose(sphere.analytic.sphere_centre_radius()[0], [0, 1, 0])  # object space
    assert cylinder.analytic is None and disk.analytic is not None and disk.analytic.kind == "disk"


def test_instances_place_one_object_by_their_transforms(tmp_path):
    instances = """
[[instances]]
object = "post"

[[instances]]
object = "post"
name = "far post"
transform = [{ rotate = { axis = [0, 1, 0], angle = 90 } }, { translate = [2, 0, 0] }]
"""
    scene = load_scene(_scene(tmp_path, instances=instances))
    assert scene.shapes == [] and len(scene.instances) == 2
    first, second = scene.instances
    assert first.object is second.object and [s.name for s in first.object.shapes] == ["cube0", "sign"]
    np.testing.assert_array_equal(first.to_world, np.eye(4))
    steps = [{"rotate": {"axis": [0, 1, 0], "angle": 90}}, {"translate": [2, 0, 0]}]
    np.testing.assert_allclose(second.to_world, transform_matrix(steps, "t"))
    assert second.name == "far post"
    # The object's shapes stay in object space: the cube is the unit cube scaled, not moved.
    np.testing.assert_allclose(np.abs(first.object.shapes[0].mesh.vertices).max(axis=0), [0.1, 0.5, 0.1])


@pytest.mark.parametrize(
    ("objects", "instances", "where", "message"),
    [
        (
            OBJECT,
            '[[instances]]\nobject = "pots"\n',
            "instances[0].object",
            "undefined object 'pots' (did you mean 'post'?)",
        ),
        (
            '[objects.lamp]\nshapes = [{ type = "rectangle", material = "grey",'
            " emitter = { radiance = { value = 1 } } }]\n",
            '[[instances]]\nobject = "lamp"\n',
            "objects.lamp.shapes[0].emitter",
            "emitters cannot be instanced",
        ),
        (
            '[objects.ball]\nshapes = [{ type = "sphere", material = "grey", transform = [{ scale = [1, 2, 1] }] }]\n',
            '[[instances]]\nobject = "ball"\n',
            "objects.ball.shapes[0].transform",
            "must scale uniformly",
        ),
        (
            "[objects.none]\nshapes = []\n",
            '[[instances]]\nobject = "none"\n',
            "objects.none.shapes",
            "at least 1",
        ),
        (OBJECT, '[[instances]]\nobject = "post"\ntransform = [{ scale = 0 }]\n', "instances[0].transform", ""),
    ],
)
def test_mistakes_name_the_key(tmp_path, objects, instances, where, message):
    with pytest.raises(SpectraceError) as error:
        load_scene(_scene(tmp_path, objects, instances))
    text = str(error.value)
    assert where in text and message in text, text
    assert "\n" not in text


def test_python_instances_are_checked_like_shapes():
    import spectrace
    from spectrace.core import limits
    from spectrace.scene.model import Instance

    obj = spectrace.instanced_object([spectrace.shape("cube", spectrace.diffuse(0.5))], name="box")
    camera = spectrace.Camera(origin=(0, 0, -5), target=(0, 0, 0))
    for matrix, says in (
        (np.full((4, 4), np.nan), "not a finite 4 x 4 matrix"),
        (np.diag([1.0, 0.0, 1.0, 1.0]), "singular"),
        (np.diag([1e38, 1e38, 1e38, 1.0]), "instance 0 ('far') places shape 'cube'"),
    ):
        scene = spectrace.Scene(camera=camera, width=4, height=4, shapes=[], instances=[Instance(obj, matrix, "far")])
        assert says in (limits.scene_geometry_problem(scene) or ""), matrix
    with pytest.raises(SpectraceError, match="emitters cannot be instanced"):
        spectrace.instanced_object([spectrace.shape("cube", spectrace.diffuse(0.5), emitter=spectrace.area_emitter(1))])
    # An analytic shape is instanced as itself (an instance may stretch it: the kernels transform the ray).
    ball = spectrace.instanced_object([spectrace.shape("sphere", spectrace.diffuse(0.5))])
    assert ball.shapes[0].analytic is not None
