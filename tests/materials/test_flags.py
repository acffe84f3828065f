"""The flags each material states on the host (is_delta, has_transmission, is_dispersive) agree with the kernels:
is_delta with the dispatch's material_has_non_delta_lobe (kernels/material.cl), which decides whether next-event
estimation runs at a hit, and has_transmission / is_dispersive with what the BSDF's samples do."""

import numpy as np
import pytest

from rgl_tensor import ggx_material
from spectrace.materials import material_row
from spectrace.scene.model import (
    ConductorMaterial,
    DielectricMaterial,
    DiffuseMaterial,
    MirrorMaterial,
    PlasticMaterial,
    PrincipledMaterial,
    RetroreflectorMaterial,
    ThindielectricMaterial,
)
from spectrace.spectral.glasses import index_of_refraction
from spectrace.spectral.metals import metal_ior
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from spectrace.textures import TextureRows
from spectrace.textures.bitmap import make as bitmap

GREY = Spectrum.constant(0.8)
# Roughness textures: smooth everywhere (largest α below the 0.001 limit), and smooth in places only.
SMOOTH_MAP = bitmap(np.array([[0.0, 0.0009]]))
MIXED_MAP = bitmap(np.array([[0.0, 0.3]]))
CASES = [
    ("diffuse", DiffuseMaterial(GREY)),
    ("mirror", MirrorMaterial(GREY)),
    *[(f"conductor-a{a}", ConductorMaterial(*metal_ior("Cu"), roughness=a)) for a in (0.0, 0.0009, 0.001, 0.3)],
    *[(f"plastic-a{a}", PlasticMaterial(GREY, roughness=a)) for a in (0.0, 0.3)],
    *[(f"retroreflector-a{a}", RetroreflectorMaterial(GREY, roughness=a)) for a in (0.0, 0.2)],
    ("thindielectric", ThindielectricMaterial(1.5)),
    *[
        (f"dielectric-{ior}-a{a}", DielectricMaterial(index_of_refraction(ior), roughness=a))
        for ior in (1.5, "SF11")
        for a in (0.0, 0.2)
    ],
    *[
        (f"{kind}-texture-{which}", make(texture))
        for which, texture in (("smooth", SMOOTH_MAP), ("mixed", MIXED_MAP))
        for kind, make in (
            ("conductor", lambda t: ConductorMaterial(*metal_ior("Cu"), roughness=t)),
            ("plastic", lambda t: PlasticMaterial(GREY, roughness=t)),
            ("retroreflector", lambda t: RetroreflectorMaterial(GREY, roughness=t)),
            ("dielectric-1.5", lambda t: DielectricMaterial(index_of_refraction(1.5), roughness=t)),
        )
    ],
    # The principled material never has a delta lobe (α ≥ 0.001); it transmits where spec_trans is above 0
    # somewhere (a texture's largest value) and metallic below 1.
    ("principled-opaque", PrincipledMaterial(GREY, index_of_refraction("SF11"), roughness=0.0)),
    ("principled-metal", PrincipledMaterial(GREY, index_of_refraction(1.5), metallic=1.0, spec_trans=1.0)),
    ("principled-glass-1.5", PrincipledMaterial(GREY, index_of_refraction(1.5), roughness=0.0, spec_trans=1.0)),
    ("principled-glass-SF11", PrincipledMaterial(GREY, index_of_refraction("SF11"), spec_trans=0.5)),
    ("principled-glass-texture", PrincipledMaterial(GREY, index_of_refraction(1.5), spec_trans=MIXED_MAP)),
    # A measured reflector (tests/rgl_tensor.py): one glossy lobe, no transmission.
    ("measured-ggx", ggx_material(0.3)),
]


@pytest.mark.parametrize("name, material", CASES, ids=[c[0] for c in CASES])
def test_is_delta_is_the_kernels_verdict(kernel_runner, name, material):
    runner = kernel_runner("testing/bsdf.cl")
    table = SpectrumTable()
    row = material_row(material, table, TextureRows(table, [np.zeros((1, 4), np.float32)]))
    result = np.zeros(1, np.int32)
    runner.run("bsdf_has_non_delta_lobe", 1, [runner.buffer(np.array([row])), runner.buffer(result, True)], {1: result})
    assert material.is_delta == (not result[0])


def test_only_the_dielectrics_and_principled_glass_transmit_and_disperse():
    for name, material in CASES:
        assert material.has_transmission == name.startswith(("dielectric", "thindielectric", "principled-glass")), name
        # A constant index steers every wavelength alike; SF11's Sellmeier index does not.
        assert material.is_dispersive == ("SF11" in name), name
