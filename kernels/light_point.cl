/* An isotropic point light (pbrt-v4's PointLight): intensity I(λ), W/(sr nm), times the light's scale, from
 * Light.position, the same in every direction. A delta position: reached only by next-event estimation, where it
 * gives the irradiance I/d² on a surface facing it; its light paths leave in directions uniform over the sphere.
 * Also the part every light at a point shares (light_spot.cl). */
#ifndef SPECTRACE_LIGHT_POINT_CL
#define SPECTRACE_LIGHT_POINT_CL

#include "light_sample.cl"

/* The geometry of next-event estimation from p toward the light's position: fills s->wi, distance and point and
 * returns d², or returns it (not positive) leaving s as it was when p is the light's position. */
inline float point_light_toward(__global const Light *light, float3 p, LightSample *s)
{
    float3 to_light = light->position.xyz - p;
    float d2 = dot(to_light, to_light);
    if (!(d2 > 0.0f)) return d2;
    float d = sqrt(d2);
    s->wi = to_light / d;
    s->distance = d;
    s->point = light->position.xyz;
    return d2;
}

/* Next-event estimation from p: s->arriving the irradiance I/d², s->pdf the pick probability. */
inline int light_point_sample_li(__global const Light *light, const LightBuffers *buffers,
                                 const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    float d2 = point_light_toward(light, p, s);
    if (!(d2 > 0.0f)) return 0;
    s->arriving = light_spectrum(light, buffers->spectra, w) * (1.0f / d2);
    s->pdf = light->pmf;
    s->is_delta = 1;
    return 1;
}

/* A light path's direction, uniform over the sphere, into *d: returns the intensity over that direction's density,
 * I·4π. */
inline float4 light_point_sample_le(__global const Light *light, const LightBuffers *buffers,
                                    const SampledWavelengths *w, float2 u, float3 *d)
{
    float4 intensity = light_spectrum(light, buffers->spectra, w);
    *d = sample_uniform_sphere(u);
    intensity *= 4.0f * PI_F;
    return intensity;
}

/* A direction leaving the light, as light_point_sample_le draws it, and its density per steradian. */
inline float3 light_point_sample_direction(__global const Light *light, __global const float4 *texels, float2 u)
{
    return sample_uniform_sphere(u);
}

inline float light_point_pdf_direction(__global const Light *light, __global const float4 *texels, float3 d)
{
    return 1.0f / (4.0f * PI_F);
}

/* The intensity, W/(sr nm), the light sends along unit d. */
inline float4 light_point_intensity(__global const Light *light, const TextureBuffers *textures,
                                    const SampledWavelengths *w, float3 d)
{
    return light_spectrum(light, textures->spectra, w);
}

#endif
