"""Each material's parameter table agrees with what is written by hand elsewhere: the model descriptions in
docs/materials.md, the Python API's helpers, and the ranges the loader enforces (each bounded range tried at its
ends). docs/scene-format.md's table is written from the parameter tables (tests/test_docs_tables.py)."""

import inspect
from pathlib import Path

import pytest

import spectrace
from scene_text import camera_film
from spectrace.core.parameters import REQUIRED
from spectrace.errors import SpectraceError
from spectrace.materials import MATERIALS
from spectrace.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[2]
MATERIALS_DOC = (ROOT / "docs" / "materials.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("name", list(MATERIALS))
def test_materials_doc_describes_every_parameter(name):
    section = MATERIALS_DOC.split(f"## `{name}`\n", 1)[1].split("\n## ", 1)[0]
    for parameter in MATERIALS[name].PARAMETERS:
        assert f"`{parameter.name}`" in section, f"docs/materials.md, {name}: {parameter.name}"


@pytest.mark.parametrize("name", list(MATERIALS))
def test_api_helper_takes_the_parameters_with_their_defaults(name):
    signature = inspect.signature(getattr(spectrace, name))
    for parameter in MATERIALS[name].PARAMETERS:
        given = signature.parameters[parameter.api_name or parameter.name]
        expected = inspect.Parameter.empty if parameter.default is REQUIRED else parameter.default
        assert given.default == expected, f"spectrace.{name}({given.name}=...)"


def _material_scene(tmp_path, name: str, key: str, value: float) -> Path:
    required = {"reflectance": "{ value = 0.5 }"} if name in ("diffuse", "plastic") else {}
    if name == "conductor":
        required = {"metal": '"Au"'}
    if name == "fluorescent":
        required = {"base": '"b"', "excitation": "{ value = 0.5 }", "emission": "{ value = 1 }"}
    lines = "".join(f"{k} = {v}\n" for k, v in {**required, key: repr(value)}.items())
    # A fluorescent material's base, which it names.
    base = '[materials.b]\ntype = "diffuse"\nreflectance = { value = 0.5 }\n' if name == "fluorescent" else ""
    path = tmp_path / "scene.toml"
    path.write_text(
        camera_film(width="4", height="4")
        + f"""
{base}[materials.m]
type = "{name}"
{lines}
[[shapes]]
type = "sphere"
material = "m"
""",
        encoding="utf-8",
    )
    return path


def _bounded_float_ranges():
    """(material, key, low, high, low_open, high_open) for every plain number key with a bounded range."""
    for name, module in MATERIALS.items():
        for p in module.PARAMETERS:
            if p.type == "float" and not p.textured and p.range is not None and p.range.bounded:
                yield name, p.name, p.range.low, p.range.high, p.range.low_open, p.range.high_open


@pytest.mark.parametrize("name, key, low, high, low_open, high_open", list(_bounded_float_ranges()))
def test_loader_enforces_the_range(tmp_path, name, key, low, high, low_open, high_open):
    step = 1e-6 * max(1.0, abs(high))
    cases = [
        (low, not low_open),
        (low - step, False),
        (low + step, True),
        (high, not high_open),
        (high + step, False),
        (high - step, True),
    ]
    for value, accepted in cases:
        path = _material_scene(tmp_path, name, key, value)
        if accepted:
            load_scene(path)
        else:
            with pytest.raises(SpectraceError) as error:
                load_scene(path)
            assert error.value.where == f"{path}: materials.m.{key}", (value, error.value)


def test_plastic_ior_range_is_one_rule_in_the_api_and_the_loader(tmp_path):
    """The rule written once holds the same way through both doors."""
    for ior, accepted in ((1.0, False), (1.01, True), (4.0, True), (4.01, False)):
        path = _material_scene(tmp_path, "plastic", "ior", ior)
        if accepted:
            assert load_scene(path).shapes[0].material == spectrace.plastic(0.5, ior=ior)
        else:
            with pytest.raises(SpectraceError, match="ior"):
                spectrace.plastic(0.5, ior=ior)
            with pytest.raises(SpectraceError):
                load_scene(path)


def test_a_rough_coat_with_its_own_transmission_needs_a_number_roughness(tmp_path):
    """Its transmittance is tabulated for one α: a roughness texture is refused, by the API and the loader alike."""
    texture = spectrace.checkerboard(0.1, 0.3)
    with pytest.raises(SpectraceError, match="coat_transmission"):
        spectrace.plastic(0.5, roughness=texture, coat_transmission="rough")
    spectrace.plastic(0.5, roughness=texture)  # the smooth coupling takes it
    path = _material_scene(tmp_path, "plastic", "coat_transmission", "rough")
    text = path.read_text(encoding="utf-8").replace("coat_transmission = 'rough'", 'coat_transmission = "rough"')
    path.write_text(text.replace("[[shapes]]", 'roughness = { texture = "checkerboard" }\n[[shapes]]'))
    with pytest.raises(SpectraceError, match="coat_transmission") as error:
        load_scene(path)
    assert "materials.m" in str(error.value.where)
