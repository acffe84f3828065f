"""`diffuse`: Lambertian reflection, f = R(λ)/π, on both faces (docs/materials.md, kernels/bsdf_diffuse.cl)."""

from spectrace.materials.opaque import ReflectanceOnly, reflectance_only
from spectrace.materials.parameters import REQUIRED, reflectance

NAME = "diffuse"
MITSUBA_PLUGINS = ("diffuse",)
PARAMETERS = (reflectance(REQUIRED, "Lambertian reflection f = R(λ)/π"),)


class DiffuseMaterial(ReflectanceOnly):
    """Lambertian, f = R(λ)/π, reflecting on both faces."""

    is_delta = False


MODEL = DiffuseMaterial


from_spec, make, write_row = reflectance_only(DiffuseMaterial)


def from_mitsuba(importer, bsdf, properties) -> dict | None:
    reflectance = properties.get("reflectance")
    spectrum = importer.spectrum(reflectance, "reflectance") if reflectance is not None else {"value": 0.5}
    return None if spectrum is None else {"type": "diffuse", "reflectance": spectrum}


def to_mitsuba(material: DiffuseMaterial, exporter) -> dict:
    # Mitsuba's diffuse is black from behind; spectrace's reflects on both faces.
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": exporter.spectrum(material.reflectance)}}
