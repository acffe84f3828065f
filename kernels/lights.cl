/* Area lights: emitting triangles picked for next-event estimation by a discrete CDF built on the host
 * (proportional to each triangle's emitted power), then sampled uniformly over their area. */
#ifndef SPECTRACE_LIGHTS_CL
#define SPECTRACE_LIGHTS_CL

#include "types.h"
#include "spectrum.cl"
#include "sampling.cl"

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

/* Radiance leaving the light's surface toward `to_viewer` (unit), whose geometric normal is n. */
inline float4 light_emitted(__global const Light *light, __global const float *spectra, const SampledWavelengths *w,
                            float3 n, float3 to_viewer)
{
    if (!light->two_sided && dot(n, to_viewer) <= 0.0f) return (float4)(0.0f);
    return light->scale * spectrum_at(spectra, light->radiance_offset, w);
}

/* Solid-angle density of reaching a light point at `distance` whose normal makes |cos| with the ray. */
inline float light_pdf_solid_angle(__global const Light *light, float distance, float abs_cos_light)
{
    if (abs_cos_light <= 0.0f) return 0.0f;
    return light->pmf * distance * distance / (light->area * abs_cos_light);
}

inline float3 triangle_normal(__global const float4 *triangle_vertices, int triangle)
{
    float3 v0 = triangle_vertices[3 * triangle].xyz;
    return normalize(cross(triangle_vertices[3 * triangle + 1].xyz - v0, triangle_vertices[3 * triangle + 2].xyz - v0));
}

inline float3 triangle_point(__global const float4 *triangle_vertices, int triangle, float2 b12)
{
    float3 v0 = triangle_vertices[3 * triangle].xyz;
    float3 v1 = triangle_vertices[3 * triangle + 1].xyz;
    float3 v2 = triangle_vertices[3 * triangle + 2].xyz;
    return (1.0f - b12.x - b12.y) * v0 + b12.x * v1 + b12.y * v2;
}

#endif
