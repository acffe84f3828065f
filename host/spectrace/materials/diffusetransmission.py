"""`diffusetransmission`: Lambertian reflection R(λ)/π on the side light arrives from and Lambertian transmission
T(λ)/π to the other side (paper, a lampshade, a leaf); pbrt-v4's `diffusetransmission` material
(docs/materials.md, kernels/bsdf_diffusetransmission.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.core.parameters import REQUIRED, reflectance
from spectrace.materials.base import Material
from spectrace.spectral import spectrum_input
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import SpectrumLike
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import reflectance_or_texture

NAME = "diffusetransmission"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = "Mitsuba 3 has no diffuse transmission BSDF (its 0.6 `difftrans` plugin was not carried over)"
PBRT_MATERIALS = ("diffusetransmission",)
PARAMETERS = (
    reflectance(REQUIRED, "Lambertian reflection f = R(λ)/π on the side the light arrives from", textured=True),
    reflectance(REQUIRED, "Lambertian transmission f = T(λ)/π to the other side (R + T ≤ 1)", name="transmittance"),
)


@dataclass(frozen=True)
class DiffusetransmissionMaterial(Material):
    """Lambertian reflection `reflectance`/π and Lambertian transmission `transmittance`/π, the same from both
    faces."""

    reflectance: Spectrum  # or a texture
    transmittance: Spectrum

    is_delta = False
    is_diffuse = True
    has_transmission = True
    is_dispersive = False


MODEL = DiffusetransmissionMaterial


def from_spec(spec, resolver, key: str) -> DiffusetransmissionMaterial:
    return DiffusetransmissionMaterial(
        resolver.spectrum_or_texture(spec.reflectance, f"{key}.reflectance", "spectrum"),
        resolver.spectrum(spec.transmittance, f"{key}.transmittance", emission=False),
    )


def make(reflectance: SpectrumLike, transmittance: SpectrumLike) -> DiffusetransmissionMaterial:
    """Lambertian reflection R/π and transmission T/π (both in [0, 1], R + T ≤ 1 for energy conservation; a linear
    sRGB triple is uplifted); `reflectance` may be a texture."""
    return DiffusetransmissionMaterial(
        reflectance_or_texture(reflectance, "reflectance"),
        spectrum_input.reflectance(transmittance, "transmittance"),
    )


def from_pbrt(context, material) -> dict | None:
    """pbrt-v4's DiffuseTransmissionMaterial: Lambertian reflection and transmission, `reflectance` and
    `transmittance` (defaults 0.25 each) both multiplied by `scale` (default 1)."""
    factor = context.one(material, "scale", 1.0)
    table: dict = {"type": "diffusetransmission"}
    for key in ("reflectance", "transmittance"):
        value = context.reflectance(material, key, 0.25)
        if factor != 1.0:
            if "value" in value:
                value = {"value": value["value"] * factor}
            elif "rgb" in value:
                value = {"rgb": [c * factor for c in value["rgb"]]}
            else:
                raise context.error(
                    material.location,
                    f'diffusetransmission "scale" {factor:g} on a {key} that is not a number or rgb: spectrace '
                    "scales only those",
                )
        table[key] = value
    return table


def write_row(row: np.ndarray, material: DiffusetransmissionMaterial, table: SpectrumTable) -> None:
    row["reflectance_offset"] = table.add(material.reflectance)
    row["transmittance_offset"] = table.add(material.transmittance)
