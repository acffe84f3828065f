"""A composite texture's values are bounded by the parameter that uses it (its Parameter table's range), not as a
reflectance wherever it is used: a checkerboard of 0.4 and 1.4 is a valid `principledthin` `diff_trans` (0–2, as
Mitsuba 3's), an invalid roughness (0–1) and an invalid reflectance (it would create energy); a scale's operand above
1 is fine where the product stays a reflectance. The API and the scene format decide alike."""

import pytest

import spectrace
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene


def _checker(high: float):
    return spectrace.checkerboard(0.4, high)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: spectrace.principledthin(diff_trans=_checker(1.4)), None),
        (lambda: spectrace.principledthin(diff_trans=_checker(2.5)), "above 2 "),
        (lambda: spectrace.principledthin(sheen=_checker(1.4)), "above 1 "),
        (lambda: spectrace.conductor("Au", roughness=_checker(1.4)), "above 1 "),
        (lambda: spectrace.mix([spectrace.diffuse(0.5), spectrace.diffuse(0.2)], _checker(1.2)), "above 1 "),
        (lambda: spectrace.diffuse(_checker(1.4)), "would create energy"),
        (lambda: spectrace.diffuse(spectrace.scale_texture(1.6, 0.5)), None),
        (lambda: spectrace.diffuse(spectrace.scale_texture(1.6, 0.8)), "above 1 "),
    ],
    ids=[
        "diff_trans 1.4",
        "diff_trans 2.5",
        "sheen 1.4",
        "roughness 1.4",
        "mix amount 1.2",
        "reflectance 1.4",
        "scaled reflectance 0.8",
        "scaled reflectance 1.28",
    ],
)
def test_the_api_bounds_a_texture_by_the_parameter_using_it(make, message):
    if message is None:
        make()
    else:
        with pytest.raises(SpectraceError, match=message):
            make()


SCENE = """
[camera]
origin = [0, 0, 3]
target = [0, 0, 0]
fov = 30
[film]
width = 8
height = 8
[[shapes]]
type = "rectangle"
material = "sheet"
[materials.sheet]
type = "{material}"
{key} = {{ texture = "checkerboard", color0 = {{ value = 0.4 }}, color1 = {{ value = {high} }} }}
"""


@pytest.mark.parametrize(
    "material, key, high, message",
    [
        ("principledthin", "diff_trans", 1.4, None),
        ("principledthin", "diff_trans", 2.5, "materials.sheet.diff_trans: checkerboard has values above 2"),
        ("principledthin", "roughness", 1.4, "materials.sheet.roughness: checkerboard has values above 1"),
        ("diffuse", "reflectance", 1.4, "materials.sheet.reflectance: checkerboard has values above 1"),
    ],
)
def test_the_scene_format_bounds_a_texture_by_the_parameter_using_it(tmp_path, material, key, high, message):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(material=material, key=key, high=high))
    if message is None:
        spectrace.load_scene(path)
    else:
        with pytest.raises(SpectraceError, match=message):
            spectrace.load_scene(path)


def test_mitsubas_principledthin_with_a_diff_trans_checkerboard_above_1_imports(tmp_path):
    """Mitsuba 3's own test scene's diff_trans (a checkerboard of 0.4 and 1.4, within Mitsuba's 0–2) imports."""
    path = tmp_path / "scene.xml"
    path.write_text(
        """<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
    <integer name="height" value="8"/></film></sensor>
  <shape type="rectangle"><bsdf type="principledthin">
    <texture name="diff_trans" type="checkerboard"><float name="color0" value="0.4"/>
      <float name="color1" value="1.4"/></texture></bsdf></shape>
</scene>"""
    )
    scene = load_mitsuba_scene(path)
    assert spectrace.textures.scalar_range(scene.shapes[0].material.diff_trans)[1] == pytest.approx(1.4)
