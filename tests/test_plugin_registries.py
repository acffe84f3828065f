"""Every registered plugin of every kind (material, texture, camera, pixel filter) has what its kind needs: the
members its kind's Protocol states, a device code that is its position in the registry and that every kernel build
is handed, a case in its kind's kernel file, and a row or section in its docs page. The tests walk the registries,
so a new plugin is checked without editing them; and no kernel or contract file writes a code a second time."""

import re
from dataclasses import dataclass
from pathlib import Path

import pytest

import spectrace
from spectrace import resources
from spectrace.cameras import CAMERAS
from spectrace.cameras.base import CameraPlugin
from spectrace.core.contract import device_contract_defines
from spectrace.core.registry import Registry
from spectrace.device.program_cache import kernel_contract
from spectrace.materials import MATERIALS, kernel_file
from spectrace.materials.base import MaterialPlugin
from spectrace.pixel_filters import PIXEL_FILTERS
from spectrace.pixel_filters.base import PixelFilterPlugin
from spectrace.plugins import generated_sources
from spectrace.textures import TEXTURES
from spectrace.textures.base import TexturePlugin

KERNELS = resources.kernels_dir()
DOCS = Path(__file__).resolve().parents[1] / "docs"


@dataclass(frozen=True)
class Kind:
    registry: Registry
    protocol: type
    prefix: str  # of its device codes, <PREFIX>_<NAME> and <PREFIX>_TYPE_COUNT
    docs: str  # the page that describes each plugin of the kind


KINDS = {
    "material": Kind(MATERIALS, MaterialPlugin, "MATERIAL", "materials.md"),
    "texture": Kind(TEXTURES, TexturePlugin, "TEXTURE", "textures.md"),
    "camera": Kind(CAMERAS, CameraPlugin, "CAMERA", "scene-format.md"),
    "pixel filter": Kind(PIXEL_FILTERS, PixelFilterPlugin, "PIXEL_FILTER", "scene-format.md"),
}
PLUGINS = [(kind, name) for kind, spec in KINDS.items() for name in spec.registry]


def _members(protocol: type) -> list[str]:
    """The members a Protocol states, its bases' included."""
    return sorted({name for cls in protocol.__mro__ for name in vars(cls) if not name.startswith("_")})


def _device_case(kind: str, name: str) -> tuple[Path, str]:
    """The kernel file that must hold the plugin's device side, and the text that shows it does."""
    code = f"{KINDS[kind].prefix}_{name.upper()}"
    if kind == "material":
        return KERNELS / kernel_file(name), ""  # its own file; tests/materials/test_registry.py reads its functions
    if kind == "texture":
        # An image texture is read by its texel format (kernels/texture.cl's texel_value); a composite by its code.
        return KERNELS / "texture.cl", code if TEXTURES[name].COMPOSITE else "texel_format"
    return KERNELS / {"camera": "camera.cl", "pixel filter": "pixel_filter.cl"}[kind], code


def _documented(page: str, name: str) -> bool:
    """A heading, a table row or a list item of `page` that opens by naming the plugin (`name` or "name")."""
    pattern = rf'^(#+ |\| |- \*\*)[`"]*{re.escape(name)}[`"]'
    return re.search(pattern, (DOCS / page).read_text(encoding="utf-8"), re.MULTILINE) is not None


def test_each_kind_states_members_for_its_plugins_to_hold():
    """The runtime check below reads the Protocols' members; one that lost them would pass every plugin."""
    for spec in KINDS.values():
        assert {"NAME", "PARAMETERS"} <= set(_members(spec.protocol)), spec.protocol


@pytest.mark.parametrize(("kind", "name"), PLUGINS)
def test_every_plugin_holds_what_its_kind_states(kind, name):
    plugin = KINDS[kind].registry[name]
    missing = [member for member in _members(KINDS[kind].protocol) if not hasattr(plugin, member)]
    assert missing == [], f"{kind} {name} lacks {missing}"
    assert name == plugin.NAME
    assert all(parameter.name for parameter in plugin.PARAMETERS)


@pytest.mark.parametrize("kind", KINDS)
def test_every_build_gets_each_plugins_position_as_its_code(kind):
    spec = KINDS[kind]
    contract = kernel_contract(generated_sources())
    codes = {name: contract[f"{spec.prefix}_{name.upper()}"] for name in spec.registry}
    assert list(codes.values()) == list(range(len(spec.registry))), codes
    assert contract[f"{spec.prefix}_TYPE_COUNT"] == len(spec.registry)


def test_no_kernel_and_not_the_contract_writes_a_generated_code():
    """The codes come from the registries alone: a `#define` of one in the kernels, or a copy in the contract's
    defines, could disagree with the registry's order."""
    generated = set(generated_sources().defines)
    assert generated & set(device_contract_defines()) == set()
    written = []
    for path in sorted(KERNELS.rglob("*")):
        if path.suffix in (".cl", ".h"):
            defined = re.findall(r"^\s*#\s*define\s+(\w+)", path.read_text(encoding="utf-8"), re.MULTILINE)
            written += [f"{path.name}: {name}" for name in defined if name in generated]
    assert written == []


@pytest.mark.parametrize(("kind", "name"), PLUGINS)
def test_every_plugin_has_its_device_case(kind, name):
    path, text = _device_case(kind, name)
    assert path.is_file(), path
    assert text in path.read_text(encoding="utf-8"), f"{path.name} does not name {text}"


@pytest.mark.parametrize(("kind", "name"), PLUGINS)
def test_every_plugin_is_described_in_its_docs_page(kind, name):
    assert _documented(KINDS[kind].docs, name), f"docs/{KINDS[kind].docs} has no heading, row or item for {name}"


@pytest.mark.parametrize("name", list(TEXTURES))
def test_every_texture_is_constructed_in_the_api_by_its_make(name):
    module = TEXTURES[name]
    assert getattr(spectrace, module.API_NAME) is module.make
    assert module.API_NAME in spectrace.__all__


def test_the_docs_check_sees_a_missing_plugin():
    assert _documented("scene-format.md", "thinlens")
    assert not _documented("scene-format.md", "pinhole")
    assert not _documented("textures.md", "bitma")
