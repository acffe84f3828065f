/* Isotropic microfacet distributions in the local shading frame (+z = normal), with Smith's height-correlated
 * masking-shadowing (Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces"; Heitz 2014,
 * "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs"). alpha is the roughness parameter α
 * (Mitsuba 3's `alpha`).
 *
 * GGX (Trowbridge-Reitz), sampled through its distribution of visible normals (Heitz 2018, "Sampling the GGX
 * Distribution of Visible Normals", JCGT 7(4)), and Beckmann, with the rational approximation of its Smith Λ and
 * the classic sampling of D(h) cos θh (Walter et al. 2007, eqs. 25-28). The microfacet_* functions take the
 * distribution (MICROFACET_*, Material.distribution); a scene without a Beckmann lobe builds with
 * SCENE_HAS_BECKMANN 0 (scene_features.h), and they are then the GGX functions themselves. */
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

/* ---------------------------------------------------------------- Beckmann (Walter et al. 2007, sec. 5.1) */

/* D(h) = exp(−tan²θh / α²) / (π α² cos⁴θh), normalised so that ∫ D(h) cos θh dh = 1. */
inline float beckmann_d(float3 h, float alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float cos2 = h.z * h.z;
    float a2 = alpha * alpha;
    float tan2 = fmax(1.0f - cos2, 0.0f) / cos2;
    return exp(-tan2 / a2) / (M_PI_F * a2 * cos2 * cos2);
}

/* Smith's Λ(ω) for Beckmann, with a = 1 / (α tan θ): the rational approximation
 * (1 − 1.259 a + 0.396 a²) / (3.535 a + 2.181 a²) for a < 1.6, else 0 (Walter et al. 2007, eq. 27, written as Λ:
 * G1 = 1 / (1 + Λ)). Its largest error against the exact (erf(a) − 1)/2 + exp(−a²)/(2 a √π) is below 0.5 % of G1. */
inline float beckmann_lambda(float3 w, float alpha)
{
    float cos2 = w.z * w.z;
    if (cos2 <= 0.0f) return INFINITY;
    float tan2 = fmax(1.0f - cos2, 0.0f) / cos2;
    if (tan2 <= 0.0f) return 0.0f;
    float a = 1.0f / (alpha * sqrt(tan2));
    if (a >= 1.6f) return 0.0f;
    return (1.0f - 1.259f * a + 0.396f * a * a) / (3.535f * a + 2.181f * a * a);
}

/* A microfacet normal with density D(h) cos θh: tan²θh = −α² ln(1 − u.x), φ = 2π u.y (Walter et al. 2007,
 * eq. 28). Unlike visible-normal sampling it may give normals that face away from ωo (the caller rejects them). */
inline float3 beckmann_sample_normal(float alpha, float2 u)
{
    float tan2 = -alpha * alpha * log1p(-fmin(u.x, 0.99999994f));
    float cos_theta = rsqrt(1.0f + tan2);
    float sin_theta = sqrt(fmax(1.0f - cos_theta * cos_theta, 0.0f));
    float2 cs = cos_sin_turns(u.y);
    return (float3)(sin_theta * cs.x, sin_theta * cs.y, cos_theta);
}

/* ---------------------------------------------------------------- either distribution */

/* 1 for a Beckmann lobe; a constant 0 in a scene that has none, so that only the GGX code is compiled. */
inline int microfacet_is_beckmann(int distribution)
{
    return SCENE_HAS_BECKMANN && distribution == MICROFACET_BECKMANN;
}

inline float microfacet_d(float3 h, float alpha, int distribution)
{
    return microfacet_is_beckmann(distribution) ? beckmann_d(h, alpha) : ggx_d(h, alpha);
}

inline float microfacet_g1(float3 w, float alpha, int distribution)
{
    return microfacet_is_beckmann(distribution) ? 1.0f / (1.0f + beckmann_lambda(w, alpha)) : ggx_g1(w, alpha);
}

inline float microfacet_g2(float3 wo, float3 wi, float alpha, int distribution)
{
    if (microfacet_is_beckmann(distribution))
        return 1.0f / (1.0f + beckmann_lambda(wo, alpha) + beckmann_lambda(wi, alpha));
    return ggx_g2(wo, wi, alpha);
}

/* A microfacet normal for light leaving toward wo (wo.z > 0): GGX's visible normals, Beckmann's D(h) cos θh. */
inline float3 microfacet_sample_normal(float3 wo, float alpha, int distribution, float2 u)
{
    return microfacet_is_beckmann(distribution) ? beckmann_sample_normal(alpha, u)
                                                : ggx_sample_visible_normal(wo, alpha, u);
}

/* The density of the normal h that microfacet_sample_normal draws for wo (wo.z > 0, wo_h = wo·h > 0):
 * G1(wo) wo·h D(h) / wo.z for GGX's visible normals, D(h) cos θh for Beckmann. */
inline float microfacet_normal_pdf(float3 wo, float3 h, float wo_h, float alpha, int distribution)
{
    if (microfacet_is_beckmann(distribution)) return beckmann_d(h, alpha) * h.z;
    return ggx_g1(wo, alpha) * wo_h * ggx_d(h, alpha) / wo.z;
}

/* Solid-angle pdf of wi = reflect(wo, h) when h is drawn by microfacet_sample_normal: that density over
 * 4 wo·h (for GGX, ggx_reflection_pdf). */
inline float microfacet_reflection_pdf(float3 wo, float3 h, float alpha, int distribution)
{
    if (!microfacet_is_beckmann(distribution)) return ggx_reflection_pdf(wo, h, alpha);
    float wo_h = dot(wo, h);
    if (wo.z <= 0.0f || wo_h <= 0.0f) return 0.0f;
    return beckmann_d(h, alpha) * h.z / (4.0f * wo_h);
}

/* D G2 / (4 cos θo) of the reflection lobe (for GGX, ggx_reflection_cos). */
inline float microfacet_reflection_cos(float3 wo, float3 wi, float alpha, int distribution)
{
    if (!microfacet_is_beckmann(distribution)) return ggx_reflection_cos(wo, wi, alpha);
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float3 h = reflection_half_vector(wo, wi);
    return beckmann_d(h, alpha) * microfacet_g2(wo, wi, alpha, distribution) / (4.0f * wo.z);
}

/* The reflection of wo about a normal drawn by microfacet_sample_normal; its z is ≤ 0 when the pair is lost (the
 * normal faces away from wo, or the reflection points below the surface). */
inline float3 microfacet_reflect(float3 wo, float3 h)
{
    float wo_h = dot(wo, h);
    return wo_h > 0.0f ? 2.0f * wo_h * h - wo : (float3)(0.0f);
}

#endif
