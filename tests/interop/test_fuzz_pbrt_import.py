"""Property: whatever a pbrt-v4 file holds, `import_pbrt` writes a TOML scene that loads, or raises SpectraceError
as one line and leaves the output file as it was. Never another exception.

The inputs are mutations of small scenes covering the directives spectrace imports (camera, film, sampler,
integrator, every light and material kind, textures, shapes inline and from PLY files plain and gzipped, Include
and Import of plain and gzipped files, named materials and media, object instances): tokens replaced by NaN,
infinities, huge, negative, fractional or malformed numbers, by strings of the wrong type or by other directives'
names; parameter types changed (`"float radius"` to `"point3 radius"`); tokens deleted, duplicated or swapped;
lines dropped or repeated; directives inserted; the text truncated or spliced with random bytes or Unicode; and
the files it includes replaced by truncated or corrupted (gzip) ones.

CI runs 300 examples, derandomised (the same ones every run), and states how many ran. A longer, random search:
    SPECTRACE_FUZZ_EXAMPLES=100000 python -m pytest -s tests/interop/test_fuzz_pbrt_import.py
"""

import gzip
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from fuzz_settings import LONG_RUN_EXAMPLES, fuzz_settings
from spectrace.errors import SpectraceError
from spectrace.interop.pbrt import import_pbrt

EXAMPLES = 300
FUZZ_SETTINGS = fuzz_settings(
    EXAMPLES, [HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large], database=None
)
PREVIOUS = "# an earlier import that a failed one must not destroy\n"

HEADER = """LookAt 0 1 6  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
Sampler "halton" "integer pixelsamples" 4
Integrator "volpath" "integer maxdepth" 5
"""
BASES = [
    HEADER
    + """WorldBegin
LightSource "point" "rgb I" [1 1 1] "point3 from" [0 3 0]
LightSource "spot" "blackbody I" 3000 "float coneangle" 30 "float conedeltaangle" 5
LightSource "distant" "spectrum L" "stdillum-D65" "point3 to" [0 -1 0]
LightSource "infinite" "rgb L" [0.1 0.2 0.3]
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.5 0.4 0.3]
  Translate 0 -1 0
  Shape "trianglemesh" "point3 P" [-3 0 -3  3 0 -3  3 0 3  -3 0 3] "integer indices" [0 1 2 0 2 3]
    "point2 uv" [0 0 1 0 1 1 0 1]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Rotate 45 0 1 0
  Shape "sphere" "float radius" 0.5
AttributeEnd
Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k" "float roughness" 0.1
Shape "disk" "float radius" 1 "float innerradius" 0.2
Material "dielectric" "float eta" 1.5
Shape "cylinder" "float radius" 0.3 "float zmin" -1 "float zmax" 1 "float phimax" 270
Include "part.pbrt"
""",
    HEADER
    + """MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [0.5 0.5 0.5]
WorldBegin
Texture "checks" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4 "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
Texture "rough" "float" "constant" "float value" 0.2
MakeNamedMaterial "coat" "string type" "coateddiffuse" "texture reflectance" "checks" "texture roughness" "rough"
MakeNamedMaterial "mixed" "string type" "mix" "string materials" ["coat" "skin"] "float amount" 0.5
MakeNamedMaterial "skin" "string type" "diffusetransmission" "rgb reflectance" [0.3 0.2 0.1]
LightSource "point" "spectrum I" [400 1 500 2 700 1]
NamedMaterial "coat"
Shape "plymesh" "string filename" "tri.ply"
NamedMaterial "mixed"
Shape "disk" "float radius" 2
ObjectBegin "thing"
  NamedMaterial "skin"
  Shape "plymesh" "string filename" "tri.ply.gz"
ObjectEnd
AttributeBegin
  Scale 2 2 2
  ObjectInstance "thing"
AttributeEnd
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" 3
AttributeEnd
Import "part.pbrt.gz"
""",
]
PART = """AttributeBegin
  Material "diffuse"
  ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 2 0 1]
  Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]
AttributeEnd
"""


def _ply() -> bytes:
    header = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    )
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes()
    return header + vertices + b"\x03" + np.array([0, 1, 2], "<i4").tobytes()


FILES = {"tri.ply": _ply(), "tri.ply.gz": gzip.compress(_ply()), "part.pbrt": PART.encode()}
FILES["part.pbrt.gz"] = gzip.compress(PART.encode())

# ---------------------------------------------------------------- mutations

TOKEN = re.compile(r'"[^"]*"|\[|\]|[^\s\[\]"]+')
NUMBERS = st.sampled_from(
    ["nan", "-nan", "inf", "-inf", "1e400", "-1e400", "1e39", "3.4e38", "1e-400", "1e30", "-1", "-0", "0", "0.5",
     "2.5", "7", "99999999999999999999", "1e12", "-1e12", "0x10", "1_0", "1e", "--1", ".", "+", "١٢"]
)  # fmt: skip
STRINGS = st.sampled_from(
    ['""', '"x"', '"float radius"', '"point3 P"', '"integer indices"', '"rgb reflectance"', '"spectrum eta"',
     '"texture reflectance"', '"bool x"', '"string filename"', '"blackbody I"', '"normal N"', '"point2 uv"',
     '"float"', '"spectrum"', '"metal-Cu-eta"', '"stdillum-A"', '"glass-BK7"', '"nowhere.ply"', '"tri.ply.gz"',
     '"part.pbrt"', '"scene.pbrt"', '"/dev/zero"', '"."', '"coat"', '"fog"', '"thing"', '"a\\"b"']
)  # fmt: skip
WORDS = st.sampled_from(
    ["WorldBegin", "AttributeBegin", "AttributeEnd", "ObjectBegin", "ObjectEnd", "Include", "Import", "Shape",
     "Material", "Texture", "LightSource", "Transform", "ReverseOrientation", "CoordinateSystem", "true", "false",
     "Bogus"]
)  # fmt: skip
TYPES = st.sampled_from(
    ["integer", "float", "point2", "point3", "vector3", "normal", "rgb", "blackbody", "spectrum", "bool", "string",
     "texture", "matrix", ""]
)  # fmt: skip
TOKEN_MUTATIONS = st.sampled_from(["number", "string", "word", "retype", "delete", "duplicate", "swap", "random"])
TEXT_MUTATIONS = st.sampled_from(["truncate", "bytes", "unicode", "drop_line", "repeat_line", "directive"])


@st.composite
def token_mutation(draw, tokens: list[str]) -> None:
    """Apply one mutation to the token list in place."""
    at = draw(st.integers(min_value=0, max_value=len(tokens) - 1))
    kind = draw(TOKEN_MUTATIONS)
    if kind == "number":
        tokens[at] = draw(NUMBERS)
    elif kind == "string":
        tokens[at] = draw(STRINGS)
    elif kind == "word":
        tokens[at] = draw(WORDS)
    elif kind == "retype" and tokens[at].startswith('"') and " " in tokens[at]:
        name = tokens[at].strip('"').split(" ", 1)[1]
        tokens[at] = f'"{draw(TYPES)} {name}"'
    elif kind == "delete":
        del tokens[at]
    elif kind == "duplicate":
        tokens.insert(at, tokens[at])
    elif kind == "swap":
        other = draw(st.integers(min_value=0, max_value=len(tokens) - 1))
        tokens[at], tokens[other] = tokens[other], tokens[at]
    elif kind == "random":
        tokens[at] = draw(st.text(max_size=8))


@st.composite
def text_mutation(draw, text: str) -> bytes:
    data = text.encode("utf-8")
    kind = draw(TEXT_MUTATIONS)
    at = draw(st.integers(min_value=0, max_value=len(data)))
    lines = text.splitlines(keepends=True)
    line = draw(st.integers(min_value=0, max_value=len(lines) - 1))
    if kind == "truncate":
        return data[:at]
    if kind == "bytes":
        return data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    if kind == "unicode":
        return data[:at] + draw(st.text(min_size=1, max_size=4)).encode("utf-8", "surrogatepass") + data[at:]
    if kind == "drop_line":
        return "".join(lines[:line] + lines[line + 1 :]).encode("utf-8")
    if kind == "repeat_line":
        return "".join(lines[: line + 1] + lines[line:] * draw(st.integers(1, 3))).encode("utf-8")
    directive = draw(
        st.sampled_from(
            ['Include "scene.pbrt"\n', 'Import "part.pbrt"\n', "AttributeEnd\n", "ObjectEnd\n", 'ObjectInstance "x"\n',
             'Shape "plymesh" "string filename" "tri.ply.gz"\n', 'NamedMaterial "none"\n', "WorldBegin\n",
             'Shape "loopsubdiv" "integer levels" 9 "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]\n']
        )
    )  # fmt: skip
    return "".join(lines[:line] + [directive] + lines[line:]).encode("utf-8")


@st.composite
def included_file_mutation(draw) -> tuple[str, bytes]:
    """One of the files the scenes read, damaged: truncated, bytes changed, or its gzip stream cut or garbled."""
    name = draw(st.sampled_from(sorted(FILES)))
    data = FILES[name]
    at = draw(st.integers(min_value=0, max_value=len(data) - 1))
    kind = draw(st.sampled_from(["truncate", "flip", "append"]))
    if kind == "truncate":
        return name, data[:at]
    if kind == "flip":
        return name, data[:at] + bytes([data[at] ^ draw(st.integers(1, 255))]) + data[at + 1 :]
    return name, data + draw(st.binary(min_size=1, max_size=16))


@st.composite
def pbrt_cases(draw) -> tuple[bytes, list[tuple[str, bytes]]]:
    text = draw(st.sampled_from(BASES))
    tokens = TOKEN.findall(text)
    for _ in range(draw(st.integers(min_value=0, max_value=3))):
        draw(token_mutation(tokens))
    text = " ".join(tokens) if tokens != TOKEN.findall(text) else text
    data = draw(text_mutation(text)) if draw(st.booleans()) else text.encode("utf-8")
    damaged = [draw(included_file_mutation()) for _ in range(draw(st.integers(min_value=0, max_value=1)))]
    return data, damaged


# ---------------------------------------------------------------- the property

COUNTS: dict[str, int] = {}


def _example_folder(root: Path) -> Path:
    folder = root / f"case{sum(COUNTS.values())}"
    folder.mkdir()
    for name, data in FILES.items():
        (folder / name).write_bytes(data)
    return folder


def assert_imports_or_reports(scene: Path, out: Path) -> str:
    out.write_text(PREVIOUS)
    try:
        import_pbrt(scene, out)
    except SpectraceError as error:
        message = str(error)
        assert len(message.splitlines()) == 1 and message.isprintable(), message
        assert out.read_text() == PREVIOUS, "a failed import changed the output file"
        return "error"
    assert tomllib.loads(out.read_text())["camera"]
    return "imported"


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    return tmp_path_factory.mktemp("pbrt-fuzz")


@pytest.mark.slow  # about 20 s on a loaded two-core machine
@FUZZ_SETTINGS
@given(case=pbrt_cases())
def test_the_pbrt_importer_imports_or_raises_its_own_one_line_error(workspace, case):
    data, damaged = case
    folder = _example_folder(workspace)
    for name, content in damaged:
        (folder / name).write_bytes(content)
    (folder / "scene.pbrt").write_bytes(data)
    outcome = assert_imports_or_reports(folder / "scene.pbrt", folder / "out.toml")
    COUNTS[outcome] = COUNTS.get(outcome, 0) + 1


@pytest.mark.parametrize("base", range(len(BASES)))
def test_the_unmutated_scenes_import(tmp_path, base):
    for name, data in FILES.items():
        (tmp_path / name).write_bytes(data)
    (tmp_path / "scene.pbrt").write_text(BASES[base])
    import_pbrt(tmp_path / "scene.pbrt", tmp_path / "out.toml")
    assert len(tomllib.loads((tmp_path / "out.toml").read_text())["shapes"]) >= 3


def test_fuzz_counts():
    """How many cases ran, by outcome (shown with -s); at least the setting's number of examples."""
    print(f"\npbrt import: {sum(COUNTS.values())} cases, by outcome {dict(sorted(COUNTS.items()))}")
    if COUNTS:  # the fuzz test ran in this process (it does unless deselected or run on another worker)
        assert sum(COUNTS.values()) >= (LONG_RUN_EXAMPLES or EXAMPLES)
