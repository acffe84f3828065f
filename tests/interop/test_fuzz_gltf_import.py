"""Property: whatever a glTF file holds, `import_gltf` writes a TOML scene that loads, or raises SpectraceError as
one line and leaves the output file as it was. Never another exception.

The inputs are mutations of a small file that uses what the importer reads (a textured material with every
texture role, alpha mask, emission and the clearcoat and sheen extensions, a mesh placed by several nodes, a
triangle strip, node matrices and TRS, spot and directional lights, both camera types): one to three JSON values
anywhere replaced by null, negative, fractional, huge, non-finite or out-of-range numbers, strings, arrays or
objects of the wrong shape, or deleted; and, as a .glb, the file's bytes truncated or flipped.

CI runs 200 examples, derandomised (the same ones every run). A longer, random search:
    SPECTRACE_FUZZ_EXAMPLES=100000 python -m pytest -s tests/interop/test_fuzz_gltf_import.py
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st
from tests.interop.gltf_builder import Gltf

from fuzz_settings import LONG_RUN_EXAMPLES, fuzz_settings
from spectrace.errors import SpectraceError
from spectrace.interop.gltf import import_gltf

EXAMPLES = 200
FUZZ_SETTINGS = fuzz_settings(
    EXAMPLES, [HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large], database=None
)
PREVIOUS = "# an earlier import that a failed one must not destroy\n"
VALUES = [None, -1, 0, 1, 3, 99, 2**40, -(2**70), 1e39, -0.5, 0.5, "x", "", [], {}, True, [1], [0, 0, 0], {"a": 1}]
VALUES += [float("nan"), float("inf"), "data:,x", "missing.bin", [1, 2, 3, 4], 5120, 5126, "VEC3", "MAT4", 10497]


def _base() -> Gltf:
    gltf = Gltf()
    texture = gltf.image_texture(np.random.default_rng(0).integers(0, 256, (2, 2, 4)), sampler={"wrapS": 33071})
    info = {"index": texture, "extensions": {"KHR_texture_transform": {"offset": [0.1, 0.2], "scale": [2, 2]}}}
    material = gltf.material(
        pbrMetallicRoughness={"baseColorTexture": info, "metallicRoughnessTexture": {"index": texture}},
        normalTexture={"index": texture},
        alphaMode="MASK",
        extensions={
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessTexture": {"index": texture}},
            "KHR_materials_sheen": {"sheenColorFactor": [0.2, 0.1, 0.0]},
        },
    )
    glowing = gltf.material(
        emissiveFactor=[1, 0.5, 0], extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 3}}
    )
    gltf.node(mesh=gltf.quad(material=material), translation=[0, 1, 0])
    shared = gltf.quad(material=glowing)
    gltf.node(mesh=shared, scale=[2, 2, 2])
    gltf.node(mesh=shared, matrix=np.eye(4).ravel().tolist())
    gltf.node(mesh=gltf.mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], mode=5), rotation=[0, 0.6, 0, 0.8])
    spot = gltf.light(type="spot", intensity=5, spot={"outerConeAngle": 0.5})
    sun = gltf.light(type="directional", intensity=5, color=[1, 0.9, 0.8])
    gltf.node(extensions={"KHR_lights_punctual": {"light": spot}}, translation=[0, 2, 0])
    gltf.node(extensions={"KHR_lights_punctual": {"light": sun}})
    gltf.node(camera=gltf.camera(type="perspective", perspective={"yfov": 0.5, "znear": 0.1}), translation=[0, 0, 5])
    gltf.node(camera=gltf.camera(type="orthographic", orthographic={"xmag": 1, "ymag": 2, "znear": 0.1, "zfar": 9}))
    return gltf


BASE = _base()


def _paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _paths(item, (*prefix, index))


PATHS = [path for path in _paths(BASE.json) if path]


@st.composite
def gltf_cases(draw) -> tuple[dict, str, tuple[str, int, int] | None]:
    document = json.loads(json.dumps(BASE.json))
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        path = draw(st.sampled_from(PATHS))
        parent = document
        try:
            for key in path[:-1]:
                parent = parent[key]
            if draw(st.booleans()) and isinstance(parent, dict) and path[-1] in parent:
                del parent[path[-1]]
            else:
                parent[path[-1]] = draw(st.sampled_from(VALUES))
        except (KeyError, IndexError, TypeError):
            pass  # an earlier mutation removed or replaced what the path leads through
    suffix = draw(st.sampled_from([".glb", ".gltf"]))
    damage = None
    if suffix == ".glb" and draw(st.integers(0, 3)) == 0:
        damage = (draw(st.sampled_from(["truncate", "flip"])), draw(st.integers(0, 10**6)), draw(st.integers(1, 255)))
    return document, suffix, damage


COUNTS: dict[str, int] = {}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    return tmp_path_factory.mktemp("gltf-fuzz")


@pytest.mark.slow  # about 35 s on a loaded two-core machine (most of it the atomic writes' fsync)
@FUZZ_SETTINGS
@given(case=gltf_cases())
def test_the_gltf_importer_imports_or_raises_its_own_one_line_error(workspace, case):
    document, suffix, damage = case
    folder = workspace / f"case{sum(COUNTS.values())}"
    folder.mkdir()
    gltf = Gltf()
    gltf.json, gltf.data = document, BASE.data
    path = gltf.write(folder / f"model{suffix}")
    if damage is not None:
        kind, at, bits = damage
        data = path.read_bytes()
        at %= len(data)
        data = data[:at] if kind == "truncate" else data[:at] + bytes([data[at] ^ bits]) + data[at + 1 :]
        path.write_bytes(data)
    out = folder / "out.toml"
    out.write_text(PREVIOUS)
    try:
        import_gltf(path, out, material_model="diffuse")
    except SpectraceError as error:
        message = str(error)
        assert len(message.splitlines()) == 1 and message.isprintable(), message
        assert out.read_text() == PREVIOUS, "a failed import changed the output file"
        COUNTS["error"] = COUNTS.get("error", 0) + 1
        return
    assert tomllib.loads(out.read_text())["camera"]
    COUNTS["imported"] = COUNTS.get("imported", 0) + 1


def test_the_unmutated_file_imports(tmp_path):
    notes = import_gltf(BASE.write(tmp_path / "model.glb"), tmp_path / "out.toml", material_model="diffuse")
    data = tomllib.loads((tmp_path / "out.toml").read_text())
    assert len(data["shapes"]) == 4 and len(data["lights"]) == 2 and notes


def test_fuzz_counts():
    """How many cases ran, by outcome (shown with -s); at least the setting's number of examples."""
    print(f"\nglTF import: {sum(COUNTS.values())} cases, by outcome {dict(sorted(COUNTS.items()))}")
    if COUNTS:
        assert sum(COUNTS.values()) >= (LONG_RUN_EXAMPLES or EXAMPLES)
