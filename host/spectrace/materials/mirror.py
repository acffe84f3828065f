"""`mirror`: perfect specular reflection of reflectance R(λ) (docs/materials.md, kernels/bsdf_mirror.cl)."""

from spectrace.core.parameters import reflectance
from spectrace.materials.opaque import ReflectanceOnly, reflectance_only
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.textures import reflectance_or_texture

NAME = "mirror"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = 'Mitsuba 3\'s mirror is a conductor of material "none", which conductor.py imports as a mirror'
PBRT_MATERIALS = ()
PBRT_NONE = "pbrt-v4 has no mirror material (pbrt-v3's `mirror` was removed)"
PARAMETERS = (reflectance(1.0, "perfect specular reflection scaled by R(λ)", textured=True),)


class MirrorMaterial(ReflectanceOnly):
    """Perfect specular reflection of reflectance R(λ)."""

    is_delta = True


MODEL = MirrorMaterial


from_spec, write_row = reflectance_only(MirrorMaterial)


def make(reflectance: SpectrumLike = PARAMETERS[0].number_default) -> MirrorMaterial:
    """Perfect specular reflection of reflectance R(λ) in [0, 1] (default 1; a spectrum or a texture), on both
    faces."""
    return MirrorMaterial(reflectance_or_texture(reflectance, "reflectance"))
