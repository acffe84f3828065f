"""Property: every integer, float and boolean key of the scene schema refuses a value of another type instead of
converting it (`width = true` is not 1, `spp = "4"` not 4, `spp = 4.0` not 4, `two_sided = 1` not true); an integer
is a float. The keys are found by walking the schema's models, so a key added later is covered without listing it.
"""

import types
import typing
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st
from pydantic import BaseModel, ValidationError

from fuzz_settings import fuzz_settings
from scene_text import camera_film
from spectrace.errors import SpectraceError
from spectrace.scene import schema
from spectrace.scene.loader import read_scene_spec

FUZZ_SETTINGS = fuzz_settings(300, [HealthCheck.too_slow], database=None)

SCALARS = (bool, int, float, str)


def _members(annotation) -> list:
    """The types a value of `annotation` may take, through Annotated, unions and containers' own types."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _members(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _members(arg)]
    if origin is typing.Literal:
        return [type(value) for value in typing.get_args(annotation)]
    return [origin or annotation]


def _nested(annotation) -> list:
    """Every annotation inside `annotation` (union members, containers' items), itself included."""
    found = [annotation]
    for arg in typing.get_args(annotation):
        if not isinstance(arg, (str, int, float, bool)) and arg is not None:
            found += _nested(arg)
    return found


def _models() -> list[type[BaseModel]]:
    """Every model the scene schema reaches from SceneSpec."""
    seen: list[type[BaseModel]] = []
    stack: list[type[BaseModel]] = [schema.SceneSpec]
    while stack:
        model = stack.pop()
        if model in seen:
            continue
        seen.append(model)
        for field in model.model_fields.values():
            for inner in _nested(field.annotation):
                if isinstance(inner, type) and issubclass(inner, BaseModel):
                    stack.append(inner)
    return seen


def _scalar_keys() -> list[tuple[type[BaseModel], str, frozenset]]:
    """(model, key, the scalar types the key takes) for every key that takes a number or a boolean itself."""
    keys = []
    for model in _models():
        for name, field in model.model_fields.items():
            taken = frozenset(t for t in _members(field.annotation) if t in SCALARS)
            if taken & {bool, int, float}:
                keys.append((model, name, taken))
    return keys


KEYS = _scalar_keys()


def test_the_walk_finds_keys_of_every_section():
    names = {f"{model.__name__}.{key}" for model, key, _ in KEYS}
    expected = {
        "FilmSpec.width",
        "FilmSpec.exposure",
        "FilmSpec.extend_rgb",
        "IntegratorSpec.max_depth",
        "IntegratorSpec.pixels_per_light_path",
        "IntegratorSpec.hide_emitters",
        "SamplerSpec.spp",
        "SamplerSpec.seed",
        "ShapeSpec.flip_normals",
        "ShapeSpec.radius",
        "InteriorSpec.g",
        "SpectrumSpec.value",
        "PerspectiveCameraSpec.fov",
        "DiffuseMaterialSpec.two_sided",
        "ConductorMaterialSpec.roughness",
        "SpotLightSpec.cutoff_angle",
        "GaussianFilterSpec.stddev",
    }
    assert expected <= names, expected - names


def wrong_values(taken: frozenset):
    """Values of a type `taken` does not include: booleans, whole and fractional floats, numbers written as text."""
    choices = []
    if bool not in taken:
        choices.append(st.booleans())
    if not taken & {int, float}:
        choices.append(st.integers(-(2**40), 2**40))
    if float not in taken:
        choices.append(st.integers(-(2**40), 2**40).map(float))
        choices.append(st.floats(allow_nan=False, allow_infinity=False))
    if str not in taken:
        choices.append(st.one_of(st.integers(-1000, 1000), st.floats(-1e3, 1e3), st.booleans()).map(str))
        choices.append(st.sampled_from(["true", "True", "1", "4", "0.5", "yes", "on"]))
    return st.one_of(choices)


def _errors_at(model: type[BaseModel], key: str, value) -> list[dict]:
    try:
        model.model_validate({key: value})
    except ValidationError as error:
        return [e for e in error.errors() if e["loc"][:1] == (key,)]
    return []


@FUZZ_SETTINGS
@given(data=st.data())
def test_every_scalar_key_refuses_a_value_of_another_type(data):
    model, key, taken = data.draw(st.sampled_from(KEYS), label="key")
    value = data.draw(wrong_values(taken), label="value")
    assert _errors_at(model, key, value), f"{model.__name__}.{key} took {value!r}"


# A value of the right type gets no complaint about its type (it may be out of range): the refusals above are about
# the type, not about the key.
RIGHT_VALUES = {bool: [True, False], int: [1, 3], float: [0.5, 2]}
TYPE_ERRORS = {"bool_type", "int_type", "float_type", "string_type"}


@pytest.mark.parametrize(("model", "key", "taken"), KEYS, ids=[f"{m.__name__}.{k}" for m, k, _ in KEYS])
def test_every_scalar_key_takes_a_value_of_its_type(model, key, taken):
    for kind in taken & set(RIGHT_VALUES):
        for value in RIGHT_VALUES[kind]:
            complaints = [e for e in _errors_at(model, key, value) if e["type"] in TYPE_ERRORS]
            assert not complaints, f"{model.__name__}.{key} refused {value!r}: {complaints}"


# ---------------------------------------------------------------- through the loader: file, key path, one line

SCENE = (
    camera_film(origin="[0, 1, -4]", target="[0, 1, 0]", fov="40", width="8", height="8")
    + """
[integrator]
type = "bdpt"

[sampler]
spp = 4

[materials.white]
type = "diffuse"
reflectance = { value = 0.5 }

[[shapes]]
type = "rectangle"
material = "white"
"""
)

SECTIONS = {
    "film": schema.FilmSpec,
    "integrator": schema.IntegratorSpec,
    "sampler": schema.SamplerSpec,
    "camera": schema.CAMERA_SPECS["perspective"],
    "materials.white": schema.MATERIAL_SPECS["diffuse"],
    "shapes.0": schema.ShapeSpec,
}
TOP_KEYS = [
    (section, key, taken)
    for section, model in SECTIONS.items()
    for m, key, taken in KEYS
    if m is model and key != "type"
]


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("types") / "scene.toml"
    path.write_text(SCENE)
    read_scene_spec(path)  # the scene itself is valid
    return path


@FUZZ_SETTINGS
@given(data=st.data())
def test_the_loader_names_the_file_and_key_of_a_wrongly_typed_value(scene_file, data):
    section, key, taken = data.draw(st.sampled_from(TOP_KEYS), label="key")
    value = data.draw(wrong_values(taken), label="value")
    dotted = f"{section}.{key}"
    with pytest.raises(SpectraceError) as raised:
        read_scene_spec(scene_file, overrides={dotted: value})
    shown = dotted.replace(".0", "[0]")
    assert str(raised.value).startswith(f"{scene_file}: {shown}"), str(raised.value)
    assert "\n" not in str(raised.value)
