"""Property: whatever a Mitsuba XML file holds, `import_mitsuba` writes a TOML scene that loads, or raises
SpectraceError as one line that names the XML file and leaves the output file as it was. Never another exception.

The inputs are mutations of the test scenes (Mitsuba's Cornell box, tests/data/mitsuba/features.xml and
textures.xml): attributes deleted or given random text, huge, NaN, infinite, negative or malformed numbers and
spectra; elements duplicated, dropped or wrapped in others, nesting far beyond any real scene; textures (bitmaps
with random files, filters, wraps and to_uv, checkerboards, other types) put in place of properties or added
anywhere; and the text truncated or spliced with random bytes or Unicode.

CI runs 1000 examples, derandomised (the same ones every run). A longer, random search:
    SPECTRACE_FUZZ_EXAMPLES=100000 python -m pytest tests/interop/test_fuzz_mitsuba_import.py
"""

import copy
import shutil
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given
from hypothesis import strategies as st

from fuzz_settings import fuzz_settings
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import import_mitsuba

DATA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"
BASES = [(DATA / name).read_text() for name in ("cornell_box.xml", "features.xml", "textures.xml")]
REFERENCED = ("triangle.obj", "lamp.spd", "quad.obj", "texture.png")  # files the scenes refer to, next to the XML
PREVIOUS = "# an earlier import that a failed one must not destroy\n"

FUZZ_SETTINGS = fuzz_settings(
    1000, [HealthCheck.function_scoped_fixture, HealthCheck.too_slow, HealthCheck.data_too_large], database=None
)

# ---------------------------------------------------------------- values

ATTRIBUTE_VALUES = st.one_of(
    st.text(max_size=12),
    st.sampled_from(
        [
            "nan",
            "-nan",
            "NaN",
            "inf",
            "-inf",
            "infinity",
            "1e400",
            "-1e400",
            "1e39",
            "-3.5e38",
            "3.4e38",
            "1e-400",
            "1e30",
            "-1",
            "-0.5",
            "0",
            "-0",
            "2.5",
            "99999999999999999999",
            "0x10",
            "1_000",
            "١٢",
            "ninety",
            "abc",
            "",
            " ",
            "1, 2",
            "1 2 3 4",
            "1,,2",
            "400:1:2",
            "abc:2",
            "400:",
            ":",
            "700:1, 400:2",
            "400:1, 400:2",
            "400:-1, 700:2",
            "400:0.5,",
            "-400:1, 700:1",
            "$spp",
            "$undefined",
            "$",
            "true",
            "false",
            "Au",
            "Cr",
            "none",
            "bk7",
            "water",
            "ggx",
            "beckmann",
            "smaller",
            "larger",
            "diagonal",
            "z",
            "50mm",
            "-5mm",
            "0mm",
            "lamp.spd",
            "triangle.obj",
            "missing.obj",
            "features.xml",
            "out.toml",
            "..",
            "white",
            "gold",
            "ramp",
            "glass",
            "texture.png",
            "quad.obj",
            "nearest",
            "bilinear",
            "trilinear",
            "repeat",
            "mirror",
            "clamp",
            "to_uv",
            "filter_type",
            "wrap_mode",
            "color0",
            "tiles",
            "tiled",
        ]
    ),
    st.floats().map(repr),
    st.integers(min_value=-(2**70), max_value=2**70).map(str),
    st.lists(st.floats(), max_size=17).map(lambda xs: " ".join(map(repr, xs))),
)
TYPES = st.sampled_from(
    [
        "obj",
        "ply",
        "rectangle",
        "cube",
        "sphere",
        "disk",
        "cylinder",
        "serialized",
        "diffuse",
        "twosided",
        "normalmap",
        "bumpmap",
        "mask",
        "conductor",
        "roughconductor",
        "plastic",
        "roughplastic",
        "dielectric",
        "roughdielectric",
        "thindielectric",
        "area",
        "point",
        "constant",
        "directional",
        "spot",
        "perspective",
        "hdrfilm",
        "path",
        "direct",
        "volpath",
        "independent",
        "box",
        "uniform",
        "regular",
        "irregular",
        "blackbody",
        "d65",
        "srgb",
        "bitmap",
        "checkerboard",
        "mesh_attribute",
        "",
    ]
)
ATTRIBUTE_NAMES = st.sampled_from(
    [
        "value",
        "name",
        "type",
        "id",
        "x",
        "y",
        "z",
        "angle",
        "origin",
        "target",
        "up",
        "filename",
        "wavelengths",
        "values",
    ]
)
WRAPPERS = st.sampled_from(["bsdf", "shape", "transform", "spectrum", "ref", "scene", "float", "texture"])
MUTATIONS = st.sampled_from(
    ["delete", "value", "value", "value", "type", "add", "duplicate", "drop", "wrap", "texture", "texture"]
)
PROPERTY_NAMES = st.sampled_from(
    [
        "reflectance",
        "diffuse_reflectance",
        "specular_reflectance",
        "color0",
        "color1",
        "radiance",
        "alpha",
        "eta",
        "normalmap",
        "opacity",
        "radius",
        "p0",
        "flip_normals",
    ]
)
# Most files stay well-formed XML, so that most mutations reach the importer rather than the XML parser.
TEXT_MUTATIONS = st.sampled_from(["none"] * 12 + ["truncate", "bytes", "unicode", "deep"])

# ---------------------------------------------------------------- mutations


@st.composite
def texture_elements(draw, name: str | None) -> ET.Element:
    """A <texture>: a bitmap with random settings, a checkerboard (perhaps with a bitmap side) or another type."""
    kind = draw(st.sampled_from(["bitmap", "bitmap", "checkerboard", "mesh_attribute", "regular", ""]))
    texture = ET.Element("texture", {"type": kind} | ({"name": name} if name is not None else {}))
    if kind == "bitmap":
        for key, values in [
            ("filename", ["texture.png", "texture.png", "quad.obj", "missing.png", "", "lamp.spd"]),
            ("filter_type", ["nearest", "bilinear", "trilinear", "cubic"]),
            ("wrap_mode", ["repeat", "mirror", "clamp", "tile"]),
        ]:
            if draw(st.booleans()):
                ET.SubElement(texture, "string", {"name": key, "value": draw(st.sampled_from(values))})
        if draw(st.booleans()):
            ET.SubElement(texture, "boolean", {"name": "raw", "value": draw(st.sampled_from(["true", "false", "1"]))})
    elif kind == "checkerboard":
        for side in ("color0", "color1"):
            if draw(st.booleans()):
                if draw(st.booleans()):
                    texture.append(draw(texture_elements(side)))
                else:
                    ET.SubElement(texture, "rgb", {"name": side, "value": draw(ATTRIBUTE_VALUES)})
    if draw(st.booleans()):
        transform = ET.SubElement(texture, "transform", {"name": "to_uv"})
        for step in draw(st.lists(st.sampled_from(["scale", "translate", "rotate", "matrix"]), max_size=3)):
            attribute = {"rotate": "angle", "matrix": "value"}.get(step, draw(st.sampled_from(["x", "y", "value"])))
            ET.SubElement(
                transform, step, {attribute: draw(ATTRIBUTE_VALUES)} | ({"z": "1"} if step == "rotate" else {})
            )
    return texture


def _parents(root: ET.Element) -> dict:
    return {child: parent for parent in root.iter() for child in parent}


@st.composite
def tree_mutation(draw, root: ET.Element) -> None:
    """Apply one mutation to the element tree in place."""
    elements = list(root.iter())
    element = elements[draw(st.integers(min_value=0, max_value=len(elements) - 1))]
    parent = _parents(root).get(element)
    kind = draw(MUTATIONS)
    keys = sorted(element.attrib)
    if kind == "delete" and keys:
        del element.attrib[keys[draw(st.integers(min_value=0, max_value=len(keys) - 1))]]
    elif kind == "value" and keys:
        element.set(keys[draw(st.integers(min_value=0, max_value=len(keys) - 1))], draw(ATTRIBUTE_VALUES))
    elif kind == "type":
        element.set("type", draw(TYPES))
    elif kind == "add":
        element.set(draw(ATTRIBUTE_NAMES), draw(ATTRIBUTE_VALUES))
    elif kind == "texture":
        # In place of a property (keeping its name), or as a new child of any element.
        if parent is not None and element.tag in ("rgb", "float", "spectrum", "ref", "texture") and draw(st.booleans()):
            index = list(parent).index(element)
            parent.remove(element)
            parent.insert(index, draw(texture_elements(element.get("name"))))
        else:
            element.append(draw(texture_elements(draw(st.one_of(st.none(), PROPERTY_NAMES)))))
    elif parent is not None:
        index = list(parent).index(element)
        if kind == "duplicate":
            parent.insert(index, copy.deepcopy(element))
        elif kind == "drop":
            parent.remove(element)
        elif kind == "wrap":
            wrapper = ET.Element(draw(WRAPPERS), {"type": draw(TYPES)} if draw(st.booleans()) else {})
            parent.remove(element)
            wrapper.append(element)
            parent.insert(index, wrapper)


@st.composite
def text_mutation(draw, text: str) -> bytes:
    data = text.encode("utf-8")
    kind = draw(TEXT_MUTATIONS)
    at = draw(st.integers(min_value=0, max_value=len(data)))
    if kind == "truncate":
        return data[:at]
    if kind == "bytes":
        return data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    if kind == "unicode":
        return data[:at] + draw(st.text(min_size=1, max_size=8)).encode("utf-8", "surrogatepass") + data[at:]
    if kind == "deep":
        # Nesting at the end of some start tag, as deep as an attacker likes (the element tree could not write it).
        depth = draw(st.sampled_from([70, 500, 2000, 5000]))
        tag = draw(WRAPPERS)
        end_of_tag = data.find(b">", data.find(b"<shape") if b"<shape" in data else 0)
        return (
            data[: end_of_tag + 1] + f"<{tag}>".encode() * depth + f"</{tag}>".encode() * depth + data[end_of_tag + 1 :]
        )
    return data


@st.composite
def mutated_scenes(draw) -> bytes:
    root = ET.fromstring(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        draw(tree_mutation(root))
    return draw(text_mutation(ET.tostring(root, encoding="unicode")))


# ---------------------------------------------------------------- the property


@pytest.fixture
def scene_folder(tmp_path) -> Path:
    for name in REFERENCED:
        shutil.copy(DATA / name, tmp_path / name)
    return tmp_path


def assert_imports_or_reports(xml: Path, out: Path) -> None:
    out.write_text(PREVIOUS)
    try:
        import_mitsuba(xml, out)
    except SpectraceError as error:
        message = str(error)
        assert len(message.splitlines()) == 1 and message.isprintable(), message
        assert message.startswith(f"{xml}"), message
        assert out.read_text() == PREVIOUS, "a failed import changed the output file"
    else:
        assert tomllib.loads(out.read_text())["camera"]
    assert [path.name for path in out.parent.glob(".out.*")] == []  # no temporary file left behind


@pytest.mark.slow
@FUZZ_SETTINGS
@given(data=mutated_scenes())
def test_the_importer_imports_or_raises_its_own_one_line_error(scene_folder, data):
    xml = scene_folder / "scene.xml"
    xml.write_bytes(data)
    assert_imports_or_reports(xml, scene_folder / "out.toml")


@pytest.mark.parametrize("base", range(len(BASES)))
def test_the_unmutated_scenes_import(scene_folder, base):
    """The fuzz test's starting points import (else every mutation would only test the refusal)."""
    xml = scene_folder / "scene.xml"
    xml.write_text(BASES[base])
    import_mitsuba(xml, scene_folder / "out.toml")
    assert tomllib.loads((scene_folder / "out.toml").read_text())["shapes"]
