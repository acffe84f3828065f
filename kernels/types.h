/* Structs shared by the host and the device.
 *
 * Each struct is mirrored by a numpy structured dtype in host/spectrace/core/contract.py with explicit
 * offsets; tests/device/test_struct_layout.py compiles a kernel that reports sizeof/offsetof and compares.
 * Only float4 and 4-byte scalars are used, float4 first, so every compiler lays them out identically
 * (float3 is avoided: it occupies 16 bytes in buffers). */
#ifndef SPECTRACE_TYPES_H
#define SPECTRACE_TYPES_H

#include "scene_features.h"

/* The numbers both sides must agree on (the wavelength grid GRID_MIN_NM, GRID_MAX_NM, GRID_SAMPLES; the MATERIAL_*,
 * IOR_*, LIGHT_* and METER_* codes; MATERIAL_NO_SPECTRUM, TRIANGLE_NO_MATERIAL; buffer layouts) have one home,
 * host/spectrace/core/contract.py, and reach every kernel build as defines. */
#ifndef GRID_SAMPLES
#error "built without the host/device contract defines (spectrace.core.contract.device_contract_defines)"
#endif

/* Bounding volume hierarchy node (32 bytes). Interior: count == 0, children at left_first and left_first + 1.
 * Leaf: count > 0 triangles starting at slot left_first of the triangle arrays. */
typedef struct {
    float bmin[3];
    int left_first;
    float bmax[3];
    int count;
} BVHNode;

/* 4-wide BVH node (128 bytes), collapsed from the binary tree on the host (geometry/bvh4.py). The four children's
 * boxes in SoA form: child_min[axis] holds that axis' lower bound of children 0..3. Child k is a 4-wide node index
 * when count[k] == 0, a leaf of count[k] triangles starting at slot child[k] when count[k] > 0, unused when -1. */
typedef struct {
    float4 child_min[3];
    float4 child_max[3];
    int4 child;
    int4 count;
} BVH4Node;

/* 8-wide BVH node (256 bytes), the same layout with eight children per node (geometry/bvh4.py, width 8). */
typedef struct {
    float8 child_min[3];
    float8 child_max[3];
    int8 child;
    int8 count;
} BVH8Node;

/* Quantised 8-wide BVH node (128 bytes; geometry/bvh4.py BVH8Q_NODE_DTYPE, after Ylitie et al. 2017): child k's
 * box has, along each axis, the planes origin[axis] + q[plane][k] * scale[axis] (world units; scale a power of two),
 * rounded outwards on the host so they contain the child's float box. */
typedef struct {
    int8 child;       /* a node index, or the float4 offset of a leaf's first block */
    uchar8 q[6];      /* lower planes x, y, z, then upper planes x, y, z, in steps of scale */
    char8 kind;       /* -1 unused slot, 0 a node, 1 a leaf */
    float origin[3];  /* the node's lower corner (world units) */
    float scale[3];   /* one step of q along each axis (world units) */
    int pad[4];
} BVH8QNode;

/* Per-triangle shading data, in BVH leaf order. */
typedef struct {
    int material;   /* index into the material array; TRIANGLE_NO_MATERIAL on an index-matched medium boundary, which
                       rays cross unchanged (docs/media.md) */
    int light;      /* index into the light array, or -1 when the triangle does not emit */
    int interior;   /* index into the medium array: the medium filling the closed shape this triangle bounds, on
                       the side opposite its geometric normal (the winding's back side, which the host makes the
                       side opposite its vertex normals where it has them); -1 when none */
    int normals;    /* its corners' shading normals are entries 3·normals .. 3·normals + 2 of triangle_normals; -1
                       when it shades with its geometric normal (flat) */
} TriangleInfo;

/* An analytic shape (kernels/shapes.cl): a sphere, disk or cylinder in its object space (Mitsuba 3's: the unit sphere
 * at the origin; the unit disk in the plane z = 0 facing +z; the cylinder of radius 1 along z from 0 to 1, open),
 * placed by an affine map. Its hits are slots triangle_count + index of the TriangleInfo array. */
typedef struct {
    float4 to_world[3];   /* rows of the object-to-world map: world coordinate i = dot(to_world[i], (p, 1)) */
    float4 to_object[3];  /* rows of its inverse */
    float4 sphere;        /* SHAPE_SPHERE: world centre (xyz) and radius (w), scene units (to_world is a similarity);
                             SHAPE_SDFGRID: x's int bits, the offset to its samples (shape_sdf_grid.cl) */
    int type;             /* SHAPE_* */
    float abs_det;        /* |det| of to_world's linear part: world area = object area · abs_det · |M⁻ᵀ n_object| */
    float object_area;    /* object-space area: 4π (sphere), π (disk), 2π (cylinder); a partial shape's own */
    int flip_normals;     /* 1: the front (normal, emitting side) faces the other way: inward, the disk's −z */
    int pbrt_uv;          /* 1: texture coordinates as pbrt-v4 gives them (shapes.cl, shape_uv_from_mitsuba) */
    float phi_max;        /* > 0: a partial shape (shape_partial.cl), kept for azimuths φ in [0, phi_max] (radians); 0:
                             the whole shape */
    float cut_min;        /* a partial sphere: kept for object z in [cut_min, cut_max]; a partial disk: for radii */
    float cut_max;        /*   r in [cut_min, 1] */
} AnalyticShape;

/* A placed copy of an instanced object (kernels/scene.cl, "Instances"): the object's triangles are stored once, at
 * slots after the scene's own triangles and all analytic shapes, under their own 4-wide BVH, and its analytic shapes
 * once, as AnalyticShape rows in object space after the scene's own; an instance adds only this row and a leaf of
 * the top-level BVH over the instances' world boxes. */
typedef struct {
    float4 to_world[3];   /* rows of the object-to-world affine map: world coordinate i = dot(to_world[i], (p, 1)) */
    float4 to_object[3];  /* rows of its inverse (rays enter object space through it; normals leave by its
                             transpose, M⁻ᵀ) */
    int nodes;            /* float4 offset of the object's BVH in instance_nodes; -1 when it has no triangles */
    int object;           /* which object (the host's numbering; the kernels do not read it) */
    int first_shape;      /* the object's analytic shapes: AnalyticShape rows [first_shape, first_shape +
                             shape_count), in the object's space (their hits: slot triangle_count + row) */
    int shape_count;
} Instance;

/* A homogeneous participating medium (kernels/medium.cl); the coefficients are tabulated spectra, already
 * multiplied by the scene's `scale`, in 1/scene unit. */
typedef struct {
    int sigma_a_offset;  /* absorption coefficient σa(λ) */
    int sigma_s_offset;  /* scattering coefficient σs(λ) */
    float g;             /* Henyey–Greenstein asymmetry parameter in (−1, 1); 0 = isotropic */
    int grid;            /* a grid medium's block in the spectra table (medium_grid.cl); -1: homogeneous */
    int emission;        /* a glowing medium's emission spectrum Le(λ) (medium_emission.cl); -1: none */
} Medium;

/* One material; which fields a BSDF reads is listed beside each (docs/scene-format.md gives the scene keys). */
typedef struct {
    float4 ior_coefficients_b;  /* IOR_SELLMEIER: B1, B2, B3 (x, y, z); IOR_CAUCHY: a, b (µm²) in x, y */
    float4 ior_coefficients_c;  /* IOR_SELLMEIER: C1, C2, C3 (µm²) in x, y, z */
    int type;                   /* MATERIAL_* */
    int reflectance_offset;     /* diffuse, plastic: base albedo; principled: base colour; mirror, retroreflector:
                                   reflectance; conductor, dielectric: optional specular tint; thindielectric:
                                   optional tint of its reflection (MATERIAL_NO_SPECTRUM: none) */
    int eta_offset;             /* conductor: real part η(λ) of the complex index of refraction; mix: its first
                                   material's row index (material_mix.cl) */
    int k_offset;               /* conductor: imaginary part k(λ) (absorption); mix: its second material's row;
                                   principled: the texture of its anisotropy's direction (or NO_TEXTURE) */
    float alpha;                /* GGX roughness α; 0 = smooth (a delta lobe). With roughness_texture: the texture's
                                   largest α, which decides the flags (smooth only if smooth everywhere); mix: the
                                   probability of its second material, `amount` */
    int ior_model;              /* IOR_*: dielectric interior, plastic coating; fluorescent: a non-separable
                                   matrix's block, or MATERIAL_NO_SPECTRUM (fluorescence_matrix.cl) */
    float ior;                  /* IOR_CONSTANT: interior index relative to the exterior */
    int reflectance_texture;    /* index into the texture array that replaces reflectance_offset (the reflectance, or
                                   the conductor's and dielectric's specular tint), or NO_TEXTURE */
    int roughness_texture;      /* conductor, plastic, dielectric, retroreflector: a scalar texture of α per point
                                   that replaces alpha there, or NO_TEXTURE; mix: a scalar texture of its amount;
                                   principled: a scalar texture of its specular level (bsdf_principled.cl) */
    int distribution;           /* conductor, plastic, dielectric: MICROFACET_* of the rough lobe */
    int nonlinear;              /* plastic: 1 = the base's internal scattering depends on its albedo (Mitsuba's
                                   `nonlinear`), 0 = it does not; principled: 1 = it transmits (spec_trans above 0
                                   somewhere), its flags' BSDF_TRANSMISSION */
    int transmittance_offset;   /* thindielectric: optional tint of its transmission; plastic: optional tint of its
                                   coat's reflection (MATERIAL_NO_SPECTRUM: none) */
    int coat_table_offset;      /* plastic with a rough coat's own transmission: GRID_SAMPLES values of t(cos θ) at
                                   cos θ = i / (GRID_SAMPLES − 1) in the spectrum table (MATERIAL_NO_SPECTRUM: the
                                   smooth interface's 1 − F instead); principled: its parameter block (each
                                   weight and its texture, bsdf_principled.cl) */
    float coat_internal_reflectance; /* with coat_table_offset: the coat's diffuse reflectance from inside, R_int */
    /* Surface detail, every type (kernels/surface_detail.cl, scene.cl; host: spectrace.materials.surface). */
    int normal_map;             /* a TEXEL_VECTOR texture of tangent-space normals, or NO_TEXTURE */
    int bump_map;               /* a scalar texture of heights, or NO_TEXTURE */
    float bump_scale;           /* scene units per bump map value */
    float opacity;              /* the probability that a ray meets the surface, where opacity_texture is NO_TEXTURE */
    int opacity_texture;        /* a scalar texture of it, or NO_TEXTURE */
    int one_sided;              /* 1: a reflecting BSDF is black seen from the back of its surface (wo on the far side
                                   of the winding's normal, which the host turns toward the vertex normals), as
                                   Mitsuba 3's outside `twosided`; 0: it reflects on both faces. BSDFs that transmit
                                   ignore it */
    int shadowing;              /* 1: with a normal or bump map, the BSDF's value is scaled by the shadowing term of
                                   Conty Estevez et al. 2019 (material.cl, material_shadowing), as Mitsuba 3's
                                   `use_shadowing_function`; 0: it is not */
    int tangent_frame;          /* 1: the BSDF's frame turns its x axis along the surface's dp/du (an anisotropic
                                   lobe's direction, material.cl's material_frame); 0: any frame about the normal */
    int normal_map_handedness;  /* 1: the normal map's bitangent is w (n × tangent), w the sign of the texture layout's
                                   handedness (glTF's frame, surface_detail.cl); 0: n × tangent (Mitsuba's) */
    float tangent_rotation;     /* with tangent_frame: radians the frame's x axis turns from dp/du, counter-clockwise
                                   about the normal (principled's anisotropic_rotation) */
} Material;

/* One texture (kernels/texture.cl; its host side: host/spectrace/textures). An image's texels are values of its
 * `storage` in the texel buffer from data_offset on, `channels` per texel, rows top to bottom; its MIP levels follow
 * level 0 there, level l being max(1, width >> l) by max(1, height >> l) texels. */
typedef struct {
    float4 uv_transform;  /* the lookup point st = uv · (x, y) + (z, w): uv_scale, then uv_offset (image widths) */
    int type;             /* TEXTURE_* */
    int texel_format;     /* TEXEL_*: SIGMOID (c0, c1, c2 with λ in nm; dimensionless when half), SCALAR (one value), BANDS (spectral),
                             VECTOR (three values as they are), RGB (linear r, g, b weighting the basis
                             spectra: an emission) */
    int channels;         /* values per texel: 3, 1, or the band count */
    int width;            /* level 0, texels */
    int height;
    int levels;           /* MIP levels (1: level 0 only) */
    int data_offset;      /* where level 0 starts in the texel buffer, in floats (4 bytes) */
    int wrap;             /* WRAP_* */
    int filter;           /* FILTER_* */
    float band_first_nm;  /* TEXEL_BANDS: centre wavelength of band 0, nm */
    float band_step_nm;   /* TEXEL_BANDS: spacing of the band centres, nm */
    int side_spectrum[2]; /* TEXTURE_CHECKERBOARD, SCALE, MIX: each side's (operand's) spectrum offset, used when
                             side_texture is NO_TEXTURE */
    int side_texture[2];  /* each side's image texture (never a composite), or NO_TEXTURE */
    int basis_offset[3];  /* TEXEL_RGB: the spectra R, G, B a texel's (r, g, b) weights: r·R(λ) + g·G(λ) + b·B(λ) */
    int storage;          /* STORAGE_*: how each value is stored (float, half, 8- or 16-bit unsigned normalised) */
    float factor;         /* TEXTURE_SCALE: the factor; TEXTURE_MIX: the amount (when factor_texture is NO_TEXTURE) */
    int factor_texture;   /* TEXTURE_SCALE, TEXTURE_MIX: a scalar image texture giving the factor, or NO_TEXTURE */
    int mapping;          /* TEXTURE_MAPPING_* (texture_mapping.cl): where the (u, v) are taken from; 0: the surface's */
    int mapping_offset;   /* a mapping's 12 floats in the texel buffer (texture_mapping.cl) */
    int pad[1];
} Texture;

/* One light; its emission is scale * table[spectrum_offset + ...](λ) in the unit of its type (`type`: a device
 * light type's code, LIGHT_<NAME>, generated from spectrace.lights.DEVICE_LIGHTS; its kernel file,
 * light_<name>.cl, states the unit and which fields it reads). */
typedef struct {
    float4 position;       /* point, spot; LIGHT_SPHERE: centre (xyz) and radius (w); LIGHT_ENVIRONMENT_MAP: row 0 of
                              the world-to-map rotation */
    float4 direction;      /* spot: unit axis; distant: unit direction the light travels; area lights: polarised
                              light's normalised S1..S3 and w = 1 (polarized_path.cl), else w = 0; LIGHT_ENVIRONMENT_MAP:
                              row 1 of the world-to-map rotation */
    int type;              /* LIGHT_* */
    int triangle;          /* LIGHT_TRIANGLE: slot in the triangle arrays; LIGHT_SPHERE, LIGHT_SHAPE: index of its
                              AnalyticShape; LIGHT_PROJECTOR, LIGHT_GONIOMETRIC: the texel where the image's
                              sampling table starts (distribution_2d.cl), -1: none */
    int spectrum_offset;
    float scale;
    float pmf;             /* probability that next-event estimation picks this light */
    float area;            /* LIGHT_TRIANGLE, LIGHT_SPHERE, LIGHT_SHAPE: m² */
    int two_sided;         /* LIGHT_TRIANGLE, LIGHT_SPHERE, LIGHT_SHAPE */
    float cos_falloff_start;  /* LIGHT_SPOT: full intensity inside this cone */
    float cos_cutoff;         /* LIGHT_SPOT: none outside this cone */
    int basis_green_offset;   /* LIGHT_ENVIRONMENT_MAP: texel radiance = r·R(λ) + g·G(λ) + b·B(λ), with R at */
    int basis_blue_offset;    /*   spectrum_offset: the uplifted emission spectra of the three primaries; both -1:
                                   smooth texels, D65 at spectrum_offset (light_environment_map.cl) */
    int map_width;            /* LIGHT_ENVIRONMENT_MAP (latitude-longitude): texels; LIGHT_PROJECTOR: its table's cells */
    int map_height;
    int texel_offset;         /* LIGHT_ENVIRONMENT_MAP: first texel of the image in the texel buffer */
    int texture;              /* LIGHT_TRIANGLE: its emission texture (an image on the surface, e.g. a screen's
                                 picture), which replaces spectrum_offset, or NO_TEXTURE */
    int linear_falloff;       /* LIGHT_SPOT: 1: linear in θ between the two cones; 0: smoothstep in cos θ */
} Light;

/* Everything a render pass needs besides the buffers. */
typedef struct {
    float4 camera_origin;    /* xyz: the eye; w: the near clip distance (kernels/camera.cl), scene units */
    float4 camera_forward;   /* xyz: unit vector; w: the far clip distance (scene units; 0: none) */
    float4 camera_right;     /* perspective, thin lens: unit vector scaled by tan(fov_x / 2); orthographic: scaled
                                by half the view's width (scene units); equirectangular: unit vector */
    float4 camera_up;        /* likewise with fov_y / the view's height */
    int width;
    int height;
    int max_depth;           /* path segments from the camera (Mitsuba 3): 1 = emitters only; -1 = unbounded */
    int rr_depth;            /* segment count at which Russian roulette starts */
    int light_count;
    int environment_light;   /* index of the LIGHT_ENVIRONMENT light, or -1 */
    int triangle_count;
    int seed;
    int sample_begin;        /* first sample index of this pass */
    int sample_count;        /* samples per pixel in this pass */
    int medium_count;        /* media in the scene: 0 (and no null_surfaces) lets visibility queries skip looking
                                for surfaces to cross */
    int hide_emitters;       /* HIDE_ENVIRONMENT | HIDE_AREA_EMITTERS bits: what the camera's own rays do not see */
    int shape_count;         /* analytic shapes (AnalyticShape rows) */
    int camera_type;         /* CAMERA_* (kernels/camera.cl) */
    int pixel_filter;        /* PIXEL_FILTER_* (kernels/pixel_filter.cl) */
    int instance_count;      /* placed objects (Instance rows) */
    int count_thin_passes;   /* path: 1: a pass straight through a thin sheet (thindielectric) is a segment toward
                                max_depth; 0: it is not (Mitsuba 3's volpath) */
    int instanced_shape_count;  /* analytic shapes of instanced objects (AnalyticShape rows after shape_count) */
    int null_surfaces;       /* 1: some surface has neither material nor medium (a light seen through): visibility
                                queries cross it, as they cross media's boundaries */
    /* The film's sizes (kernels/film.cl), run-time values so that one program serves every film of a kind. */
    int spectral_bins;       /* SPECTRAL_FILM: equal bands over [spectral_min_nm, spectral_max_nm] */
    int film_responses;      /* WAVELENGTH_TABLE: response curves after the film table's XYZ rows */
    float spectral_min_nm;
    float spectral_max_nm;
    int bdpt_only_s;         /* test builds with BDPT_ONE_STRATEGY (kernels/bdpt.cl): the one strategy kept */
    int bdpt_only_t;
    int bdpt_pixels_per_light_path;  /* bdpt: neighbouring pixels sharing one light subpath (kernels/bdpt.cl) */
    int glow_table;          /* glowing media: their light paths' table in the spectra (light_glowing_media.cl); -1 */
    int pad_params[1];       /* keeps `lens` 16-byte aligned */
    float4 lens;             /* CAMERA_THINLENS: aperture radius, focus distance along camera_forward (scene
                                units); a camera polariser's axis angle (radians) and 1 (polarized_path.cl), else
                                0, 0 */
    float4 filter_shape;     /* radius (pixels), 1 / ∫f over [-radius, radius] (per axis), then the filter's own:
                                gaussian: -1/(2σ²), exp(-radius²/(2σ²)) (σ in pixels); mitchell: B, C */
    float filter_cdf[PIXEL_FILTER_BINS];  /* gaussian, mitchell: CDF of |f| over [0, radius] at each bin's end */
    float4 lens_elements[LENS_ELEMENT_ROWS];  /* CAMERA_REALISTIC: kernels/camera_realistic.cl */
    float4 lens_pupils[LENS_PUPIL_BINS];      /* CAMERA_REALISTIC: its exit pupil's bounds per ring of the film */
} RenderParams;

typedef struct {
    float4 point;
    float4 direction;
    int type;                /* METER_* */
    int samples_per_item;
    int seed;
    int pad0;
} MeterParams;

#endif
