/* Lights for next-event estimation: one is picked by a discrete CDF built on the host (proportional to an
 * estimate of its emitted power), then sampled. Area lights are emitting triangles sampled uniformly over their
 * area; point, spot and distant lights are delta lights (reachable only by next-event estimation); the uniform
 * environment is sampled uniformly over the sphere of directions. */
#ifndef SPECTRACE_LIGHTS_CL
#define SPECTRACE_LIGHTS_CL

#include "types.h"
#include "spectrum.cl"
#include "sampling.cl"
#include "environment.cl"
#include "texture.cl"
#include "shapes.cl"

typedef struct {
    float3 wi;         /* unit direction from the shaded point toward the light */
    float distance;    /* to the light point; INFINITY for distant and environment lights */
    float3 point;      /* the light point (finite lights), to aim the shadow ray at */
    float3 normal;     /* lights on a surface (LIGHT_ON_SURFACE): its geometric normal, for the shadow ray's end offset */
    float4 arriving;   /* radiance arriving along -wi (area, environment) or, for delta lights, the irradiance
                          it produces on a surface facing it: I/d² or E (W/(m² nm)) */
    float pdf;         /* solid-angle pdf including the pick probability; for delta lights the pick probability */
    int is_delta;
} LightSample;

/* Smallest index i with u < cdf[i + 1]; cdf has light_count + 1 entries from 0 to 1. */
inline int pick_light(__global const float *light_cdf, int light_count, float u)
{
    int lo = 0, hi = light_count - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (u < light_cdf[mid + 1]) hi = mid; else lo = mid + 1;
    }
    return lo;
}

/* pick_light driven by u.x, which is then rescaled to [0, 1) within the picked light's share of the CDF, so one 2D
 * sample both picks the light and places the point on it (the "sample reuse" of Mitsuba 3 and pbrt). A stratified
 * 2D pattern then stays stratified over all the lights together, e.g. across the two triangles of a quad, where a
 * separate pick number would hand each triangle an unrelated subset of the points. */
inline int pick_light_reusing(__global const float *light_cdf, int light_count, float2 *u)
{
    int i = pick_light(light_cdf, light_count, u->x);
    float lo = light_cdf[i], share = light_cdf[i + 1] - lo;
    u->x = share > 0.0f ? clamp((u->x - lo) / share, 0.0f, 0x1.fffffep-1f) : 0.0f;
    return i;
}

inline float4 light_spectrum(__global const Light *light, __global const float *spectra, const SampledWavelengths *w)
{
    return light->scale * spectrum_at(spectra, light->spectrum_offset, w);
}

/* The unit geometric normal of the winding, which the host stores in the w of the triangle's three vertices
 * (render/scene_buffers.py). */
inline float3 triangle_normal(__global const float4 *triangle_vertices, int triangle)
{
    return (float3)(triangle_vertices[3 * triangle].w, triangle_vertices[3 * triangle + 1].w,
                    triangle_vertices[3 * triangle + 2].w);
}

inline float3 triangle_point(__global const float4 *triangle_vertices, int triangle, float2 b12)
{
    float3 v0 = triangle_vertices[3 * triangle].xyz;
    float3 v1 = triangle_vertices[3 * triangle + 1].xyz;
    float3 v2 = triangle_vertices[3 * triangle + 2].xyz;
    return (1.0f - b12.x - b12.y) * v0 + b12.x * v1 + b12.y * v2;
}

inline float2 triangle_uv(__global const float2 *triangle_uvs, int triangle, float2 b12)
{
    return (1.0f - b12.x - b12.y) * triangle_uvs[3 * triangle] + b12.x * triangle_uvs[3 * triangle + 1]
         + b12.y * triangle_uvs[3 * triangle + 2];
}

/* An emission texture at uv, at its finest level: a spectral texture's value, or for RGB texels the lookup's
 * (r, g, b) weighting the texture's three basis spectra, r·R(λ) + g·G(λ) + b·B(λ). The weights are blended before
 * they weight the spectra (texture.cl): the same, as the sum is linear in them, for fewer spectrum lookups. */
inline float4 emission_texture_radiance(const TextureBuffers *b, int index, float2 uv, const SampledWavelengths *w)
{
    __global const Texture *t = &b->textures[index];
    float4 value = texture_spectrum(b, index, uv, 0.0f, w);
    if (t->texel_format != TEXEL_RGB) return value;
    return value.x * spectrum_at(b->spectra, t->basis_offset[0], w)
         + value.y * spectrum_at(b->spectra, t->basis_offset[1], w)
         + value.z * spectrum_at(b->spectra, t->basis_offset[2], w);
}

/* Radiance leaving an emitting triangle toward `to_viewer` (unit), whose geometric normal is n, at texture
 * coordinates uv (read when the light has an emission texture: an RGB image weighting three basis spectra, or a
 * spectral one, looked up at its finest level, times the light's scale). */
inline float4 area_light_emitted(__global const Light *light, const TextureBuffers *textures,
                                 const SampledWavelengths *w, float3 n, float3 to_viewer, float2 uv)
{
    if (!light->two_sided && dot(n, to_viewer) <= 0.0f) return (float4)(0.0f);
    if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) {
        return light->scale * emission_texture_radiance(textures, light->texture, uv, w);
    }
    return light_spectrum(light, textures->spectra, w);
}

/* Solid-angle density (pick probability included) of reaching a point of an emitting triangle at `distance`
 * whose normal makes |cos| with the ray. */
inline float area_light_pdf(__global const Light *light, float distance, float abs_cos_light)
{
    if (abs_cos_light <= 0.0f) return 0.0f;
    return light->pmf * distance * distance / (light->area * abs_cos_light);
}

/* Spot falloff between the cutoff and the falloff start: smoothstep in cos θ (pbrt-v4's profile), or, where
 * linear_falloff is set, linear in the angle θ itself (Mitsuba 3's spot.cpp profile, so its scenes import exactly).
 * Contract: cos_cutoff <= cos_falloff_start; returns a factor in [0, 1]. */
inline float spot_falloff(__global const Light *light, float cos_theta)
{
    if (cos_theta >= light->cos_falloff_start) return 1.0f;
    if (cos_theta <= light->cos_cutoff) return 0.0f;
    if (light->linear_falloff) {
        float cutoff = acos(light->cos_cutoff);
        return (cutoff - acos(cos_theta)) / (cutoff - acos(light->cos_falloff_start));
    }
    float t = (cos_theta - light->cos_cutoff) / (light->cos_falloff_start - light->cos_cutoff);
    return t * t * (3.0f - 2.0f * t);
}

/* A spot's slide, Mitsuba 3's spot `texture` (spot.cpp): a reflectance image the intensity passes through,
 * projected over the cone at uv = (0.5, 0.5) + ½ (x, y) / (z tan θ_cutoff) in the light's frame: z its axis, x at
 * the angle direction.w from the tangent of the axis' orthonormal basis toward its bitangent (the host's
 * lights/spot.py measures it so), y = z × x, down the image. Looked up at its finest level.
 * Contract: light->texture is a reflectance texture, d unit and leaving the light; 0 behind the light. */
inline float4 spot_slide(__global const Light *light, const TextureBuffers *textures, const SampledWavelengths *w,
                         float3 d)
{
    float3 z = light->direction.xyz, tangent, bitangent;
    orthonormal_basis(z, &tangent, &bitangent);
    float3 x = cos(light->direction.w) * tangent + sin(light->direction.w) * bitangent;
    float3 y = cross(z, x);
    float cos_theta = dot(d, z);
    if (!(cos_theta > 0.0f)) return (float4)(0.0f);
    float tan_cutoff = sqrt(fmax(0.0f, 1.0f - light->cos_cutoff * light->cos_cutoff)) / light->cos_cutoff;
    float2 uv = 0.5f + 0.5f * (float2)(dot(d, x), dot(d, y)) / (cos_theta * tan_cutoff);
    return texture_spectrum(textures, light->texture, uv, 0.0f, w);
}

inline float3 sample_uniform_sphere(float2 u)
{
    float z = 1.0f - 2.0f * u.x;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 circle = r * cos_sin_turns(u.y);
    return (float3)(circle.x, circle.y, z);
}

/* The scene-wide buffers that sampling a light may need besides the light itself. */
typedef struct {
    __global const float4 *triangle_vertices;
    __global const float2 *triangle_uvs;
    __global const float *spectra;
    __global const float4 *texels;
    __global const float *map_cdf;
    TextureBuffers textures;  /* the emission textures' rows, the same texels as floats, the spectra */
    __global const AnalyticShape *shapes;
} LightBuffers;

/* Lights on a surface (an emitting triangle, analytic sphere or other analytic shape): their shadow rays end just off
 * the light's surface. */
#define LIGHT_ON_SURFACE(light) \
    (LIGHT_IS(light, LIGHT_TRIANGLE) || LIGHT_IS(light, LIGHT_SPHERE) || LIGHT_IS(light, LIGHT_SHAPE))

/* Texture coordinates of the sphere point whose outward world normal is n. */
inline float2 sphere_uv_of_normal(__global const AnalyticShape *shape, float3 n)
{
    float3 object_point = normalize(shape_vector_to_object(shape, n));
    return shape_uv_from_mitsuba(shape, (float2)(shape_azimuth_turns(object_point.x, object_point.y),
                    atan2(sqrt(object_point.x * object_point.x + object_point.y * object_point.y), object_point.z) * (1.0f / SHAPE_PI)));
}

/* Samples an emitting analytic shape seen from p: a sphere that p is outside by the cone it subtends, any other
 * (and a sphere from inside) uniformly over its area. */
inline int sample_shape_light(__global const Light *light, const LightBuffers *buffers, const SampledWavelengths *w,
                              float3 p, float2 u, LightSample *s)
{
    __global const AnalyticShape *shape = &buffers->shapes[light->triangle];
    float3 q, n;
    float2 uv;
    float pdf_solid_angle = 0.0f;
    float one_minus_cos = LIGHT_IS(light, LIGHT_SPHERE)
                        ? sphere_cone_one_minus_cos(light->position.xyz, light->position.w, p) : 0.0f;
    if (one_minus_cos > 0.0f) {
        q = sample_sphere_cone(light->position.xyz, light->position.w, p, u, &n, &pdf_solid_angle);
        uv = sphere_uv_of_normal(shape, n);
        if (shape->flip_normals) n = -n;
    } else {
        uv = shape_sample_uv(shape, u);
        ShapeSurface g = shape_surface(shape, uv);
        q = g.p;
        n = g.n;
        pdf_solid_angle = -1.0f;  /* from the area density below, once the distance is known */
        s->pdf = shape_area_pdf(shape, g.area_stretch);
    }
    float3 to_light = q - p;
    float d = length(to_light);
    if (!(d > 0.0f)) return 0;
    s->wi = to_light / d;
    s->distance = d;
    s->point = q;
    s->normal = n;
    s->arriving = area_light_emitted(light, &buffers->textures, w, n, -s->wi, uv);
    if (pdf_solid_angle < 0.0f) {
        float abs_cos = fabs(dot(n, s->wi));
        pdf_solid_angle = abs_cos > 0.0f ? s->pdf * d * d / abs_cos : 0.0f;
    }
    s->pdf = light->pmf * pdf_solid_angle;
    return s->pdf > 0.0f && isfinite(s->pdf);
}

/* Solid-angle density (pick probability included) with which sample_light reaches the point p (normal n, seen
 * along -wo from `from`) of an emitting surface; shape_uv: p's texture coordinates when the light is an analytic
 * shape. */
inline float emitter_hit_pdf(__global const Light *light, __global const AnalyticShape *shapes, float3 from,
                             float3 p, float3 n, float3 wo, float2 shape_uv)
{
    if (LIGHT_IS(light, LIGHT_SPHERE) || LIGHT_IS(light, LIGHT_SHAPE)) {
        if (LIGHT_IS(light, LIGHT_SPHERE)) {
            float one_minus_cos = sphere_cone_one_minus_cos(light->position.xyz, light->position.w, from);
            if (one_minus_cos > 0.0f) return light->pmf / (SHAPE_TWO_PI * one_minus_cos);
        }
        __global const AnalyticShape *shape = &shapes[light->triangle];
        float abs_cos = fabs(dot(n, wo));
        if (!(abs_cos > 0.0f)) return 0.0f;
        float d = distance(from, p);
        return light->pmf * shape_area_pdf(shape, shape_surface(shape, shape_uv).area_stretch) * d * d / abs_cos;
    }
    return area_light_pdf(light, distance(from, p), fabs(dot(n, wo)));
}

/* Samples light `light` as seen from p. Returns 0 when the sample carries no light. */
inline int sample_light(__global const Light *light, const LightBuffers *buffers, const SampledWavelengths *w,
                        float3 p, float2 u, LightSample *s)
{
    __global const float4 *triangle_vertices = buffers->triangle_vertices;
    __global const float *spectra = buffers->spectra;
    s->is_delta = 0;
    s->normal = (float3)(0.0f);
    if (LIGHT_IS(light, LIGHT_TRIANGLE)) {
        float2 b12 = sample_triangle_uniform(u);
        float3 q = triangle_point(triangle_vertices, light->triangle, b12);
        float3 n_light = triangle_normal(triangle_vertices, light->triangle);
        float3 to_light = q - p;
        float d = length(to_light);
        if (!(d > 0.0f)) return 0;
        s->wi = to_light / d;
        s->distance = d;
        s->point = q;
        s->normal = n_light;
        s->arriving = area_light_emitted(light, &buffers->textures, w, n_light, -s->wi,
                                         triangle_uv(buffers->triangle_uvs, light->triangle, b12));
        s->pdf = area_light_pdf(light, d, fabs(dot(n_light, s->wi)));
        return s->pdf > 0.0f;
    }
    if (LIGHT_IS(light, LIGHT_SPHERE) || LIGHT_IS(light, LIGHT_SHAPE)) {
        return sample_shape_light(light, buffers, w, p, u, s);
    }
    if (LIGHT_IS(light, LIGHT_POINT) || LIGHT_IS(light, LIGHT_SPOT)) {
        float3 to_light = light->position.xyz - p;
        float d2 = dot(to_light, to_light);
        if (!(d2 > 0.0f)) return 0;
        float d = sqrt(d2);
        s->wi = to_light / d;
        s->distance = d;
        s->point = light->position.xyz;
        float falloff = 1.0f;
        if (LIGHT_IS(light, LIGHT_SPOT)) falloff = spot_falloff(light, dot(-s->wi, light->direction.xyz));
        s->arriving = light_spectrum(light, spectra, w) * (falloff / d2);
        if (SCENE_HAS_LIGHT_IMAGES && LIGHT_IS(light, LIGHT_SPOT) && light->texture != NO_TEXTURE) {
            s->arriving *= spot_slide(light, &buffers->textures, w, -s->wi);
        }
        s->pdf = light->pmf;
        s->is_delta = 1;
        return falloff > 0.0f;
    }
    if (LIGHT_IS(light, LIGHT_DISTANT)) {
        s->wi = -light->direction.xyz;
        s->distance = INFINITY;
        s->point = p;
        s->arriving = light_spectrum(light, spectra, w);
        s->pdf = light->pmf;
        s->is_delta = 1;
        return 1;
    }
    /* LIGHT_ENVIRONMENT, LIGHT_ENVIRONMENT_MAP */
#if !SCENE_HAS_ENVIRONMENT
    return 0;
#endif
    s->wi = environment_sample(light, buffers->map_cdf, u, &s->pdf);
    s->distance = INFINITY;
    s->point = p;
    s->arriving = environment_radiance(light, spectra, buffers->texels, w, s->wi);
    return s->pdf > 0.0f;
}

#endif
