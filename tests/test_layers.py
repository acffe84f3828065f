"""The package's layers, read from the source with `ast` (imports inside functions and under TYPE_CHECKING
included): the bottom (spectrace.core: the host/device contract, the parameter vocabulary, the limits) imports
nothing above it; plugins build on it and never on the engine, the scene or the device layer; the device layer is
handed what the registries generate and reads none of them; the scene loader builds on the spectral layer, never on
the display experiments; the display experiments reach the renderer through the public API only. (That no modules
import each other around a loop is tests/test_import_graph.py's.) Each test lists every import that breaks its
rule."""

from package_imports import MODULES, imports, targets

PLUGINS = (
    "spectrace.materials",
    "spectrace.lights",
    "spectrace.textures",
    "spectrace.cameras",
    "spectrace.pixel_filters",
)


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def _violations(importers: tuple[str, ...], forbidden: tuple[str, ...], graph=None) -> list[str]:
    """Each "A imports B": a module A of `importers` importing a module B of `forbidden`."""
    graph = graph if graph is not None else {name: targets(name) for name in MODULES}
    return sorted(
        f"{name} imports {target}"
        for name, found in graph.items()
        if any(_in(name, package) for package in importers)
        for target in found
        if any(_in(target, package) for package in forbidden)
    )


def test_the_module_list_is_the_package():
    assert {"spectrace.scene.loader", "spectrace.displays.metamerism", "spectrace.cli"} <= set(MODULES)
    assert {"spectrace.core.contract", "spectrace.core.parameters", "spectrace.core.limits"} <= set(MODULES)
    assert {"spectrace.materials.diffuse", "spectrace.lights.point", "spectrace.device.program_cache"} <= set(MODULES)


def test_the_checks_list_what_breaks_a_rule():
    """The rules' check reports a forbidden import it is shown (so an empty list means none was found)."""
    graph = {
        "spectrace.lights.point": {"spectrace.core.limits", "spectrace.engine.renderer"},
        "spectrace.lights": {"spectrace.lights.point"},
        "spectrace.device.program_cache": {"spectrace.materials"},
    }
    assert _violations(PLUGINS, ("spectrace.engine",), graph) == [
        "spectrace.lights.point imports spectrace.engine.renderer"
    ]
    assert _violations(("spectrace.device",), ("spectrace.materials",), graph) == [
        "spectrace.device.program_cache imports spectrace.materials"
    ]


def test_the_bottom_imports_only_itself_and_modules_that_import_nothing_of_the_package():
    """spectrace.core may use the errors and the wavelength grid, which import nothing of the package; anything
    else it imported would sit below the bottom and above it at once."""
    found = [
        f"{name} imports {target}"
        for name in MODULES
        if _in(name, "spectrace.core")
        for target in sorted(targets(name))
        if not _in(target, "spectrace.core") and targets(target) - {target}
    ]
    assert found == []


def test_plugins_never_import_the_engine_the_scene_or_the_device_layer():
    """A material, light, texture, camera or pixel filter is one module over the bottom layer: the engine, the scene
    loader and the device layer import plugins (through their registries), never the other way."""
    above = ("spectrace.engine", "spectrace.scene", "spectrace.device", "spectrace.api", "spectrace.cli")
    assert _violations(PLUGINS, above) == []


def test_integrators_are_handed_their_renderer_and_import_no_layer_above_the_plugins():
    """An integrator reads the scene's fields and runs its passes through what the renderer hands it
    (spectrace.integrators.base.RenderHost); the scene layer imports the integrator registry for its names."""
    above = (
        "spectrace.engine",
        "spectrace.scene",
        "spectrace.device",
        "spectrace.film",
        "spectrace.api",
        "spectrace.cli",
    )
    assert _violations(("spectrace.integrators",), above) == []


def test_the_device_layer_reads_no_registry_and_no_scene():
    """Kernel builds are handed the registries' generated headers and codes (GeneratedSources); the device layer
    knows OpenCL runtimes and the contract, nothing of what is rendered."""
    assert _violations(("spectrace.device",), (*PLUGINS, "spectrace.scene", "spectrace.engine")) == []


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
