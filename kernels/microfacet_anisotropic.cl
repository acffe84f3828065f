/* The anisotropic GGX (Trowbridge–Reitz) and Beckmann distributions of microfacet normals in the local shading
 * frame (+z = normal, x = the frame's tangent), with widths αx along x and αy along y (dimensionless); αx = αy is
 * microfacet.cl's isotropic distribution.
 *   D(h) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²),   normalised so that ∫ D(h) cos θh dh = 1;
 *   Λ(ω) = (√(1 + (αx² ωx² + αy² ωy²)/ωz²) − 1) / 2, Smith's height-correlated G2 = 1/(1 + Λ(ωo) + Λ(ωi)).
 * Sources: Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (eqs. 85–86);
 * visible normals by stretching the view into the α = 1 configuration, sampling there and unstretching (Heitz
 * 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)), which is microfacet.cl's sampler at α = 1.
 * Beckmann: D(h) = exp(−(hx²/αx² + hy²/αy²)/hz²) / (π αx αy hz⁴); its Λ(ω) is the isotropic Λ at α = 1 of the
 * direction stretched by (αx, αy, 1), and D(h) cos θh is sampled by stretching an α = 1 normal's slopes (Heitz
 * 2014, sec. 5.3: every Smith distribution of this shape is the stretched isotropic one).
 * Contract: directions are unit vectors; functions of one direction use |ωz|, so a direction below the surface
 * (transmission) is masked as its mirror image is. */
#ifndef SPECTRACE_MICROFACET_ANISOTROPIC_CL
#define SPECTRACE_MICROFACET_ANISOTROPIC_CL

#include "microfacet.cl"

inline float ggx_aniso_d(float3 h, float2 alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float x = h.x / alpha.x, y = h.y / alpha.y;
    float t = x * x + y * y + h.z * h.z;
    return 1.0f / (M_PI_F * alpha.x * alpha.y * t * t);
}

inline float ggx_aniso_lambda(float3 w, float2 alpha)
{
    float cos2 = w.z * w.z;
    if (cos2 <= 0.0f) return INFINITY;
    float x = alpha.x * w.x, y = alpha.y * w.y;
    return 0.5f * (sqrt(1.0f + (x * x + y * y) / cos2) - 1.0f);
}

inline float ggx_aniso_g1(float3 w, float2 alpha)
{
    return 1.0f / (1.0f + ggx_aniso_lambda(w, alpha));
}

inline float ggx_aniso_g2(float3 wo, float3 wi, float2 alpha)
{
    return 1.0f / (1.0f + ggx_aniso_lambda(wo, alpha) + ggx_aniso_lambda(wi, alpha));
}

/* A normal from those visible from wo (wo.z > 0): density G1(wo) max(0, wo·h) D(h) / wo.z. */
inline float3 ggx_aniso_sample_visible_normal(float3 wo, float2 alpha, float2 u)
{
    float3 stretched = normalize((float3)(alpha.x * wo.x, alpha.y * wo.y, wo.z));
    float3 n = ggx_sample_visible_normal(stretched, 1.0f, u);
    return normalize((float3)(alpha.x * n.x, alpha.y * n.y, fmax(n.z, 1e-6f)));
}

/* The density of a normal drawn by ggx_aniso_sample_visible_normal for wo (wo.z > 0). */
inline float ggx_aniso_visible_pdf(float3 wo, float3 h, float2 alpha)
{
    float wo_h = dot(wo, h);
    if (wo.z <= 0.0f || wo_h <= 0.0f) return 0.0f;
    return ggx_aniso_g1(wo, alpha) * wo_h * ggx_aniso_d(h, alpha) / wo.z;
}

/* ---------------------------------------------------------------- Beckmann */

inline float beckmann_aniso_d(float3 h, float2 alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float cos2 = h.z * h.z;
    float x = h.x / alpha.x, y = h.y / alpha.y;
    return exp(-(x * x + y * y) / cos2) / (M_PI_F * alpha.x * alpha.y * cos2 * cos2);
}

inline float3 microfacet_stretch(float3 w, float2 alpha)
{
    return normalize((float3)(alpha.x * w.x, alpha.y * w.y, w.z));
}

inline float beckmann_aniso_lambda(float3 w, float2 alpha)
{
    if (w.z == 0.0f) return INFINITY;
    return beckmann_lambda(microfacet_stretch(w, alpha), 1.0f);
}

/* ---------------------------------------------------------------- either distribution: the reflection lobe */

inline float microfacet_aniso_d(float3 h, float2 alpha, int distribution)
{
    return microfacet_is_beckmann(distribution) ? beckmann_aniso_d(h, alpha) : ggx_aniso_d(h, alpha);
}

inline float microfacet_aniso_g2(float3 wo, float3 wi, float2 alpha, int distribution)
{
    if (microfacet_is_beckmann(distribution))
        return 1.0f / (1.0f + beckmann_aniso_lambda(wo, alpha) + beckmann_aniso_lambda(wi, alpha));
    return ggx_aniso_g2(wo, wi, alpha);
}

/* A microfacet normal for light leaving toward wo (wo.z > 0): GGX's visible normals, Beckmann's D(h) cos θh (which
 * may face away from wo: microfacet_reflect then loses the pair). */
inline float3 microfacet_aniso_sample_normal(float3 wo, float2 alpha, int distribution, float2 u)
{
    if (microfacet_is_beckmann(distribution)) {
        float3 n = beckmann_sample_normal(1.0f, u);
        return normalize((float3)(alpha.x * n.x, alpha.y * n.y, n.z));
    }
    return ggx_aniso_sample_visible_normal(wo, alpha, u);
}

/* Solid-angle pdf of wi = reflect(wo, h) when h is drawn by microfacet_aniso_sample_normal: its density over
 * 4 wo·h. */
inline float microfacet_aniso_reflection_pdf(float3 wo, float3 h, float2 alpha, int distribution)
{
    float wo_h = dot(wo, h);
    if (wo.z <= 0.0f || wo_h <= 0.0f) return 0.0f;
    float normal_pdf = microfacet_is_beckmann(distribution) ? beckmann_aniso_d(h, alpha) * h.z
                                                            : ggx_aniso_visible_pdf(wo, h, alpha);
    return normal_pdf / (4.0f * wo_h);
}

/* D G2 / (4 cos θo) of the reflection lobe, without its Fresnel factor; zero unless both directions lie above the
 * surface. */
inline float microfacet_aniso_reflection_cos(float3 wo, float3 wi, float2 alpha, int distribution)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float3 h = reflection_half_vector(wo, wi);
    return microfacet_aniso_d(h, alpha, distribution) * microfacet_aniso_g2(wo, wi, alpha, distribution) /
           (4.0f * wo.z);
}

#endif
