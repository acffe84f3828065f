/* A constant environment (pbrt-v4's UniformInfiniteLight; Mitsuba 3's constant): radiance L(λ), W/(m² sr nm),
 * times the light's scale, from every direction at infinity, sampled uniformly over the sphere (pdf 1/(4π) sr⁻¹,
 * times the pick probability). */
#ifndef SPECTRACE_LIGHT_ENVIRONMENT_CL
#define SPECTRACE_LIGHT_ENVIRONMENT_CL

#include "light_sample.cl"

#define LIGHT_ENVIRONMENT_DELTA 0

/* Radiance arriving from direction d (pointing away from the scene). */
inline float4 light_environment_radiance(__global const Light *light, __global const float *spectra,
                                         __global const float4 *texels, const SampledWavelengths *w, float3 d)
{
    return light->scale * spectrum_at(spectra, light->spectrum_offset, w);
}

/* Solid-angle pdf of sampling direction d, times the light's pick probability. */
inline float light_environment_pdf_wi(__global const Light *light, __global const float *map_cdf, float3 d)
{
    return light->pmf * INV_FOUR_PI;
}

/* Samples a direction toward the environment; returns it with its pdf (pick probability included). */
inline float3 light_environment_sample_wi(__global const Light *light, __global const float *map_cdf, float2 u,
                                          float *pdf)
{
    *pdf = light->pmf * INV_FOUR_PI;
    return sample_uniform_sphere(u);
}

inline int light_environment_sample_li(__global const Light *light, const LightBuffers *buffers,
                                       const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    s->wi = light_environment_sample_wi(light, buffers->map_cdf, u, &s->pdf);
    s->arriving = light_environment_radiance(light, buffers->spectra, buffers->texels, w, s->wi);
    return at_infinity_sampled(p, s);
}

#endif
