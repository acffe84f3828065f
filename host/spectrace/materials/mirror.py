"""`mirror`: perfect specular reflection of reflectance R(λ) (docs/materials.md, kernels/bsdf_mirror.cl)."""

from spectrace.materials.opaque import ReflectanceOnly, reflectance_only
from spectrace.materials.parameters import reflectance

NAME = "mirror"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = 'Mitsuba 3\'s mirror is a conductor of material "none", which conductor.py imports as a mirror'
PARAMETERS = (reflectance(1.0, "perfect specular reflection scaled by R(λ)"),)


class MirrorMaterial(ReflectanceOnly):
    """Perfect specular reflection of reflectance R(λ)."""

    is_delta = True


MODEL = MirrorMaterial


from_spec, make, write_row = reflectance_only(MirrorMaterial)
