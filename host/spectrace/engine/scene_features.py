"""Build defines that tell the kernels which features a scene uses (kernels/scene_features.h), so each scene's
kernels carry code only for its own materials, lights and media. Derived from the uploaded buffers, which are
exactly what the kernels will read; any row (dummy rows included) keeps its type's code in."""

from typing import Any

import numpy as np

from spectrace.core.contract import (
    CURVE_TYPE_TUBE,
    FILTER_TRILINEAR,
    MICROFACET_BECKMANN,
    NO_TEXTURE,
    SHAPE_CURVE,
    SHAPE_SDFGRID,
)
from spectrace.engine.scene_buffers import SceneBuffers
from spectrace.errors import SpectraceError
from spectrace.materials import MATERIAL_CODES, MATERIALS
from spectrace.textures import SOLID_TEXTURE_CODES, TEXTURES


def _type_bits(types: np.ndarray) -> int:
    # A set, not np.unique: that imports numpy.ma on first use, a tenth of a second of a small render's start.
    return sum(1 << code for code in {int(t) for t in types.ravel()})


def _materials_have_textures(materials: np.ndarray, spectra: np.ndarray) -> bool:
    """Some material reads a texture (any of its `*_texture` fields, a normal or bump map, or a texture it keeps in
    a parameter block of its own): only then do the path vertices need texture coordinates and footprints (the
    lights' images are looked up at the light's own uv)."""
    fields = [name for name in materials.dtype.names or () if name.endswith("_texture")] + ["normal_map", "bump_map"]
    # Hair reads its offset across the fibre from the v coordinate (kernels/bsdf_hair.cl).
    if "hair" in MATERIAL_CODES and bool(np.any(materials["type"] == MATERIAL_CODES["hair"])):
        return True
    if any(bool(np.any(materials[name] != NO_TEXTURE)) for name in fields) or _direction_textures(materials):
        return True
    return _block_textures(materials, spectra)


def _block_textures(materials: np.ndarray, spectra: np.ndarray) -> bool:
    """A material that places its own textures (WRITES_OWN_TEXTURES: the principled weights' go into a parameter
    block of the spectrum table) reads one."""
    for name, module in MATERIALS.items():
        if not getattr(module, "WRITES_OWN_TEXTURES", False):
            continue
        own: Any = module  # block_textures comes with WRITES_OWN_TEXTURES, beyond what MaterialPlugin states
        for row in materials[materials["type"] == MATERIAL_CODES[name]]:
            if np.any(own.block_textures(row, spectra) != NO_TEXTURE):
                return True
    return False


def _direction_textures(materials: np.ndarray) -> bool:
    """A principled material whose anisotropy turns by a direction texture (its row's k_offset)."""
    principled = (materials["type"] == MATERIAL_CODES["principled"]) & (materials["tangent_frame"] != 0)
    return bool(np.any(principled & (materials["k_offset"] != NO_TEXTURE)))


def _smooth_environment_maps(lights: np.ndarray) -> bool:
    """An environment map whose texels are smooth spectra (spectrace.lights.envmap's texel_spectra)."""
    from spectrace.lights import DEVICE_LIGHTS
    from spectrace.lights.envmap import ENVIRONMENT_MAP, SMOOTH_TEXELS

    maps = lights["type"] == DEVICE_LIGHTS.codes[ENVIRONMENT_MAP.name]
    return bool(np.any(maps & (lights["basis_green_offset"] == SMOOTH_TEXELS)))


def camera_feature_defines(params: np.ndarray) -> dict[str, int]:
    """The camera type and pixel filter of a scene's RenderParams (kernels/scene_features.h)."""
    return {
        "SCENE_CAMERA_TYPES": 1 << int(params["camera_type"][0]),
        "SCENE_PIXEL_FILTERS": 1 << int(params["pixel_filter"][0]),
        "SCENE_HAS_FAR_CLIP": int(params["camera_forward"][0, 3] > 0.0),
    }


def scene_feature_defines(buffers: SceneBuffers, hides_area_emitters: bool = False) -> dict[str, int]:
    """`hides_area_emitters`: the scene has area lights and hide_emitters (camera rays pass through them)."""
    materials = buffers.materials
    textures = buffers.textures[: buffers.texture_count]
    bump_maps = bool(np.any(materials["bump_map"] >= 0))
    # Only a trilinear lookup with a pyramid to choose from (texture.cl) and a checkerboard bump map's finite
    # differences (surface_detail.cl; a bitmap's gradient is exact) read the footprint.
    trilinear = bool(np.any((textures["filter"] == FILTER_TRILINEAR) & (textures["levels"] > 1)))
    bump_textures = materials["bump_map"][materials["bump_map"] >= 0]
    checkerboard_bumps = bool(np.any(textures["type"][bump_textures] == TEXTURES.codes["checkerboard"]))
    shape_rows = buffers.shapes[: buffers.shape_count + buffers.instanced_shape_count]  # SDF grids' samples follow
    return {
        "SCENE_MATERIAL_TYPES": _type_bits(buffers.materials["type"]),
        "SCENE_LIGHT_TYPES": _type_bits(buffers.lights["type"]),
        "SCENE_HAS_MEDIA": int(buffers.medium_count > 0 or buffers.null_surfaces),
        "SCENE_HAS_GRID_MEDIA": int(bool(np.any(buffers.media["grid"][: buffers.medium_count] >= 0))),
        "SCENE_HAS_MEDIUM_EMISSION": int(bool(np.any(buffers.media["emission"][: buffers.medium_count] >= 0))),
        "SCENE_HAS_LIGHT_IMAGES": int(
            bool(np.any(buffers.lights["texture"] != NO_TEXTURE) or np.any(buffers.lights["map_width"] > 0))
        ),
        "SCENE_HAS_SMOOTH_ENVIRONMENT_MAP": int(_smooth_environment_maps(buffers.lights)),
        "SCENE_HAS_BECKMANN": int(bool(np.any(materials["distribution"] == MICROFACET_BECKMANN))),
        "SCENE_HAS_NONLINEAR_PLASTIC": int(bool(np.any(materials["nonlinear"] != 0))),
        "SCENE_HAS_ROUGH_COAT": int(bool(np.any(materials["coat_table_offset"] >= 0))),
        "SCENE_HAS_MIX": int(bool(np.any(materials["type"] == MATERIAL_CODES["mix"]))),
        # A fluorescent row's ior_model holds its non-separable matrix's block (kernels/fluorescence_matrix.cl).
        "SCENE_HAS_FLUORESCENCE_MATRIX": int(
            bool(np.any((materials["type"] == MATERIAL_CODES["fluorescent"]) & (materials["ior_model"] >= 0)))
        ),
        "SCENE_HAS_TEXTURES": int(_materials_have_textures(buffers.materials, buffers.spectra)),
        "SCENE_NEEDS_FOOTPRINT": int(trilinear or checkerboard_bumps),
        "SCENE_HAS_PROCEDURAL_TEXTURES": int(bool(np.any(textures["type"] == TEXTURES.codes["dots"]))),
        "SCENE_HAS_SOLID_TEXTURES": int(bool(np.isin(textures["type"], SOLID_TEXTURE_CODES).any())),
        "SCENE_HAS_TEXTURE_MAPPINGS": int(bool(np.any(textures["mapping"] != 0))),
        "SCENE_HAS_MESH_ATTRIBUTES": int(bool(np.any(textures["type"] == TEXTURES.codes["mesh_attribute"]))),
        "SCENE_HAS_DIRECTION_MIX": int(bool(np.any(textures["type"] == TEXTURES.codes["directionmix"]))),
        "SCENE_HAS_SURFACE_NORMALS": int(bool(np.any(materials["normal_map"] >= 0)) or bump_maps),
        "SCENE_HAS_SHAPES": int(buffers.shape_count + buffers.instanced_shape_count > 0),
        "SCENE_HAS_PARTIAL_SHAPES": int(bool(np.any(shape_rows["phi_max"] > 0.0))),
        "SCENE_HAS_SDF_GRIDS": int(bool(np.any(shape_rows["type"] == SHAPE_SDFGRID))),
        "SCENE_HAS_CURVES": int(bool(np.any(shape_rows["type"] == SHAPE_CURVE))),
        "SCENE_HAS_CURVE_RIBBONS": int(
            bool(np.any((shape_rows["type"] == SHAPE_CURVE) & (shape_rows["cut_min"] != CURVE_TYPE_TUBE)))
        ),
        "SCENE_HAS_MITSUBA_CURVE_UV": int(
            bool(np.any((shape_rows["type"] == SHAPE_CURVE) & (shape_rows["pbrt_uv"] == 0)))
        ),
        "SCENE_HIDES_AREA_EMITTERS": int(hides_area_emitters),
        "SCENE_HAS_INSTANCES": int(buffers.instance_count > 0),
        "SCENE_HAS_OPACITY": int(bool(np.any((materials["opacity_texture"] >= 0) | (materials["opacity"] < 1.0)))),
        "SCENE_HAS_ONE_SIDED": int(bool(np.any(materials["one_sided"] != 0))),
        "SCENE_HAS_TANGENT_FRAMES": int(bool(np.any(materials["tangent_frame"] != 0))),
        "SCENE_HAS_DIRECTION_TEXTURES": int(_direction_textures(materials)),
        # A smooth triangle with file tangents marks its first corner normal's w (engine/vertex_tangents.py).
        "SCENE_HAS_FILE_TANGENTS": int(bool(np.any(buffers.triangle_normals[::3, 3] != 0))),
        "SCENE_HAS_NORMAL_MAP_HANDEDNESS": int(
            bool(np.any((materials["normal_map_handedness"] != 0) & (materials["normal_map"] >= 0)))
        ),
    }


# Materials that exist to polarise: a scene with one renders polarised without being asked.
POLARIZING_MATERIALS = ("polarizer", "retarder")


def is_polarized(scene, buffers: SceneBuffers) -> bool:
    """Whether `scene` renders with polarised transport (kernels/polarized_path.cl): asked for by
    integrator.polarized, or implied by a polarising material, a polarisation AOV or a camera polariser."""
    from spectrace.film.aovs import POLARIZATION_AOVS

    codes = [MATERIAL_CODES[name] for name in POLARIZING_MATERIALS]
    return bool(
        scene.polarized
        or scene.camera.polarizer_angle is not None
        or any(aov in POLARIZATION_AOVS for aov in scene.aovs)
        or np.isin(buffers.materials["type"], codes).any()
        or _polarized_emitters(buffers)
    )


def _polarized_emitters(buffers: SceneBuffers) -> bool:
    """Whether an area light emits polarised light (its row's direction.w, spectrace.lights.area)."""
    from spectrace.lights import DEVICE_LIGHTS
    from spectrace.lights.area import DEVICE_TYPES

    lights = buffers.lights
    area = np.isin(lights["type"], [DEVICE_LIGHTS.codes[t.name] for t in DEVICE_TYPES])
    return bool((area & (lights["direction"][:, 3] > 0.0)).any())


def polarization_defines(scene, buffers: SceneBuffers) -> dict[str, int]:
    """SCENE_POLARIZED for a polarised scene, in the general kernels' builds too (they leave it out); a scene the
    polarised kernels cannot render raises SpectraceError naming the key."""
    if not is_polarized(scene, buffers):
        return {}
    where = str(scene.source) if scene.source else None
    if scene.integrator != "path":
        raise SpectraceError(
            f"integrator.type = {scene.integrator!r}: polarised transport (integrator.polarized, a polarizer or "
            "retarder, a Stokes AOV or camera.polarizer_angle) is rendered by the path integrator only",
            where=where,
        )
    materials = buffers.materials
    if "fluorescent" in MATERIAL_CODES and (materials["type"] == MATERIAL_CODES["fluorescent"]).any():
        raise SpectraceError(
            "integrator.polarized: a fluorescent material in a polarised scene is not rendered (a re-emission's "
            "polarisation is not modelled)",
            where=where,
        )
    return {"SCENE_POLARIZED": 1}
