"""The BSDF library's host side: one module per material, listed in MATERIALS.

Each module opens with its parameter table (PARAMETERS, see parameters.py) and holds the rest of what the host
knows about the material: its resolved dataclass (MODEL) with the flags the kernels' dispatch also states
(is_delta: only delta lobes; has_transmission; is_dispersive), `from_spec` (a validated scene-file table to the
dataclass), `make` (the Python API's checks), `write_row` (its Material row, kernels/types.h), where a rule
spans several keys SPEC_CHECKS for the scene schema, and its Mitsuba 3 mapping: MITSUBA_PLUGINS with `from_mitsuba`
(or MITSUBA_NONE, why it has none) for the importer, `to_mitsuba` for the export where Mitsuba can do the same work
(spectrace.interop dispatches to them through MATERIALS). The BSDF itself is kernels/bsdf_<name>.cl.

Adding a BSDF: its module here, one entry in MATERIALS, its kernel file and case in kernels/material.cl, tests.
"""

import dataclasses

import numpy as np

from spectrace.dispatch import module_by_model
from spectrace.engine.device_types import MATERIAL_DTYPE, MATERIAL_NO_SPECTRUM, NO_TEXTURE
from spectrace.materials import conductor, dielectric, diffuse, mirror, plastic, retroreflector
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

# Scene-file `type` -> module, in the order the schema lists them.
MATERIALS = {m.NAME: m for m in (diffuse, mirror, conductor, plastic, retroreflector, dielectric)}
material_module = module_by_model(MATERIALS.values(), "material")


def material_textures(material) -> dict:
    """The textured parameters of `material` that hold a texture, by name."""
    from spectrace.textures import is_texture

    module = material_module(material)
    return {
        p.name: getattr(material, p.name)
        for p in module.PARAMETERS
        if p.textured and is_texture(getattr(material, p.name))
    }


def material_row(material, table: SpectrumTable, textures=None) -> np.ndarray:
    """The Material row of `material`, adding its spectra to `table` and its textures to `textures` (a
    spectrace.textures.TextureRows). A textured parameter's row field `<name>_texture` holds the texture's index;
    the module's write_row sees a zero spectrum in its place, so it needs to know nothing of textures."""
    module = material_module(material)
    row = np.zeros((), MATERIAL_DTYPE)
    row["reflectance_offset"] = row["eta_offset"] = row["k_offset"] = MATERIAL_NO_SPECTRUM
    row["ior"] = 1.0
    row["reflectance_texture"] = NO_TEXTURE
    textured = material_textures(material)
    if textured:
        material = dataclasses.replace(material, **{name: Spectrum.zeros() for name in textured})
    module.write_row(row, material, table)
    for name, texture in textured.items():
        kind = next(p.type for p in module.PARAMETERS if p.name == name)
        row[f"{name}_texture"] = textures.add(texture, "float" if kind == "float" else "spectrum")
    return row
