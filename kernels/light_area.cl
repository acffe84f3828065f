/* What every area light shares (pbrt-v4's DiffuseAreaLight; Veach 1997, sec. 8.1): a surface emitting radiance
 * L(λ), W/(m² sr nm), times the light's scale, the same in every direction on its emitting side (both sides when
 * two-sided), or an emission texture's at each point. Each shape's device type (light_triangle.cl, light_sphere.cl,
 * light_shape.cl) samples a point on its surface and states that point's densities; the emitted radiance, and the
 * cosine-distributed directions its light paths leave along, are the same for all and written here.
 * Contract: Light.area (m²) and Light.two_sided are set; Light.texture an emission texture or NO_TEXTURE. */
#ifndef SPECTRACE_LIGHT_AREA_CL
#define SPECTRACE_LIGHT_AREA_CL

#include "light_sample.cl"

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

/* Radiance leaving an emitting surface toward `to_viewer` (unit), whose geometric normal is n, at texture
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

/* Next-event estimation's geometry toward the point q (normal n) of an area light from p: fills s->wi, distance,
 * point and normal and returns the distance, or returns it (not positive) leaving s as it was when q is p. */
inline float area_light_toward(float3 p, float3 q, float3 n, LightSample *s)
{
    float3 to_light = q - p;
    float d = length(to_light);
    if (!(d > 0.0f)) return d;
    s->wi = to_light / d;
    s->distance = d;
    s->point = q;
    s->normal = n;
    return d;
}

/* Solid-angle density (pick probability included) of reaching a point of a light sampled uniformly by area at
 * `distance` whose normal makes |cos| with the ray. */
inline float area_light_pdf(__global const Light *light, float distance, float abs_cos_light)
{
    if (abs_cos_light <= 0.0f) return 0.0f;
    return light->pmf * distance * distance / (light->area * abs_cos_light);
}

/* A direction leaving the surface point of normal n, cosine-distributed on the emitting side; a two-sided light
 * picks its side with u.x (each with probability ½, u.x rescaled). *side: ±1, the side's normal is side · n. */
inline float3 area_light_sample_direction(__global const Light *light, float3 n, float2 u, float *side)
{
    *side = 1.0f;
    if (light->two_sided) {
        if (u.x < 0.5f) {
            *side = -1.0f;
            u.x *= 2.0f;
        } else {
            u.x = fmin(2.0f * u.x - 1.0f, 0x1.fffffep-1f);
        }
    }
    return sample_cosine_about(*side * n, u);
}

/* Solid-angle density with which area_light_sample_direction leaves the point of normal n along unit d. */
inline float area_light_pdf_direction(__global const Light *light, float3 n, float3 d)
{
    float c = dot(n, d);
    if (light->two_sided) return fabs(c) * (0.5f / PI_F);
    return c > 0.0f ? c / PI_F : 0.0f;
}

#endif
