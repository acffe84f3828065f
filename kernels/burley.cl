/* What the two principled BSDFs (bsdf_principled.cl, bsdf_principledthin.cl) share: Schlick's weight
 * (1 − cos θ)⁵ of Burley's diffuse, sheen and Fresnel terms (Burley 2012, "Physically Based Shading at Disney",
 * sec. 5.3), their diffuse and sheen lobes, and the read of a weight from their parameter blocks. */
#ifndef SPECTRACE_BURLEY_CL
#define SPECTRACE_BURLEY_CL

#include "sampling.cl"
#include "texture.cl"

/* (1 − c)⁵ for c the cosine of an angle, clamped to [0, 1]. */
inline float schlick_weight(float c)
{
    float x = clamp(1.0f - c, 0.0f, 1.0f);
    float x2 = x * x;
    return x2 * x2 * x;
}

/* Weight k of a parameter block (its value at 2k, its texture's index at 2k + 1: spectrace.materials.principled's
 * write_row), clamped to [0, 1]. */
inline float principled_weight(const SurfaceContext *sc, __global const float *block, int k,
                               const SampledWavelengths *w)
{
    return clamp(surface_scalar(sc, (int)block[2 * k + 1], block[2 * k], w), 0.0f, 1.0f);
}

/* `value` plus Burley's diffuse (with its retro-reflection) and then sheen, each times cos θi, for `weight` the
 * share of light they get (added one after the other, as the BSDFs summed them): wo_z, wi_z the cosines of the
 * two directions with the normal, cos_d that of wi with their half vector. The reflectance `base` and the sheen's
 * tint are per wavelength; roughness, sheen and sheen_tint lie in [0, 1]. Contract: weight ≥ 0. */
inline float4 burley_diffuse_sheen(float4 value, float4 base, float4 tint, float roughness, float sheen,
                                   float sheen_tint, float weight, float wo_z, float wi_z, float cos_d)
{
    float fo = schlick_weight(wo_z), fi = schlick_weight(wi_z);
    float rr = 2.0f * roughness * cos_d * cos_d;
    float lambert = (1.0f - 0.5f * fi) * (1.0f - 0.5f * fo) + rr * (fo + fi + fo * fi * (rr - 1.0f));
    value += base * (weight * lambert * INV_PI * wi_z);
    if (sheen > 0.0f) {
        float4 colour = mix((float4)(1.0f), tint, sheen_tint);
        value += colour * (weight * sheen * schlick_weight(cos_d) * wi_z);
    }
    return value;
}

#endif
