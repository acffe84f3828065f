/* A goniometric light (pbrt-v4's GoniometricLight, lights.h): a point light at Light.position whose radiant
 * intensity, W/(sr nm), varies over directions as a grey image in Clarberg's equal-area octahedral mapping
 * (equal_area.cl): I(d) = I(λ)·scale·image(uv(d)), the texel nearest to uv (pbrt-v4 reads it so). The map's frame:
 * a spot's slide's (light_slide_frame.cl), z = Light.direction the image's centre, with y = −(z × x) where
 * Light.linear_falloff marks a mirrored (left-handed) frame. The image: map_width × map_height texels from
 * Light.texel_offset, grey in the red channel; map_width 0: none (isotropic).
 * A delta position, as light_point.cl; light paths leave in directions drawn by the image's table
 * (distribution_2d.cl over the equal-area square, its floats from texel Light.triangle of the texel buffer, ∝ the
 * image), density p(uv)/(4π) per steradian as every cell covers the same solid angle, or uniformly over the sphere
 * (density 1/(4π)) where Light.triangle is NO_DISTRIBUTION (-1); weighted by I(d) over that density. */
#ifndef SPECTRACE_LIGHT_GONIOMETRIC_CL
#define SPECTRACE_LIGHT_GONIOMETRIC_CL

#include "light_point.cl"
#include "equal_area.cl"
#include "distribution_2d.cl"
#include "light_slide_frame.cl"

/* The map's frame (see the header): the slide's, its y turned round where mirrored. */
inline void goniometric_frame(__global const Light *light, float3 *x, float3 *y, float3 *z)
{
    light_slide_frame(light, x, y, z);
    *y *= light->linear_falloff ? -1.0f : 1.0f;
}

/* I(d), W/(sr nm), along unit d leaving the light. */
inline float4 light_goniometric_intensity(__global const Light *light, const TextureBuffers *textures,
                                          const SampledWavelengths *w, float3 d)
{
    float4 intensity = light_spectrum(light, textures->spectra, w);
    if (light->map_width <= 0) return intensity;
    float3 x, y, z;
    goniometric_frame(light, &x, &y, &z);
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

/* A light path's direction, drawn by the image's table (uniformly without one), its density per steradian in *pdf. */
inline float3 light_goniometric_draw_direction(__global const Light *light, __global const float4 *texels, float2 u,
                                               float *pdf)
{
    if (light->triangle < 0) {
        *pdf = 1.0f / (4.0f * PI_F);
        return sample_uniform_sphere(u);
    }
    float row_mass, column_mass;
    float2 uv = distribution_2d_sample((__global const float *)(texels + light->triangle), light->map_width,
                                       light->map_height, u, &row_mass, &column_mass);
    *pdf = row_mass * column_mass * (float)(light->map_width * light->map_height) / (4.0f * PI_F);
    float3 x, y, z, m = equal_area_square_to_sphere(uv);
    goniometric_frame(light, &x, &y, &z);
    return normalize(m.x * x + m.y * y + m.z * z);
}

inline float3 light_goniometric_sample_direction(__global const Light *light, __global const float4 *texels, float2 u)
{
    float pdf;
    return light_goniometric_draw_direction(light, texels, u, &pdf);
}

inline float light_goniometric_pdf_direction(__global const Light *light, __global const float4 *texels, float3 d)
{
    if (light->triangle < 0) return 1.0f / (4.0f * PI_F);
    float3 x, y, z;
    goniometric_frame(light, &x, &y, &z);
    float2 uv = equal_area_sphere_to_square((float3)(dot(d, x), dot(d, y), dot(d, z)));
    return distribution_2d_density((__global const float *)(texels + light->triangle), light->map_width,
                                   light->map_height, uv) / (4.0f * PI_F);
}

/* A light path's direction into *d: returns I(d) over its density. */
inline float4 light_goniometric_sample_le(__global const Light *light, const LightBuffers *buffers,
                                          const SampledWavelengths *w, float2 u, float3 *d)
{
    float pdf;
    *d = light_goniometric_draw_direction(light, buffers->texels, u, &pdf);
    if (!(pdf > 0.0f)) return (float4)(0.0f);
    float4 intensity = light_goniometric_intensity(light, &buffers->textures, w, *d);
    return light->triangle < 0 ? intensity * (4.0f * PI_F) : intensity / pdf;
}

#endif
