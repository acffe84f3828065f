/* A distant light (pbrt-v4's DistantLight; Mitsuba 3's directional): parallel light travelling along the unit
 * Light.direction from infinitely far away, irradiance E(λ), W/(m² nm), times the light's scale, on a surface facing
 * it. A delta direction: reached only by next-event estimation; its light paths start on a disk across the scene's
 * bounding sphere (light_emission.cl). As a light at infinity (kernels/lights.cl) its "radiance" is that irradiance
 * and the density of its one direction is its pick probability. */
#ifndef SPECTRACE_LIGHT_DISTANT_CL
#define SPECTRACE_LIGHT_DISTANT_CL

#include "light_sample.cl"

#define LIGHT_DISTANT_DELTA 1

inline int light_distant_sample_li(__global const Light *light, const LightBuffers *buffers,
                                   const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    s->wi = -light->direction.xyz;
    s->distance = INFINITY;
    s->point = p;
    s->arriving = light_spectrum(light, buffers->spectra, w);
    s->pdf = light->pmf;
    s->is_delta = 1;
    return 1;
}

/* The direction toward the light, with *pdf its pick probability. */
inline float3 light_distant_sample_wi(__global const Light *light, __global const float *map_cdf, float2 u,
                                      float *pdf)
{
    *pdf = light->pmf;
    return -light->direction.xyz;
}

inline float light_distant_pdf_wi(__global const Light *light, __global const float *map_cdf, float3 d)
{
    return light->pmf;
}

/* The irradiance, W/(m² nm), on a surface facing the light. */
inline float4 light_distant_radiance(__global const Light *light, __global const float *spectra,
                                     __global const float4 *texels, const SampledWavelengths *w, float3 d)
{
    return light_spectrum(light, spectra, w);
}

#endif
