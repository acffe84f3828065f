/* Textures: a value per wavelength that varies over a surface, looked up at its texture coordinates uv (v down the
 * image, as the meshes store them). An image texture's texels are sigmoid coefficients of RGB reflectances (Jakob &
 * Hanika 2019, rgb_spectrum.cl), spectral bands of a spectral OpenEXR, plain scalars, or the linear RGB of an
 * emission (the weights of three basis spectra, which lights.cl applies: the lights' images); the host prepares them
 * (host/spectrace/textures) into the one texel buffer, with a MIP pyramid (Williams 1983, "Pyramidal
 * Parametrics") for trilinear filtering. Filtering follows pbrt-v4 (Pharr, Jakob & Humphreys, 4th ed., ch. 10.4):
 * bilinear interpolation between the four texels around the point, texel centres at half-integer positions, and
 * trilinear blending of the two pyramid levels whose texel size brackets the footprint. Filters blend SPECTRA, not
 * coefficients: each texel is evaluated at the path's wavelengths and the values blended, so a filtered
 * reflectance stays a convex combination of the texels' (in [0, 1] when they are). Texels are stored compactly
 * where that is exact or within a measured bound (Texture.storage; host/spectrace/textures/storage.py): 8- or 16-bit
 * unsigned normalised integers for data read from such files, half floats (vload_half, core OpenCL 1.2) for sigmoid
 * coefficients in the dimensionless form, emission RGB and spectral bands, float otherwise. */
#ifndef SPECTRACE_TEXTURE_CL
#define SPECTRACE_TEXTURE_CL

#include "types.h"
#include "rgb_spectrum.cl"
#include "spectrum.cl"
#if SCENE_HAS_PROCEDURAL_TEXTURES
#include "noise.cl"
#endif
#ifndef TEXTURE_TYPE_COUNT
#error "built without the textures' generated sources (spectrace.plugins.generated_sources)"
#endif

/* What a texture lookup reads: the texture rows, the texel buffer as floats, and the spectrum table (for a
 * checkerboard side that is a spectrum). */
typedef struct {
    __global const Texture *textures;
    __global const float *texels;
    __global const float *spectra;
#if SCENE_HAS_MESH_ATTRIBUTES
    int triangle;  /* the hit's triangle slot, whose mesh attributes are read (texture_mesh_attribute.cl); -1: none */
    float2 b12;    /* the hit's barycentrics of its corners v1 and v2 */
#endif
#if SCENE_HAS_DIRECTION_MIX
    float3 normal; /* the surface's geometric normal, which a directionmix reads (texture_direction_mix.cl); 0: none */
#endif
} TextureBuffers;

/* Beyond ±2^30 texels an int index would overflow; a texture repeated that often is a constant to any filter. */
#define TEXTURE_MAX_COORDINATE 1.0e9f

inline int texture_wrap(int i, int n, int wrap)
{
    if ((uint)i < (uint)n) return i;  /* inside the image, as nearly every lookup is: no integer division */
    if (wrap == WRAP_CLAMP) return clamp(i, 0, n - 1);
    if (wrap == WRAP_MIRROR) {
        int period = 2 * n;
        int m = i % period;
        if (m < 0) m += period;
        return m < n ? m : period - 1 - m;
    }
    int m = i % n;
    return m < 0 ? m + n : m;
}

/* Value `i` of the texture's stored values (counted in values of its storage from its data_offset), as a float. */
inline float texel_value(__global const Texture *t, const TextureBuffers *b, int i)
{
    __global const float *start = b->texels + t->data_offset;
    if (t->storage == STORAGE_HALF) return vload_half(i, (__global const half *)start);
    if (t->storage == STORAGE_UNORM8) return (float)((__global const uchar *)start)[i] * (1.0f / 255.0f);
    if (t->storage == STORAGE_UNORM16) return (float)((__global const ushort *)start)[i] * (1.0f / 65535.0f);
    return start[i];
}

/* Values i, i + 1, i + 2, as texel_value reads each. */
inline float3 texel_value3(__global const Texture *t, const TextureBuffers *b, int i)
{
    __global const float *start = b->texels + t->data_offset;
    if (t->storage == STORAGE_HALF) return vload_half3(0, (__global const half *)start + i);
    if (t->storage == STORAGE_UNORM8) {
        return convert_float3(vload3(0, (__global const uchar *)start + i)) * (1.0f / 255.0f);
    }
    if (t->storage == STORAGE_UNORM16) {
        return convert_float3(vload3(0, (__global const ushort *)start + i)) * (1.0f / 65535.0f);
    }
    return vload3(0, start + i);
}

/* A sigmoid texel's spectrum: half-stored coefficients are the dimensionless ones, of t = (λ − centre) / half span,
 * float-stored ones those of λ in nm (rgb_spectrum.cl). */
inline float4 texel_sigmoid(__global const Texture *t, float3 c, float4 lambda_nm)
{
    if (t->storage == STORAGE_HALF) return sigmoid_polynomial_dimensionless(c, lambda_nm);
    return sigmoid_polynomial(c, lambda_nm);
}

/* The value of texel (x, y) of a level that starts at value `level_offset` and is `width` texels wide, at the
 * path's wavelengths. BANDS are interpolated linearly between band centres, the end bands held beyond them. */
inline float4 texel_spectrum(__global const Texture *t, const TextureBuffers *b, int level_offset, int width, int x,
                             int y, const SampledWavelengths *w)
{
    int texel = level_offset + (y * width + x) * t->channels;
    if (t->texel_format == TEXEL_SIGMOID) return texel_sigmoid(t, texel_value3(t, b, texel), w->lambda);
    if (SCENE_HAS_SURFACE_NORMALS && t->texel_format == TEXEL_VECTOR) return (float4)(texel_value3(t, b, texel), 0.0f);
    /* RGB weights are blended as they are, (r, g, b, 0): the caller weights the basis spectra with the result
     * (lights.cl), which the blend commutes with. */
    if (t->texel_format == TEXEL_RGB) return (float4)(texel_value3(t, b, texel), 0.0f);
    if (t->texel_format == TEXEL_SCALAR || t->channels == 1) return (float4)(texel_value(t, b, texel));
    float4 position = clamp((w->lambda - t->band_first_nm) / t->band_step_nm, 0.0f, (float)(t->channels - 1));
    int4 lower = texel + min(convert_int4(position), (int4)(t->channels - 2));
    float4 frac = position - convert_float4(lower - texel);
    float4 below = (float4)(texel_value(t, b, lower.x), texel_value(t, b, lower.y), texel_value(t, b, lower.z),
                            texel_value(t, b, lower.w));
    float4 above = (float4)(texel_value(t, b, lower.x + 1), texel_value(t, b, lower.y + 1),
                            texel_value(t, b, lower.z + 1), texel_value(t, b, lower.w + 1));
    return mad(frac, above - below, below);
}

/* Offset (in stored values, from the texture's data_offset) and size of MIP level `level` (level l is
 * max(1, width >> l) by max(1, height >> l)). */
inline int texture_level(__global const Texture *t, int level, int *width, int *height)
{
    int offset = 0, lw = t->width, lh = t->height;
    for (int l = 0; l < level; ++l) {
        offset += lw * lh * t->channels;
        lw = max(1, lw >> 1);
        lh = max(1, lh >> 1);
    }
    *width = lw;
    *height = lh;
    return offset;
}

/* The texel containing st at one level. */
inline float4 texture_nearest(__global const Texture *t, const TextureBuffers *b, int level, float2 st,
                              const SampledWavelengths *w)
{
    int width, height;
    int offset = texture_level(t, level, &width, &height);
    float2 p = clamp(st * (float2)(width, height), -TEXTURE_MAX_COORDINATE, TEXTURE_MAX_COORDINATE);
    int x = texture_wrap((int)floor(p.x), width, t->wrap);
    int y = texture_wrap((int)floor(p.y), height, t->wrap);
    return texel_spectrum(t, b, offset, width, x, y, w);
}

/* The cell of four texel centres around st at one level (texel centres at (i + ½) / width), its corners wrapped as
 * the texture wraps, and st's place in it: what a bilinear lookup and its gradient both read. */
typedef struct {
    int offset;         /* the level's first texel */
    int width, height;  /* the level's size, texels */
    int xa, xb, ya, yb; /* the cell's columns and rows, wrapped */
    float2 f;           /* st's fraction across the cell, [0, 1) */
} BilinearCell;

inline BilinearCell texture_bilinear_cell(__global const Texture *t, int level, float2 st)
{
    BilinearCell c;
    c.offset = texture_level(t, level, &c.width, &c.height);
    float2 p = clamp(st * (float2)(c.width, c.height) - 0.5f, -TEXTURE_MAX_COORDINATE, TEXTURE_MAX_COORDINATE);
    float2 corner = floor(p);
    c.f = p - corner;
    int x0 = (int)corner.x, y0 = (int)corner.y;
    c.xa = texture_wrap(x0, c.width, t->wrap);
    c.xb = texture_wrap(x0 + 1, c.width, t->wrap);
    c.ya = texture_wrap(y0, c.height, t->wrap);
    c.yb = texture_wrap(y0 + 1, c.height, t->wrap);
    return c;
}

/* The four texels around st at one level, blended by their distance (texel centres at (i + ½) / width). */
inline float4 texture_bilinear(__global const Texture *t, const TextureBuffers *b, int level, float2 st,
                               const SampledWavelengths *w)
{
    BilinearCell c = texture_bilinear_cell(t, level, st);
    if (t->texel_format == TEXEL_SIGMOID) {
        /* Most lookups of an image's flat regions find four equal texels: one spectrum then stands for the blend,
         * which is exactly what blending four equal values gives (mix(a, a, f) = a). */
        float3 c00 = texel_value3(t, b, c.offset + 3 * (c.ya * c.width + c.xa));
        float3 c10 = texel_value3(t, b, c.offset + 3 * (c.ya * c.width + c.xb));
        float3 c01 = texel_value3(t, b, c.offset + 3 * (c.yb * c.width + c.xa));
        float3 c11 = texel_value3(t, b, c.offset + 3 * (c.yb * c.width + c.xb));
        if (all(c00 == c10) && all(c00 == c01) && all(c00 == c11)) return texel_sigmoid(t, c00, w->lambda);
        float4 top_sigmoid = mix(texel_sigmoid(t, c00, w->lambda), texel_sigmoid(t, c10, w->lambda), c.f.x);
        float4 bottom_sigmoid = mix(texel_sigmoid(t, c01, w->lambda), texel_sigmoid(t, c11, w->lambda), c.f.x);
        return mix(top_sigmoid, bottom_sigmoid, c.f.y);
    }
    float4 top = mix(texel_spectrum(t, b, c.offset, c.width, c.xa, c.ya, w),
                     texel_spectrum(t, b, c.offset, c.width, c.xb, c.ya, w), c.f.x);
    float4 bottom = mix(texel_spectrum(t, b, c.offset, c.width, c.xa, c.yb, w),
                        texel_spectrum(t, b, c.offset, c.width, c.xb, c.yb, w), c.f.x);
    return mix(top, bottom, c.f.y);
}

/* The continuous MIP level whose texels are `footprint` wide in st units: texels of level l are 2^l / max(width,
 * height) wide, so l = log2(footprint · max(width, height)), clamped to the pyramid (0 for a zero footprint). */
inline float texture_mip_level(__global const Texture *t, float footprint_st)
{
    float finest = (float)max(t->width, t->height);
    if (!(footprint_st * finest > 1.0f)) return 0.0f;
    return fmin(log2(footprint_st * finest), (float)(t->levels - 1));
}

/* An image texture (bitmap or spectral) at uv; footprint: the width of the lookup's filter region in uv units
 * (0: the finest level). */
inline float4 image_texture_spectrum(__global const Texture *t, const TextureBuffers *b, float2 uv,
                                     float footprint, const SampledWavelengths *w)
{
    float2 st = uv * t->uv_transform.xy + t->uv_transform.zw;
    if (t->filter == FILTER_NEAREST) return texture_nearest(t, b, 0, st, w);
    if (t->filter == FILTER_BILINEAR || t->levels == 1) return texture_bilinear(t, b, 0, st, w);
    float level = texture_mip_level(t, footprint * fmax(fabs(t->uv_transform.x), fabs(t->uv_transform.y)));
    int lower = (int)floor(level);
    float frac = level - (float)lower;
    float4 value = texture_bilinear(t, b, lower, st, w);
    if (frac > 0.0f) value = mix(value, texture_bilinear(t, b, lower + 1, st, w), frac);
    return value;
}

/* The gradient ∂h/∂st of texture_bilinear's interpolant at one level (h: the first lane of a scalar texture): the
 * exact derivative of the blend, constant across u inside each cell between four texel centres and linear in v,
 * in texels, times the level's size (Mitsuba 3's bitmap eval_1_grad takes the same derivative). Wrapped neighbours
 * as the lookup wraps them, so a clamped edge is flat beyond the outer texel centres. */
inline float2 texture_bilinear_gradient(__global const Texture *t, const TextureBuffers *b, int level, float2 st,
                                        const SampledWavelengths *w)
{
    BilinearCell c = texture_bilinear_cell(t, level, st);
    float h00 = texel_spectrum(t, b, c.offset, c.width, c.xa, c.ya, w).x;
    float h10 = texel_spectrum(t, b, c.offset, c.width, c.xb, c.ya, w).x;
    float h01 = texel_spectrum(t, b, c.offset, c.width, c.xa, c.yb, w).x;
    float h11 = texel_spectrum(t, b, c.offset, c.width, c.xb, c.yb, w).x;
    float2 per_texel = (float2)(mix(h10 - h00, h11 - h01, c.f.y), mix(h01 - h00, h11 - h10, c.f.x));
    return per_texel * (float2)(c.width, c.height);
}

/* ∂h/∂uv of an image texture's lookup at uv (image_texture_spectrum's first lane): 0 for a nearest lookup, whose
 * steps have no derivative (as Mitsuba 3's eval_1_grad gives), the bilinear interpolant's gradient otherwise, and
 * for a trilinear lookup the same blend of its two levels' gradients (the blend is linear). */
inline float2 image_texture_gradient(__global const Texture *t, const TextureBuffers *b, float2 uv, float footprint,
                                     const SampledWavelengths *w)
{
    if (t->filter == FILTER_NEAREST) return (float2)(0.0f);
    float2 st = uv * t->uv_transform.xy + t->uv_transform.zw;
    float2 gradient;
    if (t->filter == FILTER_BILINEAR || t->levels == 1) {
        gradient = texture_bilinear_gradient(t, b, 0, st, w);
    } else {
        float level = texture_mip_level(t, footprint * fmax(fabs(t->uv_transform.x), fabs(t->uv_transform.y)));
        int lower = (int)floor(level);
        float frac = level - (float)lower;
        gradient = texture_bilinear_gradient(t, b, lower, st, w);
        if (frac > 0.0f) gradient = mix(gradient, texture_bilinear_gradient(t, b, lower + 1, st, w), frac);
    }
    return gradient * t->uv_transform.xy;  /* the chain rule through st = uv · scale + offset */
}

/* Which side of a checkerboard st is on: 0 where floor(s) + floor(t) is even. */
inline int checkerboard_side(float2 st)
{
    float k = floor(st.x) + floor(st.y);
    return (k - 2.0f * floor(0.5f * k)) != 0.0f;
}

#if SCENE_HAS_SOLID_TEXTURES
#include "texture_solid.cl"
#endif
#if SCENE_HAS_MESH_ATTRIBUTES
#include "texture_mesh_attribute.cl"
#endif
#if SCENE_HAS_TEXTURE_MAPPINGS
#include "texture_mapping.cl"
#else
#define texture_uv(b, t, uv, p) (uv)
#endif

/* A texture that is no composite (an image texture, or a solid texture looked up at the world-space point p). */
inline float4 inner_texture_spectrum(const TextureBuffers *b, __global const Texture *t, float2 uv, float3 p,
                                     float footprint, const SampledWavelengths *w)
{
#if SCENE_HAS_SOLID_TEXTURES
    if (texture_is_solid(t)) return solid_texture_spectrum(b, t, p, w);
#endif
#if SCENE_HAS_MESH_ATTRIBUTES
    if (t->type == TEXTURE_MESH_ATTRIBUTE) return mesh_attribute_spectrum(b, t, w);
#endif
    return image_texture_spectrum(t, b, texture_uv(b, t, uv, p), footprint, w);
}

/* Side `side` of a composite texture: its inner texture, or its spectrum. */
inline float4 texture_side(const TextureBuffers *b, __global const Texture *t, int side, float2 uv, float3 p,
                           float footprint, const SampledWavelengths *w)
{
    int inner = t->side_texture[side];
    if (inner == NO_TEXTURE) return spectrum_at(b->spectra, t->side_spectrum[side], w);
    return inner_texture_spectrum(b, &b->textures[inner], uv, p, footprint, w);
}

#if SCENE_HAS_DIRECTION_MIX
#include "texture_direction_mix.cl"
#endif

/* Texture `index` at uv and the world-space point p (which only solid textures read), at the path's four
 * wavelengths. Composites (checkerboard, scale, mix, dots) read their operands, which are never composites, so
 * nothing recurses. */
inline float4 texture_spectrum_at(const TextureBuffers *b, int index, float2 uv, float3 p, float footprint,
                                  const SampledWavelengths *w)
{
    __global const Texture *t = &b->textures[index];
    if (t->type == TEXTURE_CHECKERBOARD) {
        return texture_side(b, t, checkerboard_side(texture_uv(b, t, uv, p) * t->uv_transform.xy + t->uv_transform.zw), uv, p, footprint,
                            w);
    }
#if SCENE_HAS_PROCEDURAL_TEXTURES
    if (t->type == TEXTURE_DOTS) {
        return texture_side(b, t, dots_side(texture_uv(b, t, uv, p) * t->uv_transform.xy + t->uv_transform.zw), uv, p, footprint, w);
    }
#endif
#if SCENE_HAS_DIRECTION_MIX
    if (t->type == TEXTURE_DIRECTIONMIX) return direction_mix_spectrum(b, t, uv, p, footprint, w);
#endif
    if (t->type == TEXTURE_SCALE || t->type == TEXTURE_MIX) {
        /* The factor is a number, the same at every wavelength: a scalar texture's first lane. */
        float factor = t->factor_texture == NO_TEXTURE
                     ? t->factor
                     : inner_texture_spectrum(b, &b->textures[t->factor_texture], uv, p, footprint, w).x;
#if SCENE_HAS_SOLID_TEXTURES
        /* A solid texture's amount (fbm's about [−2, 2]) is held to [0, 1], so that a mix stays a blend. */
        if (t->type == TEXTURE_MIX && t->factor_texture != NO_TEXTURE
            && texture_is_solid(&b->textures[t->factor_texture])) {
            factor = clamp(factor, 0.0f, 1.0f);
        }
#endif
        float4 first = texture_side(b, t, 0, uv, p, footprint, w);
        if (t->type == TEXTURE_SCALE) return factor * first;
        return mix(first, texture_side(b, t, 1, uv, p, footprint, w), factor);
    }
    return inner_texture_spectrum(b, t, uv, p, footprint, w);
}

/* Texture `index` where no surface point is at hand (lights' images, which are never solid textures). */
inline float4 texture_spectrum(const TextureBuffers *b, int index, float2 uv, float footprint,
                               const SampledWavelengths *w)
{
    return texture_spectrum_at(b, index, uv, (float3)(0.0f), footprint, w);
}

/* A texture read as numbers rather than a spectrum: scalars (heights, opacity) and vectors (normal maps) are the
 * same at every wavelength; a checkerboard side that is a spectrum is read at one fixed wavelength (a constant
 * `{ value = ... }` is what such a side should be). */
inline float4 texture_numbers_at(const TextureBuffers *b, int index, float2 uv, float3 p, float footprint)
{
    SampledWavelengths w = fixed_wavelengths((float4)(560.0f));
    return texture_spectrum_at(b, index, uv, p, footprint, &w);
}

inline float4 texture_numbers(const TextureBuffers *b, int index, float2 uv, float footprint)
{
    return texture_numbers_at(b, index, uv, (float3)(0.0f), footprint);
}

/* What a material's parameters are looked up with at a surface point: the buffers, the point's texture
 * coordinates and the lookup's footprint (the width of its filter region in uv units; 0 reads the finest level);
 * what the shadowing term of a normal or bump map needs (material.cl, material_shadowing); and the direction an
 * anisotropic material's frame follows (material.cl, material_frame). */
typedef struct {
    TextureBuffers buffers;
    float2 uv;
    float3 p;  /* the world-space surface point, where solid textures are looked up (0 where none is at hand) */
    float footprint;
    float3 base_normal;  /* unit: the shading normal before a normal or bump map turned it; 0: no shadowing term */
    float3 dpdu;         /* the surface's dp/du at the point, for a material with Material.tangent_frame; 0: none */
    float tangent_w;     /* ±1: the handedness of dpdu's frame (a file tangent's w, vertex_tangents.cl), toward whose
                            signed bitangent an anisotropic frame turns; 1 where dpdu is not a file's */
    int adjoint;         /* 1: the transport carries importance, so a sampled direction is the viewer's side and
                            wo the light's (light tracer, photons, BDPT light subpaths); 0: radiance */
#if SCENE_HAS_MITSUBA_CURVE_UV
    int fibre_h_from_geometry;  /* 1: a curve whose v is Mitsuba 3's (along it): the hair BSDF's h comes from wo */
#endif
} SurfaceContext;

/* Where a surface context's lookups read mesh attributes: the hit of vertex v (a PathVertex or BdptVertex); and
 * whether it is on a curve with Mitsuba 3's texture coordinates (scene.cl, curve_slot_has_mitsuba_uv, of the
 * caller's `scene`). */
#if SCENE_HAS_MESH_ATTRIBUTES
#define SURFACE_MESH_AT_HIT(sc, v) ((sc).buffers.triangle = (v).triangle, (sc).buffers.b12 = (v).b12)
#else
#define SURFACE_MESH_AT_HIT(sc, v) ((void)0)
#endif
/* Where a surface context's lookups take the normal n from (a directionmix's): SURFACE_AT_HIT gives them the
 * vertex's geometric normal, as pbrt-v4's TextureEvalContext carries its interaction's n. */
#if SCENE_HAS_DIRECTION_MIX
#define SURFACE_NORMAL(sc, n) ((sc).buffers.normal = (n))
#else
#define SURFACE_NORMAL(sc, n) ((void)0)
#endif
#if SCENE_HAS_MITSUBA_CURVE_UV
#define SURFACE_HIT_DETAIL(sc, v) \
    (SURFACE_MESH_AT_HIT(sc, v), (sc).fibre_h_from_geometry = curve_slot_has_mitsuba_uv(scene, (v).triangle))
#else
#define SURFACE_HIT_DETAIL(sc, v) SURFACE_MESH_AT_HIT(sc, v)
#endif
#define SURFACE_AT_HIT(sc, v) (SURFACE_HIT_DETAIL(sc, v), SURFACE_NORMAL(sc, (v).n))

/* A textured parameter: its texture when it has one, else its tabulated spectrum. In a scene without textures the
 * test folds away (SCENE_HAS_TEXTURES) and this is the plain table lookup. */
inline float4 surface_spectrum(const SurfaceContext *sc, int texture, int spectrum_offset,
                               const SampledWavelengths *w)
{
    if (SCENE_HAS_TEXTURES && texture != NO_TEXTURE) {
        return texture_spectrum_at(&sc->buffers, texture, sc->uv, sc->p, sc->footprint, w);
    }
    return spectrum_at(sc->buffers.spectra, spectrum_offset, w);
}

/* A textured number (a roughness): its one-channel texture when it has one, else `value`. */
inline float surface_scalar(const SurfaceContext *sc, int texture, float value, const SampledWavelengths *w)
{
    if (SCENE_HAS_TEXTURES && texture != NO_TEXTURE) {
        return texture_spectrum_at(&sc->buffers, texture, sc->uv, sc->p, sc->footprint, w).x;
    }
    return value;
}

#endif
