"""The cameras (kernels/camera.cl): one module per type, each with its parameter table (the keys it takes beside
the shared ones in `shared.py`), the Mitsuba 3 plugins it imports and how it fills the RenderParams' camera fields.
`CAMERAS` lists them in the order of their device codes (spectrace.core.contract.CAMERA_TYPES)."""

from types import ModuleType

from spectrace.cameras import equirectangular, orthographic, perspective, thinlens
from spectrace.core.contract import CAMERA_TYPES

CAMERAS: dict[str, ModuleType] = {m.NAME: m for m in (perspective, thinlens, orthographic, equirectangular)}
assert tuple(CAMERAS) == CAMERA_TYPES
