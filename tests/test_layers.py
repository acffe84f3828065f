"""The package's layers, read from the source with `ast`: the scene loader builds on the spectral layer, never on
the display experiments; the display experiments reach the renderer through the public API only. (That no modules
import each other around a loop is tests/test_import_graph.py's.)"""

from package_imports import MODULES, imports, targets


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_the_module_list_is_the_package():
    assert {"spectrace.scene.loader", "spectrace.displays.metamerism", "spectrace.cli"} <= set(MODULES)


def test_the_scene_layer_does_not_import_the_display_experiments():
    found = [
        f"{name} imports {target}"
        for name in MODULES
        if _in(name, "spectrace.scene")
        for target in targets(name)
        if _in(target, "spectrace.displays")
    ]
    assert found == []


def test_the_spectral_layer_imports_no_layer_above_it():
    above = ("spectrace.scene", "spectrace.displays", "spectrace.engine", "spectrace.api", "spectrace.cli")
    found = [
        f"{name} imports {target}"
        for name in MODULES
        if _in(name, "spectrace.spectral")
        for target in targets(name)
        if any(_in(target, layer) for layer in above)
    ]
    assert found == []


def test_the_display_experiments_reach_the_renderer_through_the_public_api_only():
    found = []
    for name in MODULES:
        if not _in(name, "spectrace.displays"):
            continue
        for module, attribute, line in imports(name):
            if _in(module, "spectrace.engine"):
                found.append(f"{name}:{line} imports {module}")
            elif module == "spectrace.api" and attribute.startswith("_"):
                found.append(f"{name}:{line} imports the private {module}.{attribute}")
    assert found == []
