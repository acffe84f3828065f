/* Retroreflector (road signs, cat's eyes): light returns toward where it came from. Built from a rough-specular
 * GGX lobe evaluated with ωi rotated 180° about the normal, ρ(ωi) = (−x, −y, z):
 *     f(ωo, ωi) = R(λ) D(h) G2(ωo, ωi) / (4 cos θo cos θi),   h = (ωo + ρ(ωi)) / |ωo + ρ(ωi)|.
 * Reciprocal: swapping ωo and ωi turns h into ρ(h), and D, G2 and the cosines are unchanged by the rotation.
 * R(λ) ≤ 1 and the GGX lobe loses energy to single scattering, so ∫ f cos ≤ 1. Smooth (α < GGX_SMOOTH_ALPHA): a
 * delta lobe straight back along ωo. Sampling draws h from the visible normals, reflects, then rotates. */
#ifndef SPECTRACE_BSDF_RETROREFLECTOR_CL
#define SPECTRACE_BSDF_RETROREFLECTOR_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "microfacet.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 reflectance;
    float alpha;
} RetroreflectorParams;

inline int retroreflector_flags(__global const Material *m)
{
    return ggx_lobe_flags(m);
}

inline RetroreflectorParams retroreflector_params(__global const Material *m, const SurfaceContext *sc,
                                                  const SampledWavelengths *w)
{
    RetroreflectorParams p;
    p.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    return p;
}

/* The 180° rotation about the normal (its own inverse). */
inline float3 retro_rotate(float3 v)
{
    return (float3)(-v.x, -v.y, v.z);
}

inline float4 retroreflector_eval(const RetroreflectorParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha)) return (float4)(0.0f);
    return p->reflectance * ggx_reflection_cos(wo, retro_rotate(wi), p->alpha);
}

inline float retroreflector_pdf(const RetroreflectorParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha) || wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    return ggx_reflection_pdf(wo, reflection_half_vector(wo, retro_rotate(wi)), p->alpha);
}

inline int retroreflector_sample(const RetroreflectorParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (ggx_is_smooth(p->alpha)) return delta_sample(wo, p->reflectance, 1.0f, s);
    if (wo.z <= 0.0f) return 0;
    float3 h = ggx_sample_visible_normal(wo, p->alpha, u);
    float3 wi = retro_rotate(2.0f * dot(wo, h) * h - wo);
    if (wi.z <= 0.0f) return 0;
    return continuous_sample(wi, retroreflector_eval(p, wo, wi), retroreflector_pdf(p, wo, wi), s);
}

#endif
