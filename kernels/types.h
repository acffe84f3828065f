/* Structs shared by the host and the device.
 *
 * Each struct is mirrored by a numpy structured dtype in host/spectrace/render/device_types.py with explicit
 * offsets; tests/test_struct_layout.py compiles a kernel that reports sizeof/offsetof and compares.
 * Only float4 and 4-byte scalars are used, float4 first, so every compiler lays them out identically
 * (float3 is avoided: it occupies 16 bytes in buffers). */
#ifndef SPECTRACE_TYPES_H
#define SPECTRACE_TYPES_H

/* Wavelength grid of every tabulated spectrum (nm). Must match spectrace.spectral.grid. */
#define GRID_MIN_NM 360.0f
#define GRID_MAX_NM 830.0f
#define GRID_SAMPLES 471

#define MATERIAL_DIFFUSE 0

/* Bounding volume hierarchy node (32 bytes). Interior: count == 0, children at left_first and left_first + 1.
 * Leaf: count > 0 triangles starting at slot left_first of the triangle arrays. */
typedef struct {
    float bmin[3];
    int left_first;
    float bmax[3];
    int count;
} BVHNode;

/* Per-triangle shading data, in BVH leaf order. */
typedef struct {
    int material;   /* index into the material array */
    int light;      /* index into the light array, or -1 when the triangle does not emit */
} TriangleInfo;

typedef struct {
    int type;                /* MATERIAL_* */
    int reflectance_offset;  /* offset (floats) of the reflectance spectrum in the spectrum table */
    int pad0;
    int pad1;
} Material;

/* An emitting triangle: radiance L(λ) = scale * table[radiance_offset + ...](λ), in W/(m² sr nm). */
typedef struct {
    int triangle;          /* slot in the triangle arrays */
    int radiance_offset;
    float scale;
    float pmf;             /* probability that next-event estimation picks this light */
    float area;            /* m² */
    int two_sided;
    int pad0;
    int pad1;
} Light;

/* Everything a render pass needs besides the buffers. */
typedef struct {
    float4 camera_origin;
    float4 camera_forward;   /* unit vector */
    float4 camera_right;     /* unit vector scaled by tan(fov_x / 2) */
    float4 camera_up;        /* unit vector scaled by tan(fov_y / 2) */
    int width;
    int height;
    int max_depth;           /* path segments from the camera (Mitsuba 3): 1 = emitters only; -1 = unbounded */
    int rr_depth;            /* segment count at which Russian roulette starts */
    int light_count;
    int seed;
    int sample_begin;        /* first sample index of this pass */
    int sample_count;        /* samples per pixel in this pass */
} RenderParams;

#endif
