/* A projector (Mitsuba 3's `projector`, projector.cpp; pbrt-v4's ProjectionLight, lights.cpp): a point light at
 * Light.position sending an image through a rectangular field of view about the unit axis Light.direction. Its frame
 * is a spot's slide's (light_slide_frame.cl): z the axis, x across the image, y = z × x down it. A direction d meets the plane z = 1 at (x, y) = d.xy/d.z;
 * the image spans |x| <= tan_x = Light.cos_falloff_start, |y| <= tan_y = Light.cos_cutoff there, at
 * uv = (0.5, 0.5) + ½ (x/tan_x, y/tan_y). Radiant intensity, W/(sr nm), I(d) = I(λ)·image(uv)/cos³θ where
 * Light.linear_falloff is set (Mitsuba's profile: the plane z = 1 receives I(λ)·image(uv) in W/(m² nm)), else
 * I(λ)·image(uv) (pbrt-v4's); 0 outside the field and behind the light. Light.texture: the image, a reflectance
 * texture, or NO_TEXTURE for a white one.
 * A delta position, as light_point.cl; light paths leave through a point of the image's rectangle on z = 1 drawn
 * with the density p(uv) of the image's table (distribution_2d.cl; its floats from texel Light.triangle of the
 * texel buffer, Light.map_width × map_height cells, ∝ the image's luminance), or uniformly where Light.triangle is
 * NO_DISTRIBUTION (-1); the solid-angle density is p(uv)/(A cos³θ), A = 4 tan_x tan_y (dω = cos³θ dA on that
 * plane). */
#ifndef SPECTRACE_LIGHT_PROJECTOR_CL
#define SPECTRACE_LIGHT_PROJECTOR_CL

#include "light_point.cl"
#include "distribution_2d.cl"
#include "light_slide_frame.cl"

/* I(d), W/(sr nm), along unit d leaving the light (see the header); 0 outside the field of view. */
inline float4 light_projector_intensity(__global const Light *light, const TextureBuffers *textures,
                                        const SampledWavelengths *w, float3 d)
{
    float3 x, y, z;
    light_slide_frame(light, &x, &y, &z);
    float cos_theta = dot(d, z);
    if (!(cos_theta > 0.0f)) return (float4)(0.0f);
    float2 plane = (float2)(dot(d, x), dot(d, y)) / cos_theta;
    float2 half_size = (float2)(light->cos_falloff_start, light->cos_cutoff);
    if (fabs(plane.x) > half_size.x || fabs(plane.y) > half_size.y) return (float4)(0.0f);
    float4 intensity = light_spectrum(light, textures->spectra, w);
    if (light->linear_falloff) intensity /= cos_theta * cos_theta * cos_theta;
    if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) {
        float2 uv = 0.5f + 0.5f * plane / half_size;
        intensity *= texture_spectrum(textures, light->texture, uv, 0.0f, w);
    }
    return intensity;
}

/* Next-event estimation from p: s->arriving the irradiance I(−wi)/d², s->pdf the pick probability. */
inline int light_projector_sample_li(__global const Light *light, const LightBuffers *buffers,
                                     const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    float d2 = point_light_toward(light, p, s);
    if (!(d2 > 0.0f)) return 0;
    s->arriving = light_projector_intensity(light, &buffers->textures, w, -s->wi) / d2;
    s->pdf = light->pmf;
    s->is_delta = 1;
    return any(s->arriving != (float4)(0.0f));
}

/* A direction through a point of the image's rectangle on the plane z = 1, drawn by the image's table (uniformly
 * without one), and its density per steradian in *pdf (0 outside the field, which a table's point never is). */
inline float3 light_projector_draw_direction(__global const Light *light, __global const float4 *texels, float2 u,
                                             float *pdf)
{
    float3 x, y, z;
    light_slide_frame(light, &x, &y, &z);
    float density_uv = 1.0f, row_mass, column_mass;
    if (light->triangle >= 0) {
        u = distribution_2d_sample((__global const float *)(texels + light->triangle), light->map_width,
                                   light->map_height, u, &row_mass, &column_mass);
        density_uv = row_mass * column_mass * (float)(light->map_width * light->map_height);
    }
    float2 plane = (2.0f * u - 1.0f) * (float2)(light->cos_falloff_start, light->cos_cutoff);
    float3 d = normalize(plane.x * x + plane.y * y + z);
    float cos_theta = dot(d, z);
    float area = 4.0f * light->cos_falloff_start * light->cos_cutoff;
    *pdf = density_uv / (area * cos_theta * cos_theta * cos_theta);
    return d;
}

inline float3 light_projector_sample_direction(__global const Light *light, __global const float4 *texels, float2 u)
{
    float pdf;
    return light_projector_draw_direction(light, texels, u, &pdf);
}

/* Its density per steradian: p(uv)/(A cos³θ) within the field, 0 outside. */
inline float light_projector_pdf_direction(__global const Light *light, __global const float4 *texels, float3 d)
{
    float3 x, y, z;
    light_slide_frame(light, &x, &y, &z);
    float cos_theta = dot(d, z);
    if (!(cos_theta > 0.0f)) return 0.0f;
    float2 half_size = (float2)(light->cos_falloff_start, light->cos_cutoff);
    float2 plane = (float2)(dot(d, x), dot(d, y)) / cos_theta;
    if (fabs(plane.x) > half_size.x || fabs(plane.y) > half_size.y) return 0.0f;
    float density_uv = light->triangle < 0 ? 1.0f
                     : distribution_2d_density((__global const float *)(texels + light->triangle), light->map_width,
                                               light->map_height, 0.5f + 0.5f * plane / half_size);
    float area = 4.0f * half_size.x * half_size.y;
    return density_uv / (area * cos_theta * cos_theta * cos_theta);
}

/* A light path's direction into *d: returns I(d) over its density. */
inline float4 light_projector_sample_le(__global const Light *light, const LightBuffers *buffers,
                                        const SampledWavelengths *w, float2 u, float3 *d)
{
    float pdf;
    *d = light_projector_draw_direction(light, buffers->texels, u, &pdf);
    if (!(pdf > 0.0f)) return (float4)(0.0f);
    return light_projector_intensity(light, &buffers->textures, w, *d) / pdf;
}

#endif
