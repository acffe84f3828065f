"""The integrators: one module per integrator, listed in INTEGRATORS (the `[integrator] type`s).

Each module opens with its NAME and its parameter table (PARAMETERS: the `[integrator]` keys it takes, the shared
ones of base.py and its own) and owns the rest of what the renderer asks of it (IntegratorPlugin): its kernel
programs by kernel shape (PROGRAMS) and their build `defines`, what it refuses (`problem`, one line naming the way
out; REFUSES, the features it refuses in any scene), whether its contributions land in any pixel (SPLATS: then it
renders whole films, never tiles), why it cannot save a checkpoint (CHECKPOINT_PROBLEM; a checkpoint holds the
film's state and matches the program's `defines` and `params`), its run-time `params` (RenderParams fields of its
own), and its `passes`: the device state and the pass loop over a renderer (base.RenderHost). The engine asks these,
never an integrator's name.

Adding an integrator: its module here, its line in INTEGRATORS, its kernel program (kernels/integrator_<NAME>.cl),
tests (docs/integrators.md, "Adding an integrator").
"""

from collections.abc import Mapping
from typing import Protocol

from spectrace.core import limits
from spectrace.core.parameters import Parameter
from spectrace.core.registry import Plugin, Registry
from spectrace.integrators import bdpt, direct, light, path, sppm
from spectrace.integrators.base import Passes, RenderHost, Scene


class IntegratorPlugin(Plugin, Protocol):
    """What an integrator module holds (mypy checks each module of INTEGRATORS against it), with its importer
    mappings: MITSUBA_PLUGINS with `from_mitsuba(importer, element, properties, settings) -> dict` (the Mitsuba
    integrators it imports; `settings` the shared keys read) or MITSUBA_NONE saying why it has none, and optional
    `to_mitsuba(scene) -> dict` (the export's integrator); PBRT_INTEGRATORS with `from_pbrt(context, integrator)
    -> dict` or PBRT_NONE."""

    @property
    def PARAMETERS(self) -> tuple[Parameter, ...]: ...  # noqa: N802 (module constants)
    @property
    def PROGRAMS(self) -> Mapping[str, str]: ...  # noqa: N802 (kernel shape -> program file under kernels/)
    @property
    def SPLATS(self) -> str | None: ...  # noqa: N802 (what of a pass lands in any pixel; None: its own pixel's)
    @property
    def CHECKPOINT_PROBLEM(self) -> str | None: ...  # noqa: N802 (why it cannot save a checkpoint)
    @property
    def SHARES_GENERAL_PROGRAM(self) -> bool: ...  # noqa: N802 (whether `common` renders on its general program)
    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802
    @property
    def PBRT_INTEGRATORS(self) -> tuple[str, ...]: ...  # noqa: N802
    @property
    def REFUSES(self) -> tuple[str, ...]: ...  # noqa: N802 (of base.FEATURES: what `problem` refuses in any scene)

    def problem(self, scene: Scene, medium_count: int, spectral_bins: int) -> str | None:
        """Why it cannot render `scene` (with `medium_count` media, `spectral_bins` bands), or None."""
        ...

    def defines(self, scene: Scene) -> dict[str, int]:
        """Build defines of its program for `scene` beyond the renderer's (a checkpoint must match them too)."""
        ...

    def params(self, scene: Scene) -> dict[str, int]:
        """Fields of RenderParams its kernels read for `scene`: settings of its own passed at run time rather than
        as defines, so that one program serves every value (a checkpoint must match them too)."""
        ...

    def passes(self, host: RenderHost, shape: str, spectral_bins: int) -> Passes:
        """Its passes over a renderer of kernel shape `shape` (one of PROGRAMS), with its device state."""
        ...


# In the order the schema and the docs list them.
INTEGRATORS = Registry[IntegratorPlugin]("integrator", (path, direct, light, bdpt, sppm))
KERNEL_SHAPES = tuple(dict.fromkeys(shape for plugin in INTEGRATORS.values() for shape in plugin.PROGRAMS))


def _owners(key: str) -> list[str]:
    return [name for name, plugin in INTEGRATORS.items() if any(p.name == key for p in plugin.PARAMETERS)]


def _own_keys() -> dict[str, Parameter]:
    """Every key some integrators take and others do not, by name."""
    keys = {p.name: p for plugin in INTEGRATORS.values() for p in plugin.PARAMETERS}
    return {name: p for name, p in keys.items() if len(_owners(name)) < len(INTEGRATORS)}


def key_problem(integrator: str, key: str, value: object) -> str | None:
    """Why `key` = `value` cannot be given to `integrator` (a key of other integrators set away from its default), or
    None. A flag names the value refused (its default is allowed anywhere)."""
    parameter = _own_keys().get(key)
    if parameter is None or value == parameter.default or key in {p.name for p in INTEGRATORS[integrator].PARAMETERS}:
        return None
    owners = " or ".join(f"'{name}'" for name in _owners(key))
    given = f"{key} = {str(value).lower()}" if parameter.type == "bool" else key
    return f"{given} is only for integrator {owners}, not '{integrator}'"


def value_problem(key: str, value: object) -> str | None:
    """Why `value` is not a value of an integrator's own key `key` (a whole number within its range), or None."""
    parameter = _own_keys().get(key)
    if parameter is None or value is None or parameter.type != "int":
        return None
    if problem := limits.whole_number_problem(key, value):
        return problem
    bounds = parameter.range
    if bounds is not None and bounds.bounded and not bounds.contains(float(value)):  # type: ignore[arg-type]
        return f"{key} must lie in {bounds.low:g}..{bounds.high:g}, got {value}"
    return None


def settings_problem(integrator: str, settings: object) -> str | None:
    """Why the integrator keys of `settings` (a scene file's [integrator] table) cannot go to `integrator`: a key of
    other integrators, or a value out of its range; or None."""
    for key in _own_keys():
        value = getattr(settings, key)
        if problem := key_problem(integrator, key, value) or value_problem(key, value):
            return problem
    return None


def scene_settings_problem(scene: Scene) -> str | None:
    """settings_problem for a scene about to be rendered. A render switched to another integrator (with_overrides,
    --integrator) leaves the number keys of the scene's own unused (a bdpt scene's pixels_per_light_path rendered by
    'path'); their ranges still hold. A flag set away from its default changes what a path is, so another
    integrator refuses it rather than render something else than asked. A fluorescent material is refused by the
    integrators that transport each wavelength on its own (spectrace.materials.fluorescent.INTEGRATORS)."""
    from spectrace.materials.fluorescent import integrator_problem

    if problem := integrator_problem(scene, scene.integrator):
        return problem
    for key, parameter in _own_keys().items():
        value = getattr(scene, key)
        owner_problem = key_problem(scene.integrator, key, value) if parameter.type == "bool" else None
        if problem := owner_problem or value_problem(key, value):
            return problem
    return None
