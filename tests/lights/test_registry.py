"""The lights' registry (spectrace/lights/__init__.py) is the one list of the lights: the scene's `[[lights]]` types,
the API's constructors, and, through each module's DEVICE_TYPES, the device light types: their codes, their kernel
files and the X-macro lists the kernels dispatch through. No kernel file keeps a list of the light types or tests
one by name outside its own file, so a new light is its module, its registry line and its kernel file."""

import re

import pytest

import spectrace
from spectrace import api, resources
from spectrace.device.program_cache import kernel_contract
from spectrace.lights import (
    DEVICE_LIGHTS,
    KERNEL_HEADER_NAME,
    LIGHT_SOURCES,
    LIGHTS,
    area,
    generated_sources,
)
from spectrace.lights.base import DEVICE_LIGHT_KINDS, Light

KERNELS = resources.kernels_dir()
HEADER = generated_sources().headers[KERNEL_HEADER_NAME]

# What a device light type's kernel file defines, by its kind (kernels/lights.cl says what each one is).
FUNCTIONS = {
    "area": ("sample_li", "pdf_li", "sample_point", "pdf_point"),
    "position": ("sample_li", "sample_le", "sample_direction", "pdf_direction", "intensity"),
    "infinite": ("sample_li", "sample_wi", "pdf_wi", "radiance"),
}


def _entries(list_name: str) -> list[tuple[str, str]]:
    body = HEADER.split(f"#define {list_name}(X)", 1)[1].split("\n#define", 1)[0]
    return re.findall(r"X\((\w+), (\w+)\)", body)


def test_every_kind_states_its_functions():
    assert set(FUNCTIONS) == set(DEVICE_LIGHT_KINDS)


@pytest.mark.parametrize("device", DEVICE_LIGHTS.values(), ids=list(DEVICE_LIGHTS))
def test_every_device_light_type_has_its_kernel_file_with_the_functions_of_its_kind(device):
    path = KERNELS / device.kernel_file
    assert path.is_file(), path
    assert f'#include "{device.kernel_file}"' in HEADER
    source = path.read_text(encoding="utf-8")
    for function in FUNCTIONS[device.kind]:
        assert re.search(rf"^inline [\w ]+\blight_{device.name}_{function}\(", source, re.M), f"{path.name}: {function}"
    if device.kind == "infinite":
        assert re.search(rf"#define LIGHT_{device.name.upper()}_DELTA [01]\b", source), path.name
    # The header names its sources, units and contracts.
    assert source.startswith("/*") and re.search(r"W/\(", source.split("*/", 1)[0]), path.name


def test_the_x_macro_lists_hold_every_device_type_once_in_code_order_and_each_under_its_kind():
    everything = [(t.name, t.name.upper()) for t in DEVICE_LIGHTS.values()]
    assert _entries("LIGHT_LIST") == everything
    for kind in DEVICE_LIGHT_KINDS:
        assert _entries(f"LIGHT_LIST_{kind.upper()}") == [
            (t.name, t.name.upper()) for t in DEVICE_LIGHTS.values() if t.kind == kind
        ]


def test_the_codes_are_each_type_s_place_among_every_light_module_s_device_types():
    """Light.type codes: the shapes' emitters' types, then the `[[lights]]`' in registry order; LIGHT_TYPE_COUNT
    bounds them (SCENE_LIGHT_TYPES is a bit mask of them)."""
    declared = [t.name for source in LIGHT_SOURCES for t in source.DEVICE_TYPES]
    assert declared[:3] == ["triangle", "sphere", "shape"] and LIGHT_SOURCES[0] is area
    contract = kernel_contract(generated_sources())
    assert [contract[f"LIGHT_{name.upper()}"] for name in declared] == list(range(len(declared)))
    assert contract["LIGHT_TYPE_COUNT"] == len(declared) == len(set(declared))
    environments = {t.name for m in LIGHTS.values() if m.IS_ENVIRONMENT for t in m.DEVICE_TYPES}
    assert environments == {"environment", "environment_map"}
    assert contract["LIGHT_ENVIRONMENT_TYPES"] == sum(1 << contract[f"LIGHT_{n.upper()}"] for n in environments)


def test_every_light_kernel_file_is_a_registered_device_type():
    shared = {
        "light_sample.cl",
        "light_area.cl",
        "light_emission.cl",
        "light_tracer.cl",
        "light_slide_frame.cl",
        "light_glowing_media.cl",
    }
    files = {path.name for path in KERNELS.glob("light_*.cl")} - shared
    assert files == {t.kernel_file for t in DEVICE_LIGHTS.values()}


def test_no_kernel_file_lists_or_names_the_light_types_outside_its_own():
    """The dispatch goes through the generated lists: a type's code appears only in its own file (its DELTA flag),
    no file defines a light list or includes a light's file itself, and types.h keeps no copy of the codes."""
    own = {t.kernel_file: t.name.upper() for t in DEVICE_LIGHTS.values()}
    found = []
    for path in sorted(KERNELS.rglob("*")):
        if path.suffix not in (".cl", ".h"):
            continue
        text = re.sub(r"/\*.*?\*/", "", path.read_text(encoding="utf-8"), flags=re.S)
        for t in DEVICE_LIGHTS.values():
            code = f"LIGHT_{t.name.upper()}"
            if own.get(path.name) != t.name.upper() and re.search(rf"\b{code}\b", text):
                found.append(f"{path.name}: {code}")
            if re.search(rf'#\s*include\s+"{t.kernel_file}"', text) and path.name not in own:
                found.append(f"{path.name}: includes {t.kernel_file}")
        if re.search(r"#\s*define\s+LIGHT_LIST\w*\(", text):
            found.append(f"{path.name}: a light list")
    assert found == []


def test_every_light_module_has_what_the_protocol_states():
    """mypy checks the modules against LightPlugin; this checks what it cannot: the values."""
    for name, module in LIGHTS.items():
        assert name == module.NAME and issubclass(module.MODEL, Light)
        assert module.DEVICE_TYPES and all(t.name in DEVICE_LIGHTS for t in module.DEVICE_TYPES)
        assert isinstance(module.IS_ENVIRONMENT, bool) and module.PARAMETERS


def test_the_api_constructors_are_the_modules_make():
    """spectrace.<API_NAME> is the module's own `make` (no second list of its parameters in the API), and each is a
    public name of the package."""
    constructors = {m.API_NAME: m.make for m in LIGHTS.values() if m.API_NAME is not None}
    expected = {
        "point_light",
        "spot_light",
        "distant_light",
        "constant_environment",
        "projector_light",
        "goniometric_light",
    }
    assert set(constructors) == expected
    for api_name, make in constructors.items():
        assert getattr(api, api_name) is make and getattr(spectrace, api_name) is make
        assert api_name in spectrace.__dir__()
    assert all((m.API_NAME is None) == (m.make is None) for m in LIGHTS.values())
