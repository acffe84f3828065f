"""Lights' host side: one module per light, listed in LIGHTS (the `[[lights]]` types) plus `area` (a shape's
emitter).

Each module opens with its parameter table (PARAMETERS, spectrace.core.parameters) and holds its resolved
dataclass (MODEL), `from_spec` (a validated scene-file table to the dataclass), SPEC_CHECKS for rules spanning
several keys, IS_ENVIRONMENT (a scene has at most one environment), `write_rows`, which adds its Light rows
(kernels/types.h) with an estimate of the power each emits to a LightRows (base.py), and its Mitsuba 3 mapping as a
material's: MITSUBA_PLUGINS with `from_mitsuba(importer, emitter, properties, to_world)` (area's without to_world:
it is on a shape) or MITSUBA_NONE, and `to_mitsuba` where the export has one.
"""

from spectrace.dispatch import module_by_model
from spectrace.lights import area, constant, distant, envmap, point, spot

__all__ = ["LIGHTS", "area", "constant", "distant", "envmap", "point", "spot"]

# Scene-file `type` -> module, in the order the schema lists them.
LIGHTS = {m.NAME: m for m in (point, spot, distant, constant, envmap)}
light_module = module_by_model(LIGHTS.values(), "light")
