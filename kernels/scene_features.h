/* What a scene uses, fixed when its kernels are built (spectrace.engine.scene_features writes the defines), so a
 * kernel carries no code for materials, lights or media the scene lacks. On CPU runtimes that matters beyond the
 * branches themselves: a smaller kernel keeps more of a path's state in registers, and a vectoriser that runs
 * work-items in SIMD lanes executes every branch some lane takes. A kernel built without these defines handles
 * every scene. */
#ifndef SPECTRACE_SCENE_FEATURES_H
#define SPECTRACE_SCENE_FEATURES_H

/* Bit t set: some material of type MATERIAL_t / some light of type LIGHT_t is in the scene (the codes:
 * spectrace.core.contract). */
#ifndef SCENE_MATERIAL_TYPES
#define SCENE_MATERIAL_TYPES ((1 << MATERIAL_TYPE_COUNT) - 1)
#endif
#ifndef SCENE_LIGHT_TYPES
#define SCENE_LIGHT_TYPES ((1 << LIGHT_TYPE_COUNT) - 1)
#endif
/* Participating media (and with them index-matched boundaries), or surfaces without material (lights seen through):
 * what visibility queries must cross. */
#ifndef SCENE_HAS_MEDIA
#define SCENE_HAS_MEDIA 1
#endif
/* Media whose density varies, read from a voxel grid (medium_grid.cl). */
#ifndef SCENE_HAS_GRID_MEDIA
#define SCENE_HAS_GRID_MEDIA SCENE_HAS_MEDIA
#endif
/* Media that glow (medium_emission.cl). */
#ifndef SCENE_HAS_MEDIUM_EMISSION
#define SCENE_HAS_MEDIUM_EMISSION SCENE_HAS_MEDIA
#endif
/* Partial analytic shapes (kernels/shape_partial.cl: pbrt's phimax, zmin/zmax, innerradius cuts). */
#ifndef SCENE_HAS_PARTIAL_SHAPES
#define SCENE_HAS_PARTIAL_SHAPES 1
#endif
/* Curve segments among the analytic shapes (kernels/shape_curve.cl: hair, fur, wires). */
#ifndef SCENE_HAS_CURVES
#define SCENE_HAS_CURVES 1
#endif
/* Flat and ribbon curves among them (pbrt-v4's curve types: kernels/curve_ribbon.cl). */
#ifndef SCENE_HAS_CURVE_RIBBONS
#define SCENE_HAS_CURVE_RIBBONS SCENE_HAS_CURVES
#endif
/* Curves with Mitsuba 3's texture coordinates (shape_curve.cl), on which the hair BSDF takes h from wo. */
#ifndef SCENE_HAS_MITSUBA_CURVE_UV
#define SCENE_HAS_MITSUBA_CURVE_UV 1
#endif
/* Lights showing an image (environment maps; area lights' emission textures, pictures on screens among them). */
#ifndef SCENE_HAS_LIGHT_IMAGES
#define SCENE_HAS_LIGHT_IMAGES 1
#endif
/* Environment maps whose texels are smooth spectra (`texel_spectra = "smooth"`, light_environment_map.cl). */
#ifndef SCENE_HAS_SMOOTH_ENVIRONMENT_MAP
#define SCENE_HAS_SMOOTH_ENVIRONMENT_MAP SCENE_HAS_LIGHT_IMAGES
#endif

/* Rough lobes with the Beckmann microfacet distribution (kernels/microfacet.cl); without them every rough lobe is
 * GGX and the distribution is not read. */
#ifndef SCENE_HAS_BECKMANN
#define SCENE_HAS_BECKMANN 1
#endif
/* Plastics whose base's internal scattering depends on its albedo (`nonlinear`, kernels/bsdf_plastic.cl). */
#ifndef SCENE_HAS_NONLINEAR_PLASTIC
#define SCENE_HAS_NONLINEAR_PLASTIC 1
#endif

/* Plastics whose rough coat passes light by its own tabulated transmittance (`coat_transmission = "rough"`). */
#ifndef SCENE_HAS_ROUGH_COAT
#define SCENE_HAS_ROUGH_COAT 1
#endif

/* Mix materials (kernels/material_mix.cl): each vertex resolves its material into one of a mix's. */
#ifndef SCENE_HAS_MIX
#define SCENE_HAS_MIX 1
#endif

/* Material textures (kernels/texture.cl). */
#ifndef SCENE_HAS_TEXTURES
#define SCENE_HAS_TEXTURES 1
#endif

/* Procedural textures built on noise (dots: kernels/noise.cl). */
#ifndef SCENE_HAS_PROCEDURAL_TEXTURES
#define SCENE_HAS_PROCEDURAL_TEXTURES 1
#endif

/* 2D textures looked up at coordinates a mapping makes from the surface point (kernels/texture_mapping.cl). */
#ifndef SCENE_HAS_TEXTURE_MAPPINGS
#define SCENE_HAS_TEXTURE_MAPPINGS 1
#endif
/* Solid textures, looked up at the surface point (fbm, wrinkled, windy, marble: kernels/texture_solid.cl). */
#ifndef SCENE_HAS_SOLID_TEXTURES
#define SCENE_HAS_SOLID_TEXTURES 1
#endif

/* Mesh attribute textures, read at the hit's triangle (kernels/texture_mesh_attribute.cl). */
#ifndef SCENE_HAS_MESH_ATTRIBUTES
#define SCENE_HAS_MESH_ATTRIBUTES SCENE_HAS_TEXTURES
#endif

/* Textures that read the shading normal (directionmix: kernels/texture_direction_mix.cl). */
#ifndef SCENE_HAS_DIRECTION_MIX
#define SCENE_HAS_DIRECTION_MIX SCENE_HAS_TEXTURES
#endif

/* Lookups that read the texture footprint (trilinear filtering, a checkerboard bump map's differences): only then
 * does a hit pay for camera_footprint (kernels/scene.cl); elsewhere the footprint stays 0, which no other lookup
 * reads. */
#ifndef SCENE_NEEDS_FOOTPRINT
#define SCENE_NEEDS_FOOTPRINT SCENE_HAS_TEXTURES
#endif

/* Normal or bump maps (kernels/surface_detail.cl). */
#ifndef SCENE_HAS_SURFACE_NORMALS
#define SCENE_HAS_SURFACE_NORMALS 1
#endif
/* Materials with an opacity below 1 (cut-outs): visibility queries may pass through surfaces (kernels/scene.cl). */
#ifndef SCENE_HAS_OPACITY
#define SCENE_HAS_OPACITY 1
#endif

/* Normal maps whose bitangent follows the texture layout's handedness (Material.normal_map_handedness, glTF's
 * frame: kernels/surface_detail.cl). */
#ifndef SCENE_HAS_NORMAL_MAP_HANDEDNESS
#define SCENE_HAS_NORMAL_MAP_HANDEDNESS 1
#endif

/* Triangles whose tangent frame a mesh file supplies (glTF's TANGENT, kernels/vertex_tangents.cl). */
#ifndef SCENE_HAS_FILE_TANGENTS
#define SCENE_HAS_FILE_TANGENTS 1
#endif

/* Materials that reflect on one face only (Material.one_sided, kernels/material.cl). */
#ifndef SCENE_HAS_ONE_SIDED
#define SCENE_HAS_ONE_SIDED 1
#endif

/* Materials whose frame follows dp/du (Material.tangent_frame, kernels/material.cl): vertices carry dp/du. */
#ifndef SCENE_HAS_TANGENT_FRAMES
#define SCENE_HAS_TANGENT_FRAMES 1
#endif
/* Principled materials whose anisotropy turns by a direction texture (kernels/anisotropy_direction.cl). */
#ifndef SCENE_HAS_DIRECTION_TEXTURES
#define SCENE_HAS_DIRECTION_TEXTURES 1
#endif

/* hide_emitters with area lights: the camera's own rays pass through them (kernels/path_tracer.cl). */
#ifndef SCENE_HIDES_AREA_EMITTERS
#define SCENE_HIDES_AREA_EMITTERS 1
#endif

/* Analytic spheres, disks and cylinders (kernels/shapes.cl), tested beside the triangles' BVH. */
#ifndef SCENE_HAS_SHAPES
#define SCENE_HAS_SHAPES 1
#endif
/* Signed-distance grids among the analytic shapes (kernels/shape_sdf_grid.cl). */
#ifndef SCENE_HAS_SDF_GRIDS
#define SCENE_HAS_SDF_GRIDS SCENE_HAS_SHAPES
#endif

/* Bit t set: the camera is of type CAMERA_t / the pixel filter is PIXEL_FILTER_t (one bit each in a scene's build;
 * every bit without the defines). */
#ifndef SCENE_CAMERA_TYPES
#define SCENE_CAMERA_TYPES ((1 << CAMERA_TYPE_COUNT) - 1)
#endif
/* A camera with a far clip plane (RenderParams.camera_forward.w > 0, kernels/camera.cl). */
#ifndef SCENE_HAS_FAR_CLIP
#define SCENE_HAS_FAR_CLIP 1
#endif
#ifndef SCENE_PIXEL_FILTERS
#define SCENE_PIXEL_FILTERS ((1 << PIXEL_FILTER_TYPE_COUNT) - 1)
#endif

/* Instanced objects (kernels/scene.cl, "Instances"): a top-level BVH over the instances beside the triangles'. */
#ifndef SCENE_HAS_INSTANCES
#define SCENE_HAS_INSTANCES 1
#endif

/* Polarised transport (kernels/polarized_path.cl): camera paths carry a Mueller matrix. Not a specialisation of
 * the general kernels, which leave it out: a polarised scene's build always defines it, whichever kernels it takes. */
#ifndef SCENE_POLARIZED
#define SCENE_POLARIZED 0
#endif

#define SCENE_USES_MATERIAL(type) ((SCENE_MATERIAL_TYPES >> (type)) & 1)
/* Fluorescent materials: a path's wavelength may change at a vertex (kernels/fluorescence.cl). */
#define SCENE_HAS_FLUORESCENCE SCENE_USES_MATERIAL(MATERIAL_FLUORESCENT)
/* A fluorescent material given by a non-separable re-radiation matrix (kernels/fluorescence_matrix.cl). */
#ifndef SCENE_HAS_FLUORESCENCE_MATRIX
#define SCENE_HAS_FLUORESCENCE_MATRIX SCENE_HAS_FLUORESCENCE
#endif
#define SCENE_USES_LIGHT(type) ((SCENE_LIGHT_TYPES >> (type)) & 1)
/* LIGHT_ENVIRONMENT_TYPES: the bits of the device light types of environments (spectrace.lights). */
#define SCENE_HAS_ENVIRONMENT ((SCENE_LIGHT_TYPES & LIGHT_ENVIRONMENT_TYPES) != 0)

/* Type tests that fold to constants when the scene has none of that type, or nothing else. */
#define MATERIAL_IS(m, t) (SCENE_USES_MATERIAL(t) && (SCENE_MATERIAL_TYPES == (1 << (t)) || (m)->type == (t)))
#define CAMERA_IS(params, t) \
    (((SCENE_CAMERA_TYPES >> (t)) & 1) && (SCENE_CAMERA_TYPES == (1 << (t)) || (params)->camera_type == (t)))
#define PIXEL_FILTER_IS(params, t) \
    (((SCENE_PIXEL_FILTERS >> (t)) & 1) && (SCENE_PIXEL_FILTERS == (1 << (t)) || (params)->pixel_filter == (t)))
#define LIGHT_IS(light, t) (SCENE_USES_LIGHT(t) && (SCENE_LIGHT_TYPES == (1 << (t)) || (light)->type == (t)))

#endif
