"""The package's own imports, read from its source with `ast` (imports inside functions and under TYPE_CHECKING
included): what the layer and import-graph tests inspect."""

import ast
import functools
from pathlib import Path

import spectrace

ROOT = Path(spectrace.__file__).parent


def _module_name(path: Path) -> str:
    parts = ["spectrace", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1]) if parts[-1] == "__init__" else ".".join(parts)


MODULES = {_module_name(path): path for path in sorted(ROOT.rglob("*.py"))}


@functools.cache  # several tests walk every module's imports; the sources do not change during a run
def imports(name: str) -> tuple[tuple[str, str, int], ...]:
    """(module imported, name taken from it or "", line) for each import anywhere in module `name`."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, "", node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            found += [(base, alias.name, node.lineno) for alias in node.names]
    return tuple(found)


def targets(name: str) -> set[str]:
    """The package's modules that module `name` imports (`from package import module` names the module)."""
    found = set()
    for module, attribute, _ in imports(name):
        submodule = f"{module}.{attribute}"
        found.add(submodule if submodule in MODULES else module)
    return {target for target in found if target in MODULES}
