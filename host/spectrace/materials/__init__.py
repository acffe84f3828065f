"""The BSDF library's host side: one module per material, listed in MATERIALS.

Each module opens with its parameter table (PARAMETERS, see parameters.py) and holds the rest of what the host
knows about the material: its resolved dataclass (MODEL, a base.Material) with the flags the kernels' dispatch also
states (is_delta: only delta lobes; has_transmission; is_dispersive), `from_spec` (a validated scene-file table to
the dataclass), `make` (the Python API's constructor, `spectrace.<NAME>`), `write_row` (its Material row but the
type code, kernels/types.h), where a rule spans several keys SPEC_CHECKS for the scene schema, and its Mitsuba 3
mapping: MITSUBA_PLUGINS with `from_mitsuba` (or MITSUBA_NONE, why it has none) for the importer, `to_mitsuba` for
the export where Mitsuba can do the same work (spectrace.interop dispatches to them through MATERIALS). The BSDF
itself is kernels/bsdf_<NAME>.cl.

MATERIALS is the one list of the BSDFs: the type codes, the kernels' MATERIAL_LIST and their bsdf_*.cl includes
(`kernel_defines`, `kernel_header`, added to every kernel build by spectrace.device), the scene schema, the API's
constructors and the package's public names all come from it. Adding a BSDF: its module here, its line in
MATERIALS, its kernel file, tests (docs/materials.md, "Adding a BSDF").
"""

import dataclasses
from typing import Any

import numpy as np

from spectrace.core.api_calls import recorded
from spectrace.core.contract import MATERIAL_DTYPE, MATERIAL_NO_SPECTRUM, NO_TEXTURE, GeneratedSources
from spectrace.core.registry import Registry
from spectrace.errors import SpectraceError
from spectrace.materials import (
    coatedconductor,
    coateddiffuse,
    conductor,
    dielectric,
    diffuse,
    diffusetransmission,
    fluorescent,
    hair,
    measured,
    mirror,
    mix,
    plastic,
    polarizer,
    pplastic,
    principled,
    principledthin,
    retarder,
    retroreflector,
    surface,
    thindielectric,
)
from spectrace.materials.base import MaterialPlugin
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable

# Scene-file `type` -> module. A module's position is its Material.type code (MATERIAL_<NAME> in the kernels), and
# the order in which the schema lists the types and the kernels' dispatch tests them.
# The composites come last: made of other materials (COMPOSITE), they have no BSDF and are no entries of the
# kernels' MATERIAL_LIST; kernels/material_mix.cl resolves a mix into one of its materials at each vertex,
# kernels/fluorescence.cl a fluorescent material into its base or its re-emission.
MATERIALS = Registry[MaterialPlugin](
    "material",
    (
        diffuse,
        conductor,
        mirror,
        plastic,
        dielectric,
        retroreflector,
        thindielectric,
        diffusetransmission,
        principled,
        principledthin,
        polarizer,
        retarder,
        pplastic,
        hair,
        measured,
        coatedconductor,
        coateddiffuse,
        mix,
        fluorescent,
    ),
)
# The BSDFs: the materials with a bsdf_<name>.cl and an entry in MATERIAL_LIST.
BSDFS = {name: m for name, m in MATERIALS.items() if not getattr(m, "COMPOSITE", False)}
MATERIAL_CODES = MATERIALS.codes
material_module = MATERIALS.for_model
# Every material takes the surface-detail keys (surface.py) besides its own: its API constructor too. Each object
# it makes remembers its arguments, by which a live session edits a scene built in Python (core/api_calls.py).
for _module in MATERIALS.values():
    _module.make = recorded(surface.accepting_detail(_module.make))  # type: ignore[method-assign]


def _parameter_textures(material) -> dict:
    from spectrace.textures import is_texture

    module = material_module(material)
    return {
        p.name: getattr(material, p.name)
        for p in module.PARAMETERS
        if (p.textured or p.type == "texture") and is_texture(getattr(material, p.name))
    }


def material_textures(material) -> dict:
    """The textured parameters of `material` that hold a texture, and its surface detail's textures, by name (a
    mix's materials' too, under `materials[i].<name>`)."""
    detail = material.detail
    found = _parameter_textures(material) | (detail.textures() if detail is not None else {})
    if isinstance(material, mix.MixMaterial):
        for i, part in enumerate(material.materials):
            found |= {f"materials[{i}].{name}": texture for name, texture in material_textures(part).items()}
    if isinstance(material, fluorescent.FluorescentMaterial):
        found |= {f"base.{name}": texture for name, texture in material_textures(material.base).items()}
    return found


def uv_material_textures(material) -> dict:
    """material_textures looked up at texture coordinates: what a shape wearing `material` needs them for (a mesh
    attribute is read from the mesh itself)."""
    from spectrace.textures import uv_textures

    return uv_textures(material_textures(material))


def append_material_rows(material, rows: list[np.ndarray], table: SpectrumTable, textures, index: dict) -> int:
    """The row index of `material` in `rows`, appending its row (material_row) on first use, keyed by id() in
    `index`; a mix's materials are appended after it, recursively, and their indices written into its row."""
    key = id(material)
    if key in index:
        return index[key]
    at = index[key] = len(rows)
    if isinstance(material, mix.MixMaterial) and (problem := mix.surface_detail_problem(material)) is not None:
        raise SpectraceError(problem)
    if (
        isinstance(material, fluorescent.FluorescentMaterial)
        and (problem := fluorescent.surface_detail_problem(material)) is not None
    ):
        raise SpectraceError(problem)
    rows.append(material_row(material, table, textures))
    if isinstance(material, mix.MixMaterial):
        for field, part in zip(mix.ROW_FIELDS, material.materials):
            rows[at][field] = append_material_rows(part, rows, table, textures, index)
    if isinstance(material, fluorescent.FluorescentMaterial):
        parts = (material.base, fluorescent.reemission_lobe())
        for field, part in zip(fluorescent.ROW_FIELDS, parts):
            rows[at][field] = append_material_rows(part, rows, table, textures, index)
    return at


def material_row(material, table: SpectrumTable, textures=None) -> np.ndarray:
    """The Material row of `material`, adding its spectra to `table` and its textures to `textures` (a
    spectrace.textures.TextureRows). A textured parameter's row field (Parameter.row_texture_field) holds the
    texture's index; the module's write_row sees, in its place, a zero spectrum for a spectrum and the texture's
    largest value for a number, so it needs to know nothing of textures. A textured roughness thus leaves its
    largest α in the row's `alpha`, from which the BSDF's flags come: a surface is treated as smooth (delta) only
    where every α it has is below the smooth limit, and otherwise the BSDF reads α per hit."""
    from spectrace.textures import scalar_range

    module = material_module(material)
    row = np.zeros((), MATERIAL_DTYPE)
    row["type"] = MATERIAL_CODES[module.NAME]
    for offset in ("reflectance_offset", "eta_offset", "k_offset", "transmittance_offset", "coat_table_offset"):
        row[offset] = MATERIAL_NO_SPECTRUM
    row["ior"] = 1.0
    row["reflectance_texture"] = row["roughness_texture"] = NO_TEXTURE
    if getattr(module, "WRITES_OWN_TEXTURES", False):
        # Parameters that have no row fields of their own: the module is handed the textures and places them.
        own: Any = module  # its write_row takes the textures too, beyond what MaterialPlugin states
        own.write_row(row, material, table, textures)
        write_detail(row, material.detail, textures)
        return row
    textured = _parameter_textures(material)
    parameters = {p.name: p for p in module.PARAMETERS}
    if textured:
        stand_ins = {
            name: scalar_range(texture)[1] if parameters[name].type == "float" else Spectrum.zeros()
            for name, texture in textured.items()
        }
        material = dataclasses.replace(material, **stand_ins)
    module.write_row(row, material, table)
    for name, texture in textured.items():
        parameter = parameters[name]
        row[parameter.row_texture_field] = textures.add(texture, "float" if parameter.type == "float" else "spectrum")
    write_detail(row, material.detail, textures)
    return row


def write_detail(row: np.ndarray, detail, textures) -> None:
    """The surface-detail fields at the end of a Material row (kernels/types.h); their defaults change nothing."""
    row["normal_map"] = row["bump_map"] = row["opacity_texture"] = NO_TEXTURE
    row["bump_scale"], row["opacity"], row["one_sided"], row["shadowing"] = 0.0, 1.0, 0, 0
    if detail is None:
        return
    row["one_sided"] = int(not detail.two_sided)
    row["shadowing"] = int(detail.shadowing_function and (detail.normal_map is not None or detail.bump_map is not None))
    if detail.normal_map is not None:
        row["normal_map"] = textures.add(detail.normal_map, "vector")
        row["normal_map_handedness"] = int(detail.normal_map_handedness)
    if detail.bump_map is not None:
        row["bump_map"] = textures.add(detail.bump_map, "float")
        row["bump_scale"] = detail.bump_scale
    if isinstance(detail.opacity, float):
        row["opacity"] = detail.opacity
    else:
        row["opacity_texture"] = textures.add(detail.opacity, "float")


def kernel_file(name: str) -> str:
    """The kernel file of material `name`, in the kernels folder: bsdf_<name>.cl for a BSDF, the composite's own
    KERNEL_FILE otherwise."""
    return getattr(MATERIALS[name], "KERNEL_FILE", f"bsdf_{name}.cl")


def kernel_defines() -> dict[str, int]:
    """MATERIAL_<NAME>: each BSDF's Material.type code, and MATERIAL_TYPE_COUNT, for every kernel build."""
    return MATERIALS.kernel_defines("MATERIAL")


# The header kernels/material.cl includes as "material_list.h"; spectrace.device writes it for each build that is
# handed it (`generated_sources`).
KERNEL_HEADER_NAME = "material_list.h"


def kernel_header() -> str:
    """material_list.h: every BSDF's kernel file included, and MATERIAL_LIST, the X-macro list kernels/material.cl
    expands into its dispatch: X(code, name, Params) per BSDF, in code order, with Params = <Name>Params, the
    struct <name>_params returns."""
    includes = "".join(f'#include "{kernel_file(name)}"\n' for name in BSDFS)
    entries = " \\\n".join(f"    X(MATERIAL_{name.upper()}, {name}, {name.capitalize()}Params)" for name in BSDFS)
    return (
        "/* Generated from spectrace.materials.MATERIALS: do not edit. */\n"
        "#ifndef SPECTRACE_MATERIAL_LIST_H\n#define SPECTRACE_MATERIAL_LIST_H\n\n"
        f"{includes}\n#define MATERIAL_LIST(X) \\\n{entries}\n\n#endif\n"
    )


def generated_sources() -> GeneratedSources:
    """The material codes and material_list.h, which a build of kernels that dispatch over materials is handed."""
    return GeneratedSources(kernel_defines(), {KERNEL_HEADER_NAME: kernel_header()})
