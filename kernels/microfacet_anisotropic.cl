/* The anisotropic GGX (Trowbridge–Reitz) distribution of microfacet normals in the local shading frame (+z =
 * normal, x = the frame's tangent), with widths αx along x and αy along y (dimensionless); αx = αy is
 * microfacet.cl's isotropic GGX.
 *   D(h) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²),   normalised so that ∫ D(h) cos θh dh = 1;
 *   Λ(ω) = (√(1 + (αx² ωx² + αy² ωy²)/ωz²) − 1) / 2, Smith's height-correlated G2 = 1/(1 + Λ(ωo) + Λ(ωi)).
 * Sources: Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (eqs. 85–86);
 * visible normals by stretching the view into the α = 1 configuration, sampling there and unstretching (Heitz
 * 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)), which is microfacet.cl's sampler at α = 1.
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

#endif
