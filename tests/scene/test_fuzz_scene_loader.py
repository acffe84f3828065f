"""Property: whatever a scene file holds, the loader returns a Scene or raises SpectraceError, as one line that
names the scene file. Never any other exception.

The inputs are mutations of real scene files (the Cornell box and small generated scenes): keys deleted,
duplicated under other names or retyped, values replaced by random ones, NaN, infinities, huge and negative
numbers, and the text itself truncated, spliced with bytes, lines dropped or repeated.

CI runs 1000 examples, derandomised (the same ones every run). A longer, random search:
    SPECTRACE_FUZZ_EXAMPLES=100000 python -m pytest tests/scene/test_fuzz_scene_loader.py
"""

import copy
import json
import math
import re
import shutil
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from fuzz_settings import fuzz_settings
from spectrace.errors import SpectraceError
from spectrace.resources import scenes_dir
from spectrace.scene import Scene, load_scene

FUZZ_SETTINGS = fuzz_settings(
    1000, [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much], database=None
)

CORNELL_TEXT = (scenes_dir() / "cornell_box.toml").read_text()

# Files the mutated scenes may refer to, present in the folder the scene is loaded from.
SPECTRUM_CSV = "# test\nwavelength_nm,a,b\n380,0.1,0.5\n550,0.4,0.6\n780,0.9,0.7\n"
TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
EMPTY_OBJ = "# no faces\nv 0 0 0\n"

# ---------------------------------------------------------------- values

SCALARS = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1, 0.0, -0.0, 1e-320, 1e308, -1e308, 1e39, 16385, 1 << 27, 1 << 31, math.nan, math.inf]),
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(
        [
            "mesh",
            "rectangle",
            "cube",
            "sphere",
            "prism",
            "diffuse",
            "mirror",
            "conductor",
            "plastic",
            "retroreflector",
            "dielectric",
            "BK7",
            "SF11",
            "Au",
            "Ag",
            "metals/Cu:eta",
            "path",
            "direct",
            "point",
            "spot",
            "distant",
            "constant",
            "envmap",
            "area",
            "white",
            "light",
            "cie:D65",
            "cornell_box/light",
            "cornell_box/reflectance:red",
            "spectrum.csv",
            "triangle.obj",
            "empty.obj",
            "missing.obj",
            "cornell_box/white.obj",
            "400:0.5, 700:0.7",
            "x",
            "",
        ]
    ),
)
KEY_NAMES = st.sampled_from(
    [
        "type",
        "file",
        "material",
        "rgb",
        "value",
        "values",
        "spectrum",
        "scale",
        "fov",
        "origin",
        "target",
        "up",
        "width",
        "height",
        "spp",
        "seed",
        "emitter",
        "radiance",
        "transform",
        "translate",
        "rotate",
        "matrix",
        "axis",
        "angle",
        "power",
        "position",
        "intensity",
        "direction",
        "irradiance",
        "column",
        "library",
        "blackbody",
        "two_sided",
        "max_depth",
        "rr_depth",
        "name",
        "fvo",
        "materail",
        "bogus",
        "cutoff_angle",
        "metal",
        "eta",
        "k",
        "roughness",
        "ior",
        "specular_tint",
    ]
)


def _values(depth: int = 2):
    if depth == 0:
        return SCALARS
    inner = _values(depth - 1)
    return st.one_of(
        SCALARS,
        st.lists(SCALARS, max_size=5),
        st.lists(st.lists(SCALARS, max_size=4), max_size=4),
        st.dictionaries(KEY_NAMES, inner, max_size=4),
    )


VALUES = _values()

# ---------------------------------------------------------------- small generated scenes

VECTORS = st.lists(st.floats(-10, 10, allow_nan=False), min_size=3, max_size=3)
SPECTRA = st.one_of(
    st.builds(lambda v: {"value": v}, st.floats(0, 1)),
    st.builds(lambda rgb: {"rgb": rgb}, st.lists(st.floats(0, 1), min_size=3, max_size=3)),
    st.just({"spectrum": "cornell_box/reflectance:white"}),
    st.just({"values": "400:0.2, 600:0.8"}),
    st.just({"file": "spectrum.csv", "column": "a"}),
    st.builds(lambda t: {"blackbody": t, "scale": 0.001}, st.floats(1000, 10000)),
)
SHAPES = st.one_of(
    st.builds(lambda t: {"type": t, "material": "m"}, st.sampled_from(["rectangle", "cube", "sphere"])),
    st.just({"type": "mesh", "file": "triangle.obj", "material": "m"}),
    st.builds(
        lambda s, r: {
            "type": "rectangle",
            "material": "m",
            "emitter": {"radiance": r},
            "transform": [{"scale": s}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}],
        },
        st.floats(0.1, 3),
        SPECTRA,
    ),
)
LIGHTS = st.one_of(
    st.builds(lambda p, w: {"type": "point", "position": p, "power": w}, VECTORS, st.floats(0, 100)),
    st.builds(lambda p, t: {"type": "spot", "position": p, "target": t, "intensity": {"value": 1}}, VECTORS, VECTORS),
    st.builds(lambda d: {"type": "distant", "direction": d, "irradiance": {"value": 1}}, VECTORS),
    st.just({"type": "constant", "radiance": {"blackbody": 6500}}),
)
GENERATED_SCENES = st.fixed_dictionaries(
    {
        "camera": st.fixed_dictionaries({"origin": VECTORS, "target": VECTORS, "fov": st.floats(1, 179)}),
        "film": st.fixed_dictionaries({"width": st.integers(1, 64), "height": st.integers(1, 64)}),
        "sampler": st.fixed_dictionaries({"spp": st.integers(1, 64), "seed": st.integers(0, 100)}),
        "materials": st.fixed_dictionaries(
            {
                "m": st.one_of(
                    st.fixed_dictionaries(
                        {"type": st.sampled_from(["diffuse", "mirror", "retroreflector"]), "reflectance": SPECTRA}
                    ),
                    st.fixed_dictionaries(
                        {
                            "type": st.just("plastic"),
                            "reflectance": SPECTRA,
                            "ior": st.floats(1.01, 4.0),
                            "roughness": st.floats(0, 1),
                        }
                    ),
                    st.fixed_dictionaries(
                        {
                            "type": st.just("conductor"),
                            "metal": st.sampled_from(["Au", "Ag", "Cu", "Al"]),
                            "roughness": st.floats(0, 1),
                        }
                    ),
                    st.fixed_dictionaries(
                        {
                            "type": st.just("dielectric"),
                            "roughness": st.floats(0, 1),
                            "ior": st.one_of(
                                st.floats(0.5, 5.0),
                                st.sampled_from(["BK7", "N-BK7", "SF11", "N-SF11", "BK8"]),
                                st.fixed_dictionaries(
                                    {"sellmeier": st.lists(st.floats(-2, 200), min_size=5, max_size=7)}
                                ),
                                st.fixed_dictionaries({"cauchy": st.lists(st.floats(-1, 3), min_size=1, max_size=3)}),
                            ),
                        }
                    ),
                )
            }
        ),
        "shapes": st.lists(SHAPES, max_size=3),
        "lights": st.lists(LIGHTS, max_size=2),
    }
)

# ---------------------------------------------------------------- TOML output (inline tables only)

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key) -> str:
    key = str(key)
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(type(value))


def to_toml(document: dict) -> str:
    return "".join(f"{_toml_key(k)} = {_toml_value(v)}\n" for k, v in document.items())


# ---------------------------------------------------------------- mutations


def _paths(node, prefix=()):
    """Every key path into a nested dict/list document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, child in items:
        yield prefix + (key,)
        yield from _paths(child, prefix + (key,))


def _parent(document, path):
    node = document
    for part in path[:-1]:
        node = node[part]
    return node


@st.composite
def mutated_documents(draw, base):
    """A copy of `base` (a parsed TOML document) with 1 to 4 structural mutations."""
    document = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 4))):
        paths = list(_paths(document))
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = _parent(document, path), path[-1]
        action = draw(st.sampled_from(["delete", "duplicate", "retype", "rename"]))
        if action == "delete":
            del parent[key]
        elif action == "retype":
            parent[key] = draw(VALUES)
        elif isinstance(parent, dict):
            new_key = draw(KEY_NAMES)
            parent[new_key] = parent[key] if action == "duplicate" else parent.pop(key)
        else:
            parent.append(parent[key])
    return document


@st.composite
def mutated_texts(draw, text: str):
    """`text` with 1 to 3 textual mutations (truncation, byte garbage, dropped or repeated lines, splices)."""
    data = text.encode()
    for _ in range(draw(st.integers(1, 3))):
        action = draw(st.sampled_from(["truncate", "insert_bytes", "drop_line", "repeat_line", "replace_char"]))
        position = draw(st.integers(0, len(data)))
        if action == "truncate":
            data = data[:position]
        elif action == "insert_bytes":
            data = data[:position] + draw(st.binary(min_size=1, max_size=8)) + data[position:]
        elif action == "replace_char":
            data = (
                data[:position]
                + draw(st.sampled_from([b"=", b"[", b"]", b"{", b'"', b"\n", b"-", b"9", b"nan", b"inf", b"e99"]))
                + data[position + 1 :]
            )
        else:
            lines = data.split(b"\n")
            index = draw(st.integers(0, max(len(lines) - 1, 0)))
            if action == "drop_line":
                del lines[index]
            else:
                lines.insert(index, lines[index])
            data = b"\n".join(lines)
    return data


# ---------------------------------------------------------------- the property


@pytest.fixture(scope="module")
def scene_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz")
    shutil.copytree(scenes_dir() / "cornell_box", folder / "cornell_box")
    (folder / "spectrum.csv").write_text(SPECTRUM_CSV)
    (folder / "triangle.obj").write_text(TRIANGLE_OBJ)
    (folder / "empty.obj").write_text(EMPTY_OBJ)
    return folder


def assert_loads_or_reports(path: Path) -> None:
    try:
        scene = load_scene(path)
    except SpectraceError as error:
        message = str(error)
        assert "\n" not in message, message
        assert str(path) in message, f"the message does not name the scene file: {message}"
    else:
        assert isinstance(scene, Scene)


CORNELL_DOCUMENT = tomllib.loads(CORNELL_TEXT)
INPUTS = st.one_of(
    mutated_documents(CORNELL_DOCUMENT).map(lambda d: to_toml(d).encode()),
    mutated_texts(CORNELL_TEXT),
    GENERATED_SCENES.map(lambda d: to_toml(d).encode()),
    GENERATED_SCENES.flatmap(mutated_documents).map(lambda d: to_toml(d).encode()),
    GENERATED_SCENES.map(to_toml).flatmap(mutated_texts),
)


@pytest.mark.slow
@FUZZ_SETTINGS
@given(data=INPUTS)
def test_the_loader_loads_or_raises_its_own_one_line_error(scene_folder, data):
    path = scene_folder / "scene.toml"
    path.write_bytes(data)
    assert_loads_or_reports(path)


def test_the_toml_writer_round_trips():
    """The fuzzer's own TOML output parses back to the same document (else its mutations would be untested)."""
    document = {"a": {"b": [1, 2.5, 'x"y'], "c": {"d": True}}, "e": [{"f": -1e300}], "odd key": "é"}
    assert tomllib.loads(to_toml(document)) == document
    assert math.isnan(tomllib.loads(to_toml({"n": math.nan}))["n"])
