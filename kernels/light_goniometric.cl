/* A goniometric light (pbrt-v4's GoniometricLight, lights.h): a point light at Light.position whose radiant
 * intensity, W/(sr nm), varies over directions as a grey image in Clarberg's equal-area octahedral mapping
 * (equal_area.cl): I(d) = I(λ)·scale·image(uv(d)), the texel nearest to uv (pbrt-v4 reads it so). The map's frame:
 * z = Light.direction (the image's centre), x at the angle direction.w from the tangent of its orthonormal basis
 * toward the bitangent (as a spot's slide, light_spot.cl), y = z × x, or −(z × x) where Light.linear_falloff marks a
 * mirrored (left-handed) frame. The image: map_width × map_height texels from Light.texel_offset, grey in the red
 * channel; map_width 0: none (isotropic).
 * A delta position, as light_point.cl; light paths leave in directions uniform over the sphere (density 1/(4π)),
 * weighted by I(d)·4π. */
#ifndef SPECTRACE_LIGHT_GONIOMETRIC_CL
#define SPECTRACE_LIGHT_GONIOMETRIC_CL

#include "light_point.cl"
#include "equal_area.cl"

/* I(d), W/(sr nm), along unit d leaving the light. */
inline float4 light_goniometric_intensity(__global const Light *light, const TextureBuffers *textures,
                                          const SampledWavelengths *w, float3 d)
{
    float4 intensity = light_spectrum(light, textures->spectra, w);
    if (light->map_width <= 0) return intensity;
    float3 z = light->direction.xyz, tangent, bitangent;
    orthonormal_basis(z, &tangent, &bitangent);
    float3 x = cos(light->direction.w) * tangent + sin(light->direction.w) * bitangent;
    float3 y = (light->linear_falloff ? -1.0f : 1.0f) * cross(z, x);
    float2 uv = equal_area_sphere_to_square((float3)(dot(d, x), dot(d, y), dot(d, z)));
    int column = clamp((int)(uv.x * (float)light->map_width), 0, light->map_width - 1);
    int row = clamp((int)(uv.y * (float)light->map_height), 0, light->map_height - 1);
    return intensity * textures->texels[4 * (light->texel_offset + row * light->map_width + column)];
}

/* Next-event estimation from p: s->arriving the irradiance I(−wi)/d², s->pdf the pick probability. */
inline int light_goniometric_sample_li(__global const Light *light, const LightBuffers *buffers,
                                       const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    float d2 = point_light_toward(light, p, s);
    if (!(d2 > 0.0f)) return 0;
    s->arriving = light_goniometric_intensity(light, &buffers->textures, w, -s->wi) / d2;
    s->pdf = light->pmf;
    s->is_delta = 1;
    return any(s->arriving != (float4)(0.0f));
}

inline float3 light_goniometric_sample_direction(__global const Light *light, float2 u)
{
    return sample_uniform_sphere(u);
}

inline float light_goniometric_pdf_direction(__global const Light *light, float3 d)
{
    return 1.0f / (4.0f * PI_F);
}

/* A light path's direction into *d, uniform over the sphere: returns I(d)·4π. */
inline float4 light_goniometric_sample_le(__global const Light *light, const LightBuffers *buffers,
                                          const SampledWavelengths *w, float2 u, float3 *d)
{
    *d = sample_uniform_sphere(u);
    return light_goniometric_intensity(light, &buffers->textures, w, *d) * (4.0f * PI_F);
}

#endif
