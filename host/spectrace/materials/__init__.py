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

import numpy as np

from spectrace.dispatch import module_by_model
from spectrace.engine.device_types import MATERIAL_DTYPE, MATERIAL_NO_SPECTRUM
from spectrace.materials import conductor, dielectric, diffuse, mirror, plastic, retroreflector
from spectrace.spectral.table import SpectrumTable

# Scene-file `type` -> module, in the order the schema lists them.
MATERIALS = {m.NAME: m for m in (diffuse, mirror, conductor, plastic, retroreflector, dielectric)}
material_module = module_by_model(MATERIALS.values(), "material")


def material_row(material, table: SpectrumTable) -> np.ndarray:
    """The Material row of `material`, adding its spectra to `table`."""
    module = material_module(material)
    row = np.zeros((), MATERIAL_DTYPE)
    row["reflectance_offset"] = row["eta_offset"] = row["k_offset"] = MATERIAL_NO_SPECTRUM
    row["ior"] = 1.0
    module.write_row(row, material, table)
    return row
