"""The scene model's Material and Light unions are written out for the type checker; they must name exactly the
dataclass (MODEL) of every registered material and light module, or a new module's objects would be typed wrong."""

import typing

from spectrace.lights import LIGHTS
from spectrace.materials import MATERIALS
from spectrace.scene.model import Light, Material


def test_material_union_is_every_material_model():
    assert list(typing.get_args(Material)) == [m.MODEL for m in MATERIALS.values()]


def test_light_union_is_every_light_model():
    assert list(typing.get_args(Light)) == [m.MODEL for m in LIGHTS.values()]
