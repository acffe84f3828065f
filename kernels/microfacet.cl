/* The isotropic GGX (Trowbridge-Reitz) microfacet distribution in the local shading frame (+z = normal), with
 * Smith's height-correlated masking-shadowing (Walter et al. 2007, "Microfacet Models for Refraction through
 * Rough Surfaces"; Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs") and
 * sampling of the distribution of visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible
 * Normals", JCGT 7(4)). alpha is the roughness parameter α (Mitsuba 3's `alpha`). */
#ifndef SPECTRACE_MICROFACET_CL
#define SPECTRACE_MICROFACET_CL

#include "types.h"
#include "bsdf_sample.cl"
#include "sampling.cl"

/* Below this α a GGX lobe is treated as a delta lobe: narrower lobes lose float precision (pbrt-v4 uses the
 * same threshold). */
#define GGX_SMOOTH_ALPHA 1e-3f

inline int ggx_is_smooth(float alpha)
{
    return alpha < GGX_SMOOTH_ALPHA;
}

/* The lobe flags (bsdf_sample.cl) of material m's GGX lobe. A textured roughness leaves its largest α in m->alpha
 * (host/spectrace/materials): the lobe is a delta lobe only where α is below the limit, so it is one everywhere
 * only when that largest α is, and a rough surface whose texture dips below the limit has delta points as well. */
inline int ggx_lobe_flags(__global const Material *m)
{
    if (ggx_is_smooth(m->alpha)) return BSDF_DELTA;
    return (SCENE_HAS_TEXTURES && m->roughness_texture != NO_TEXTURE) ? BSDF_NON_DELTA | BSDF_DELTA : BSDF_NON_DELTA;
}

/* D(h) = α² / (π ((α² − 1) cos²θh + 1)²), normalised so that ∫ D(h) cos θh dh = 1. */
inline float ggx_d(float3 h, float alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float t = mad(h.z * h.z, a2 - 1.0f, 1.0f);
    return a2 / (M_PI_F * t * t);
}

/* Smith's Λ(ω) = (−1 + √(1 + α² tan²θ)) / 2. */
inline float ggx_lambda(float3 w, float alpha)
{
    float cos2 = w.z * w.z;
    if (cos2 <= 0.0f) return INFINITY;
    float tan2 = fmax(1.0f - cos2, 0.0f) / cos2;
    return 0.5f * (sqrt(mad(alpha * alpha, tan2, 1.0f)) - 1.0f);
}

inline float ggx_g1(float3 w, float alpha)
{
    return 1.0f / (1.0f + ggx_lambda(w, alpha));
}

/* Height-correlated masking-shadowing G2 = 1 / (1 + Λ(ωo) + Λ(ωi)). */
inline float ggx_g2(float3 wo, float3 wi, float alpha)
{
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/* A microfacet normal from the normals visible from wo (wo.z > 0), with density
 * D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo.z (Heitz 2018, listing 1). */
inline float3 ggx_sample_visible_normal(float3 wo, float alpha, float2 u)
{
    float3 v = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = v.x * v.x + v.y * v.y;
    float3 t1 = len2 > 0.0f ? (float3)(-v.y, v.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(v, t1);
    float r = sqrt(u.x);
    float2 disk = r * cos_sin_turns(u.y);
    float p1 = disk.x;
    float p2 = disk.y;
    float s = 0.5f * (1.0f + v.z);
    p2 = mad(1.0f - s, sqrt(fmax(1.0f - p1 * p1, 0.0f)), s * p2);
    float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(1.0f - p1 * p1 - p2 * p2, 0.0f)) * v;
    return normalize((float3)(alpha * nh.x, alpha * nh.y, fmax(nh.z, 1e-6f)));
}

/* Solid-angle pdf of wi = reflect(wo, h) when h is drawn by ggx_sample_visible_normal:
 * D_wo(h) / (4 wo·h) = G1(wo) D(h) / (4 wo.z). */
inline float ggx_reflection_pdf(float3 wo, float3 h, float alpha)
{
    if (wo.z <= 0.0f) return 0.0f;
    return ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0f * wo.z);
}

/* The half vector of a reflection pair, or 0 when none exists (both directions must lie above the surface). */
inline float3 reflection_half_vector(float3 wo, float3 wi)
{
    float3 h = wo + wi;
    float len2 = dot(h, h);
    return len2 > 0.0f ? h * rsqrt(len2) : (float3)(0.0f);
}

/* f·cos θi of the GGX reflection lobe without its Fresnel factor: D G2 / (4 cos θo). Zero unless both directions
 * lie above the surface. */
inline float ggx_reflection_cos(float3 wo, float3 wi, float alpha)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float3 h = reflection_half_vector(wo, wi);
    return ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0f * wo.z);
}

#endif
