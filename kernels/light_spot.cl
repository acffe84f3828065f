/* A spot light (pbrt-v4's SpotLight; Mitsuba 3's spot): a point light at Light.position emitting into the cone of
 * half-angle acos(Light.cos_cutoff) about the unit axis Light.direction, with intensity I(λ), W/(sr nm), times the
 * light's scale on the axis, full within acos(Light.cos_falloff_start) and falling to 0 at the cutoff, optionally
 * through a slide (Light.texture, a reflectance texture). A delta position, as light_point.cl; its light paths
 * leave in directions uniform within the cutoff cone. */
#ifndef SPECTRACE_LIGHT_SPOT_CL
#define SPECTRACE_LIGHT_SPOT_CL

#include "light_point.cl"
#include "light_slide_frame.cl"

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
 * projected over the cone at uv = (0.5, 0.5) + ½ (x, y) / (z tan θ_cutoff) in the light's frame (light_slide_frame.cl:
 * z its axis, y = z × x down the image). Looked up at its finest level.
 * Contract: light->texture is a reflectance texture, d unit and leaving the light; 0 behind the light. */
inline float4 spot_slide(__global const Light *light, const TextureBuffers *textures, const SampledWavelengths *w,
                         float3 d)
{
    float3 x, y, z;
    light_slide_frame(light, &x, &y, &z);
    float cos_theta = dot(d, z);
    if (!(cos_theta > 0.0f)) return (float4)(0.0f);
    float tan_cutoff = sqrt(fmax(0.0f, 1.0f - light->cos_cutoff * light->cos_cutoff)) / light->cos_cutoff;
    float2 uv = 0.5f + 0.5f * (float2)(dot(d, x), dot(d, y)) / (cos_theta * tan_cutoff);
    return texture_spectrum(textures, light->texture, uv, 0.0f, w);
}

/* Next-event estimation from p: s->arriving the irradiance I·falloff/d² (through the slide), s->pdf the pick
 * probability. Returns 0 outside the cone. */
inline int light_spot_sample_li(__global const Light *light, const LightBuffers *buffers,
                                const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    float d2 = point_light_toward(light, p, s);
    if (!(d2 > 0.0f)) return 0;
    float falloff = spot_falloff(light, dot(-s->wi, light->direction.xyz));
    s->arriving = light_spectrum(light, buffers->spectra, w) * (falloff / d2);
    if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) {
        s->arriving *= spot_slide(light, &buffers->textures, w, -s->wi);
    }
    s->pdf = light->pmf;
    s->is_delta = 1;
    return falloff > 0.0f;
}

/* A light path's direction, uniform within the cutoff cone, into *d: returns the intensity along it over that
 * direction's density, I·falloff(θ)·2π(1 − cos θ_cutoff) (through the slide). */
inline float4 light_spot_sample_le(__global const Light *light, const LightBuffers *buffers,
                                   const SampledWavelengths *w, float2 u, float3 *d)
{
    float4 intensity = light_spectrum(light, buffers->spectra, w);
    float3 axis = light->direction.xyz;
    *d = sample_uniform_cone_about(axis, light->cos_cutoff, u);
    float solid_angle = TWO_PI * (1.0f - light->cos_cutoff);
    intensity *= spot_falloff(light, dot(*d, axis)) * solid_angle;
    if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) {
        intensity *= spot_slide(light, &buffers->textures, w, *d);
    }
    return intensity;
}

/* A direction leaving the light, as light_spot_sample_le draws it, and its density per steradian. */
inline float3 light_spot_sample_direction(__global const Light *light, __global const float4 *texels, float2 u)
{
    return sample_uniform_cone_about(light->direction.xyz, light->cos_cutoff, u);
}

inline float light_spot_pdf_direction(__global const Light *light, __global const float4 *texels, float3 d)
{
    if (dot(d, light->direction.xyz) < light->cos_cutoff) return 0.0f;
    return 1.0f / (TWO_PI * (1.0f - light->cos_cutoff));
}

/* The intensity, W/(sr nm), the light sends along unit d: the falloff's share, through the slide. */
inline float4 light_spot_intensity(__global const Light *light, const TextureBuffers *textures,
                                   const SampledWavelengths *w, float3 d)
{
    float4 intensity = light_spectrum(light, textures->spectra, w);
    intensity *= spot_falloff(light, dot(d, light->direction.xyz));
    if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) intensity *= spot_slide(light, textures, w, d);
    return intensity;
}

#endif
