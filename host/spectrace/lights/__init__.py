"""Lights' host side: one module per light, listed in LIGHTS (the `[[lights]]` types) plus `area` (a shape's
emitter).

Each module opens with its parameter table (PARAMETERS, spectrace.core.parameters) and holds what base.LightPlugin
states: its resolved dataclass (MODEL), `from_spec` (a validated scene-file table to the dataclass), SPEC_CHECKS for
rules spanning several keys, IS_ENVIRONMENT (a scene has at most one environment), `write_rows`, which adds its
Light rows (kernels/types.h) with an estimate of the power each emits to a LightRows (base.py), `make` (the Python
API's constructor, `spectrace.<API_NAME>`), DEVICE_TYPES (the device light types of its rows) and its Mitsuba 3
mapping as a material's: MITSUBA_PLUGINS with `from_mitsuba(importer, emitter, properties, to_world)` (area's
without to_world: it is on a shape) or MITSUBA_NONE, and `to_mitsuba` where the export has one.

On the device a light is one unit, as pbrt-v4's: each device light type's kernel file kernels/light_<name>.cl holds
its sampling from a point, its densities, its emission sampling and its emitted light together. DEVICE_LIGHTS,
every module's DEVICE_TYPES in order, gives their codes (LIGHT_<NAME>, LIGHT_TYPE_COUNT) and light_list.h, the
X-macro lists through which kernels/lights.cl, light_emission.cl and bdpt.cl dispatch (`generated_sources`).
Adding a light: its module here and its line in LIGHTS, its kernel file, tests (docs/lights.md).
"""

from spectrace.core.api_calls import recorded
from spectrace.core.contract import GeneratedSources
from spectrace.core.registry import Registry
from spectrace.lights import area, constant, distant, envmap, goniometric, point, projector, spot
from spectrace.lights.base import DEVICE_LIGHT_KINDS, DeviceLight, LightPlugin, LightSource

__all__ = [
    "DEVICE_LIGHTS",
    "LIGHTS",
    "area",
    "constant",
    "distant",
    "envmap",
    "generated_sources",
    "goniometric",
    "point",
    "projector",
    "spot",
]

# Scene-file `type` -> module, in the order the schema lists them.
LIGHTS = Registry[LightPlugin]("light", (point, spot, distant, constant, envmap, projector, goniometric))
light_module = LIGHTS.for_model
# Each light an API constructor makes remembers its arguments, by which a live session edits it (core/api_calls.py).
for _module in LIGHTS.values():
    if _module.make is not None:
        _module.make = recorded(_module.make)  # type: ignore[misc]

# Every module that writes Light rows: the shapes' emitters, then the `[[lights]]`.
LIGHT_SOURCES: tuple[LightSource, ...] = (area, *LIGHTS.values())
# The device light types, in code order (Light.type).
DEVICE_LIGHTS = Registry[DeviceLight]("device light", (t for source in LIGHT_SOURCES for t in source.DEVICE_TYPES))

# The header kernels/lights.cl includes as "light_list.h"; spectrace.device writes it for each build that is handed
# it (`generated_sources`).
KERNEL_HEADER_NAME = "light_list.h"


def kernel_header() -> str:
    """light_list.h: every device light type's kernel file included; LIGHT_LIST(X), the X-macro list of them all,
    X(name, NAME) in code order; for each kind (base.DEVICE_LIGHT_KINDS) LIGHT_LIST_<KIND>(X), its types, through
    which the kernels dispatch the functions of that kind, and LIGHT_KIND_<KIND>(light), whether a light is of it."""
    includes = "".join(f'#include "{t.kernel_file}"\n' for t in DEVICE_LIGHTS.values())

    def entries(kind: str | None) -> str:
        chosen = [t for t in DEVICE_LIGHTS.values() if kind is None or t.kind == kind]
        return "".join(f" \\\n    X({t.name}, {t.name.upper()})" for t in chosen)

    def test(kind: str) -> str:
        chosen = [f"LIGHT_IS(light, LIGHT_{t.name.upper()})" for t in DEVICE_LIGHTS.values() if t.kind == kind]
        return " || ".join(chosen) or "0"

    lists = f"#define LIGHT_LIST(X){entries(None)}\n"
    for kind in DEVICE_LIGHT_KINDS:
        lists += f"#define LIGHT_LIST_{kind.upper()}(X){entries(kind)}\n"
        lists += f"#define LIGHT_KIND_{kind.upper()}(light) ({test(kind)})\n"
    return (
        "/* Generated from spectrace.lights.DEVICE_LIGHTS: do not edit. */\n"
        "#ifndef SPECTRACE_LIGHT_LIST_H\n#define SPECTRACE_LIGHT_LIST_H\n\n"
        f"{lists}\n{includes}\n#endif\n"
    )


def kernel_defines() -> dict[str, int]:
    """LIGHT_<NAME>: each device light type's code, LIGHT_TYPE_COUNT, and LIGHT_ENVIRONMENT_TYPES, the bits of the
    environments' types (kernels/scene_features.h: SCENE_HAS_ENVIRONMENT)."""
    codes = DEVICE_LIGHTS.codes
    environments = [t.name for m in LIGHTS.values() if m.IS_ENVIRONMENT for t in m.DEVICE_TYPES]
    return DEVICE_LIGHTS.kernel_defines("LIGHT") | {
        "LIGHT_ENVIRONMENT_TYPES": sum(1 << codes[name] for name in environments)
    }


def generated_sources() -> GeneratedSources:
    """The device light codes (kernel_defines) and light_list.h, which a build of kernels that sample lights is
    handed."""
    return GeneratedSources(kernel_defines(), {KERNEL_HEADER_NAME: kernel_header()})
