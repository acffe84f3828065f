/* Metal: reflection weighted by the exact conductor Fresnel term of a complex index of refraction η(λ) + i k(λ)
 * (fresnel.cl), per wavelength, times an optional specular tint. Smooth (α < GGX_SMOOTH_ALPHA): a delta lobe,
 * f = F(cos θo) δ(ωi − reflect(ωo)) / cos θi. Rough: the microfacet BRDF (GGX or Beckmann)
 *     f = F(ωo·h) D(h) G2(ωo, ωi) / (4 cos θo cos θi),   h = (ωo + ωi) / |ωo + ωi|,
 * sampled as microfacet.cl samples normals. Single scattering only: light that would bounce between
 * microfacets is lost, so a rough conductor with F = 1 reflects less than 1 (increasingly with α). */
#ifndef SPECTRACE_BSDF_CONDUCTOR_CL
#define SPECTRACE_BSDF_CONDUCTOR_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "fresnel.cl"
#include "microfacet.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 eta;
    float4 k;
    float4 tint;
    float alpha;
    int distribution;  /* MICROFACET_* */
} ConductorParams;

inline int conductor_flags(__global const Material *m)
{
    return ggx_lobe_flags(m);
}

inline ConductorParams conductor_params(__global const Material *m, const SurfaceContext *sc,
                                        const SampledWavelengths *w)
{
    ConductorParams p;
    p.eta = spectrum_at(sc->buffers.spectra, m->eta_offset, w);
    p.k = spectrum_at(sc->buffers.spectra, m->k_offset, w);
    p.tint = m->reflectance_offset == MATERIAL_NO_SPECTRUM
                 ? (float4)(1.0f)
                 : surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    p.distribution = m->distribution;
    return p;
}

inline float4 conductor_fresnel(const ConductorParams *p, float cos_i)
{
    return p->tint * fresnel_conductor(cos_i, p->eta, p->k);
}

inline float4 conductor_eval(const ConductorParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha) || wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    float3 h = reflection_half_vector(wo, wi);
    return conductor_fresnel(p, dot(wo, h)) * microfacet_reflection_cos(wo, wi, p->alpha, p->distribution);
}

inline float conductor_pdf(const ConductorParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha) || wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    return microfacet_reflection_pdf(wo, reflection_half_vector(wo, wi), p->alpha, p->distribution);
}

inline int conductor_sample(const ConductorParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (ggx_is_smooth(p->alpha)) return delta_sample(reflect_local(wo), conductor_fresnel(p, wo.z), 1.0f, s);
    if (wo.z <= 0.0f) return 0;
    float3 wi = microfacet_reflect(wo, microfacet_sample_normal(wo, p->alpha, p->distribution, u));
    if (wi.z <= 0.0f) return 0;
    return continuous_sample(wi, conductor_eval(p, wo, wi), conductor_pdf(p, wo, wi), s);
}

#endif
