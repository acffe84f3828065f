"""`diffuse`: Lambertian reflection, f = R(λ)/π, on both faces (docs/materials.md, kernels/bsdf_diffuse.cl)."""

from spectrace.core.parameters import REQUIRED, reflectance
from spectrace.materials.opaque import ReflectanceOnly, reflectance_only
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.textures import reflectance_or_texture

NAME = "diffuse"
MITSUBA_PLUGINS = ("diffuse",)
PBRT_MATERIALS = ("diffuse",)
PARAMETERS = (reflectance(REQUIRED, "Lambertian reflection f = R(λ)/π", textured=True),)


class DiffuseMaterial(ReflectanceOnly):
    """Lambertian, f = R(λ)/π, reflecting on both faces."""

    is_delta = False
    is_diffuse = True


MODEL = DiffuseMaterial


from_spec, write_row = reflectance_only(DiffuseMaterial)


def make(reflectance: SpectrumLike) -> DiffuseMaterial:
    """Lambertian material, f = R(λ)/π, reflecting on both faces; `reflectance` in [0, 1] (a linear sRGB triple is
    uplifted)."""
    return DiffuseMaterial(reflectance_or_texture(reflectance, "reflectance"))


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    reflectance = properties.get("reflectance")
    spectrum = importer.spectrum(reflectance, "reflectance") if reflectance is not None else {"value": 0.5}
    return None if spectrum is None else {"type": "diffuse", "reflectance": spectrum}


def from_pbrt(context, material) -> dict | None:
    return {"type": "diffuse", "reflectance": context.reflectance(material, "reflectance", 0.5)}


def to_mitsuba(material: DiffuseMaterial, exporter) -> dict:
    # Mitsuba's diffuse is black from behind; spectrace's reflects on both faces.
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": exporter.spectrum(material.reflectance)}}
