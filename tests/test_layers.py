"""The package's layers, read from the source with `ast`: the scene loader builds on the spectral layer, never on
the display experiments; the display experiments reach the renderer through the public API only. (That no modules
import each other around a loop is tests/test_import_graph.py's.)"""

import ast
from pathlib import Path

import spectrace

ROOT = Path(spectrace.__file__).parent


def _module_name(path: Path) -> str:
    parts = ["spectrace", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1]) if parts[-1] == "__init__" else ".".join(parts)


MODULES = {_module_name(path): path for path in sorted(ROOT.rglob("*.py"))}


def _imports(name: str, top_level_only: bool) -> list[tuple[str, str, int]]:
    """(module imported, name taken from it or "", line) for each import in module `name`: every one, or only
    those run when the module is first imported (the module's own statements, not functions or TYPE_CHECKING)."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    found = []
    for node in nodes:
        if isinstance(node, ast.Import):
            found += [(alias.name, "", node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            found += [(base, alias.name, node.lineno) for alias in node.names]
    return found


def _targets(name: str, top_level_only: bool) -> set[str]:
    """The package's modules that module `name` imports (`from package import module` names the module)."""
    targets = set()
    for module, attribute, _ in _imports(name, top_level_only):
        submodule = f"{module}.{attribute}"
        targets.add(submodule if submodule in MODULES else module)
    return {target for target in targets if target in MODULES}


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_the_module_list_is_the_package():
    assert {"spectrace.scene.loader", "spectrace.displays.metamerism", "spectrace.cli"} <= set(MODULES)


def test_the_scene_layer_does_not_import_the_display_experiments():
    found = [
        f"{name} imports {target}"
        for name in MODULES
        if _in(name, "spectrace.scene")
        for target in _targets(name, top_level_only=False)
        if _in(target, "spectrace.displays")
    ]
    assert found == []


def test_the_spectral_layer_imports_no_layer_above_it():
    above = ("spectrace.scene", "spectrace.displays", "spectrace.engine", "spectrace.api", "spectrace.cli")
    found = [
        f"{name} imports {target}"
        for name in MODULES
        if _in(name, "spectrace.spectral")
        for target in _targets(name, top_level_only=False)
        if any(_in(target, layer) for layer in above)
    ]
    assert found == []


def test_the_display_experiments_reach_the_renderer_through_the_public_api_only():
    found = []
    for name in MODULES:
        if not _in(name, "spectrace.displays"):
            continue
        for module, attribute, line in _imports(name, top_level_only=False):
            if _in(module, "spectrace.engine"):
                found.append(f"{name}:{line} imports {module}")
            elif module == "spectrace.api" and attribute.startswith("_"):
                found.append(f"{name}:{line} imports the private {module}.{attribute}")
    assert found == []
