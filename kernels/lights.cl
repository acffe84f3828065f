/* Lights for next-event estimation, and the dispatch over the device light types. A light is one unit, as
 * pbrt-v4's lights are: each device light type's file, light_<name>.cl, holds its sampling from a point, its
 * densities, its emission sampling (where light paths start) and its emitted light together. The host generates
 * light_list.h from its registry of lights (spectrace.lights.DEVICE_LIGHTS): the types' codes (LIGHT_<NAME>), their
 * files, LIGHT_LIST(X) and, per kind, LIGHT_LIST_<KIND>(X) and LIGHT_KIND_<KIND>(light), through which this file,
 * light_emission.cl and bdpt.cl dispatch.
 *
 * What a light_<name>.cl defines, by its kind (all: name##_sample_li, next-event estimation from a point):
 * - AREA (emits from a surface; the shared radiance and directions: light_area.cl): _pdf_li (the solid-angle density
 *   of _sample_li reaching a point of it), _sample_point (a light path's origin and its area density), _pdf_point;
 * - POSITION (a delta position): _sample_le (a light path's direction and I/p_ω), _sample_direction and
 *   _pdf_direction (the same direction drawn and its density, for BDPT), _intensity (I along a direction);
 * - INFINITE (at infinity): _sample_wi (a direction toward it, with its density), _pdf_wi, _radiance (arriving from
 *   a direction; a delta direction's irradiance) and LIGHT_<NAME>_DELTA (1 for a delta direction, whose density is
 *   its pick probability).
 * Picking: one light by a discrete CDF built on the host (proportional to an estimate of its emitted power). */
#ifndef SPECTRACE_LIGHTS_CL
#define SPECTRACE_LIGHTS_CL

#include "light_sample.cl"
#include "light_list.h"

/* Lights on a surface (an emitting triangle, analytic sphere or other analytic shape): their shadow rays end just off
 * the light's surface. */
#define LIGHT_ON_SURFACE(light) LIGHT_KIND_AREA(light)

/* Smallest index i with u < cdf[i + 1]; cdf has light_count + 1 entries from 0 to 1. */
inline int pick_light(__global const float *light_cdf, int light_count, float u)
{
    return cdf_search(light_cdf, light_count, u);
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

/* Solid-angle density (pick probability included) with which sample_light reaches the point p (normal n, seen
 * along -wo from `from`) of an emitting surface; shape_uv: p's texture coordinates when the light is an analytic
 * shape. */
inline float emitter_hit_pdf(__global const Light *light, __global const AnalyticShape *shapes, float3 from,
                             float3 p, float3 n, float3 wo, float2 shape_uv)
{
#define X(name, NAME) \
    if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_li(light, shapes, from, p, n, wo, shape_uv);
    LIGHT_LIST_AREA(X)
#undef X
    return 0.0f;
}

/* Samples light `light` as seen from p. Returns 0 when the sample carries no light. */
inline int sample_light(__global const Light *light, const LightBuffers *buffers, const SampledWavelengths *w,
                        float3 p, float2 u, LightSample *s)
{
    s->is_delta = 0;
    s->normal = (float3)(0.0f);
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_sample_li(light, buffers, w, p, u, s);
    LIGHT_LIST(X)
#undef X
    return 0;
}

/* Radiance arriving from direction d (pointing away from the scene) from the environment `light`. */
inline float4 environment_radiance(__global const Light *light, __global const float *spectra,
                                   __global const float4 *texels, const SampledWavelengths *w, float3 d)
{
#define X(name, NAME) \
    if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_radiance(light, spectra, texels, w, d);
    LIGHT_LIST_INFINITE(X)
#undef X
    return (float4)(0.0f);
}

/* Solid-angle pdf of sampling direction d toward the environment `light`, times its pick probability. */
inline float environment_pdf(__global const Light *light, __global const float *map_cdf, float3 d)
{
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_wi(light, map_cdf, d);
    LIGHT_LIST_INFINITE(X)
#undef X
    return 0.0f;
}

/* Samples a direction toward the environment `light`; returns it with its pdf (pick probability included). */
inline float3 environment_sample(__global const Light *light, __global const float *map_cdf, float2 u, float *pdf)
{
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_sample_wi(light, map_cdf, u, pdf);
    LIGHT_LIST_INFINITE(X)
#undef X
    *pdf = 0.0f;
    return (float3)(0.0f);
}

#endif
