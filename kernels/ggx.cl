/* The GGX (Trowbridge–Reitz) microfacet distribution with Smith masking, in a local frame whose +z is the
 * macro-surface normal; α is the roughness (isotropic). Walter et al. 2007, "Microfacet Models for Refraction
 * through Rough Surfaces"; Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs";
 * Heitz 2018, "Sampling the GGX Distribution of Visible Normals". Microfacet normals always lie in z > 0. */
#ifndef SPECTRACE_GGX_CL
#define SPECTRACE_GGX_CL

#include "sampling.cl"

/* D(h) = 1 / (π α² cos⁴θ (1 + tan²θ/α²)²), written without trigonometry so it stays finite at the pole. */
inline float ggx_ndf(float3 h, float alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
    return 1.0f / (M_PI_F * a2 * t * t);
}

/* Smith's Λ(ω) = (−1 + √(1 + α² tan²θ)) / 2; it depends on |tan θ| only, so both sides of the surface share it. */
inline float ggx_lambda(float3 w, float alpha)
{
    float cos2 = w.z * w.z;
    if (cos2 <= 0.0f) return INFINITY;
    float tan2 = fmax(1.0f - cos2, 0.0f) / cos2;
    return 0.5f * (sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}

inline float ggx_g1(float3 w, float alpha)
{
    return 1.0f / (1.0f + ggx_lambda(w, alpha));
}

/* Height-correlated masking-shadowing G2 = 1 / (1 + Λ(ωo) + Λ(ωi)) (Heitz 2014, eq. 99), for reflection and for
 * transmission alike: it is symmetric in its arguments, which reciprocity needs. */
inline float ggx_g(float3 wo, float3 wi, float alpha)
{
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/* Density of visible normals seen from wo (wo.z > 0): D_wo(h) = G1(wo) max(0, wo·h) D(h) / cos θo. */
inline float ggx_visible_ndf(float3 wo, float3 h, float alpha)
{
    float wo_dot_h = dot(wo, h);
    if (wo.z <= 0.0f || wo_dot_h <= 0.0f) return 0.0f;
    return ggx_g1(wo, alpha) * wo_dot_h * ggx_ndf(h, alpha) / wo.z;
}

/* A microfacet normal distributed by D_wo (Heitz 2018, listing 1): stretch the view to the α = 1 configuration,
 * sample the projected hemisphere seen from it, unstretch. wo.z > 0. */
inline float3 ggx_sample_visible_normal(float3 wo, float alpha, float2 u)
{
    float3 v = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = v.x * v.x + v.y * v.y;
    float3 t1 = len2 > 0.0f ? (float3)(-v.y, v.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(v, t1);
    float r = sqrt(u.x);
    float phi = TWO_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5f * (1.0f + v.z);
    p2 = (1.0f - s) * sqrt(fmax(1.0f - p1 * p1, 0.0f)) + s * p2;
    float3 n = p1 * t1 + p2 * t2 + sqrt(fmax(1.0f - p1 * p1 - p2 * p2, 0.0f)) * v;
    return normalize((float3)(alpha * n.x, alpha * n.y, fmax(n.z, 1e-7f)));
}

#endif
