"""The scene model's Material and Light are base classes, not unions written out by hand: every registered
material and light module's dataclass (MODEL) must be one, or its objects would be typed wrong."""

from spectrace.lights import LIGHTS
from spectrace.materials import MATERIALS
from spectrace.scene.model import Light, Material


def test_every_material_model_is_a_material():
    assert all(issubclass(m.MODEL, Material) for m in MATERIALS.values())


def test_every_light_model_is_a_light():
    assert all(issubclass(m.MODEL, Light) for m in LIGHTS.values())
