"""MATERIALS (spectrace/materials/__init__.py) is the one list of the BSDFs: the type codes, the kernels' dispatch
list and includes, the scene model's material type, the API's constructors and the package's names all come from
it, and no other list of the materials is kept by hand, on the host or in the kernels."""

import ast
import re

import pytest

import spectrace
from package_imports import MODULES
from spectrace import api, resources
from spectrace.device.program_cache import kernel_contract
from spectrace.materials import BSDFS, KERNEL_HEADER_NAME, MATERIAL_CODES, MATERIALS, generated_sources, kernel_file
from spectrace.materials.base import Material

KERNELS = resources.kernels_dir()


def _generated_list() -> list[tuple[str, str, str]]:
    header = generated_sources().headers[KERNEL_HEADER_NAME]
    body = header.split("#define MATERIAL_LIST(X)", 1)[1]
    return re.findall(r"X\((\w+), (\w+), (\w+)\)", body)


def test_the_generated_kernel_list_is_the_registry_in_code_order():
    """The BSDFs come first, in code order; the composites (a mix, a fluorescent dye over its base), which have no
    BSDF, after them and outside the list, with codes of their own."""
    expected = [(f"MATERIAL_{name.upper()}", name, f"{name.capitalize()}Params") for name in BSDFS]
    assert _generated_list() == expected
    contract = kernel_contract(generated_sources())
    assert [contract[code] for code, _, _ in _generated_list()] == list(range(len(BSDFS)))
    assert contract["MATERIAL_TYPE_COUNT"] == len(MATERIALS) == len(set(MATERIAL_CODES.values()))
    composites = [name for name in MATERIALS if name not in BSDFS]
    assert composites == ["mix", "fluorescent"]
    assert [contract[f"MATERIAL_{name.upper()}"] for name in composites] == list(range(len(BSDFS), len(MATERIALS)))


def test_every_registered_bsdf_has_its_kernel_file_with_the_functions_the_dispatch_calls():
    header = generated_sources().headers[KERNEL_HEADER_NAME]
    for name in BSDFS:
        path = KERNELS / kernel_file(name)
        assert path.is_file(), path
        assert f'#include "{kernel_file(name)}"' in header
        source = path.read_text(encoding="utf-8")
        assert re.search(rf"}}\s*{name.capitalize()}Params;", source), f"{path.name}: {name.capitalize()}Params"
        for function in ("flags", "params", "eval", "pdf", "sample"):
            assert re.search(rf"\b{name}_{function}\(", source), f"{path.name}: {name}_{function}"


def test_every_bsdf_kernel_file_is_registered():
    shared = {"bsdf_sample.cl"}  # what every BSDF uses, not a BSDF
    files = {path.name for path in KERNELS.glob("bsdf_*.cl")} - shared
    assert files == {kernel_file(name) for name in BSDFS}


def test_a_composite_has_its_own_kernel_file_outside_the_bsdf_list():
    header = generated_sources().headers[KERNEL_HEADER_NAME]
    for name in set(MATERIALS) - set(BSDFS):
        assert (KERNELS / kernel_file(name)).is_file() and not kernel_file(name).startswith("bsdf_")
        assert kernel_file(name) not in header


def test_no_kernel_file_lists_the_bsdfs():
    listed = []
    for path in sorted(KERNELS.rglob("*")):
        if path.suffix in (".cl", ".h"):
            text = path.read_text(encoding="utf-8")
            if re.search(r"#\s*define\s+MATERIAL_LIST\b", text):
                listed.append(f"{path.name}: MATERIAL_LIST")
            listed += [f"{path.name}: {n}" for n in re.findall(r'#\s*include\s+"(bsdf_(?!sample)\w+\.cl)"', text)]
    assert listed == []


@pytest.mark.slow
def test_no_host_module_but_the_registry_names_every_material():
    """A module holding every material's name as a string, or importing every material module, keeps a list."""
    names = set(MATERIALS)
    found = []
    for module, path in MODULES.items():
        if module == "spectrace.materials":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        strings = {node.value for node in ast.walk(tree) if isinstance(node, ast.Constant)}
        imported = {
            alias.name
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.module == "spectrace.materials"
            for alias in node.names
        }
        if names <= strings or names <= imported:
            found.append(module)
    assert found == []


def test_the_api_constructors_and_models_come_from_the_registry():
    for name, module in MATERIALS.items():
        assert getattr(api, name) is module.make
        assert getattr(spectrace, name) is module.make
        assert name in spectrace.__all__ and module.MODEL.__name__ in spectrace.__all__
        assert getattr(spectrace, module.MODEL.__name__) is module.MODEL
        assert issubclass(module.MODEL, Material)
