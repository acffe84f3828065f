"""`mirror`: perfect specular reflection of reflectance R(λ) (docs/materials.md, kernels/bsdf_mirror.cl)."""

from dataclasses import dataclass

from spectrace.engine.device_types import MATERIAL_MIRROR
from spectrace.materials.opaque import Opaque, reflectance_only
from spectrace.materials.parameters import reflectance
from spectrace.spectral.spectrum import Spectrum

NAME = "mirror"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = 'Mitsuba 3\'s mirror is a conductor of material "none", which conductor.py imports as a mirror'
PARAMETERS = (reflectance(1.0, "perfect specular reflection scaled by R(λ)"),)


@dataclass(frozen=True)
class MirrorMaterial(Opaque):
    """Perfect specular reflection of reflectance R(λ)."""

    reflectance: Spectrum

    is_delta = True


MODEL = MirrorMaterial


from_spec, make, write_row = reflectance_only(MirrorMaterial, MATERIAL_MIRROR)
