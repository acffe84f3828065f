/* Polarised plastic (Baek et al. 2018, "Simultaneous Acquisition of Polarimetric SVBRDF and Normals", as Mitsuba 3's
 * `pplastic`): a rough specular reflection off a dielectric interface of relative index η, plus a diffuse base
 * whose light crosses the interface twice, added rather than layered:
 *     f cos θi = k_s F(ωo·h) D(h) G2(ωo, ωi) / (4 cos θo)  +  ρ/π (1 − F(cos θo)) (1 − F(cos θi)) cos θi,
 * F the smooth dielectric Fresnel reflectance (fresnel.cl), D and G2 the microfacet distribution's (microfacet.cl),
 * k_s an optional specular tint. The sum is not energy conserving (the specular lobe loses what single scattering
 * loses, and the base keeps only what crosses the interface), as Mitsuba 3's. In a polarised render the specular
 * lobe applies the Fresnel Mueller matrix on the microfacet and the diffuse one the two refractions' Mueller
 * matrices about a depolarising base (microfacet_polarized.cl); this file is the unpolarised BSDF they scale, which
 * unpolarised renders use alone, as Mitsuba 3's unpolarised variants do.
 *
 * Frame: local, +z the normal on ωo's side; both directions above the surface (a reflector). Sampling picks the
 * specular lobe with probability s̄ / (s̄ + ρ̄) (the means of k_s and ρ over the path's wavelengths), else the
 * cosine-weighted base, and weights by f cos / the mixture pdf.
 * Row: reflectance_offset / reflectance_texture ρ, transmittance_offset k_s (MATERIAL_NO_SPECTRUM: 1), ior η, alpha
 * and roughness_texture α, distribution. */
#ifndef SPECTRACE_BSDF_PPLASTIC_CL
#define SPECTRACE_BSDF_PPLASTIC_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "fresnel.cl"
#include "microfacet.cl"
#include "sampling.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 diffuse;   /* ρ */
    float4 specular;  /* k_s */
    float eta;
    float alpha;
    int distribution;  /* MICROFACET_* */
} PplasticParams;

inline int pplastic_flags(__global const Material *m)
{
    return BSDF_NON_DELTA;
}

inline PplasticParams pplastic_params(__global const Material *m, const SurfaceContext *sc,
                                      const SampledWavelengths *w)
{
    PplasticParams p;
    p.diffuse = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.specular = m->transmittance_offset == MATERIAL_NO_SPECTRUM
                     ? (float4)(1.0f)
                     : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    p.eta = m->ior;
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    p.distribution = m->distribution;
    return p;
}

/* The specular lobe's f cos θi. */
inline float4 pplastic_specular_eval(const PplasticParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    float3 h = reflection_half_vector(wo, wi);
    return p->specular * (fresnel_dielectric(dot(wo, h), p->eta)
                          * microfacet_reflection_cos(wo, wi, p->alpha, p->distribution));
}

/* The diffuse lobe's f cos θi. */
inline float4 pplastic_diffuse_eval(const PplasticParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    float through = (1.0f - fresnel_dielectric(wo.z, p->eta)) * (1.0f - fresnel_dielectric(wi.z, p->eta));
    return p->diffuse * (through * INV_PI * wi.z);
}

inline float4 pplastic_eval(const PplasticParams *p, float3 wo, float3 wi)
{
    return pplastic_specular_eval(p, wo, wi) + pplastic_diffuse_eval(p, wo, wi);
}

/* Probability of drawing the specular lobe. */
inline float pplastic_specular_probability(const PplasticParams *p)
{
    float s = dot(p->specular, (float4)(0.25f)), d = dot(p->diffuse, (float4)(0.25f));
    return s + d > 0.0f ? s / (s + d) : 1.0f;
}

inline float pplastic_pdf(const PplasticParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float specular = pplastic_specular_probability(p);
    return specular * microfacet_reflection_pdf(wo, reflection_half_vector(wo, wi), p->alpha, p->distribution)
         + (1.0f - specular) * cosine_hemisphere_pdf(wi.z);
}

inline int pplastic_sample(const PplasticParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z <= 0.0f) return 0;
    float3 wi = uc < pplastic_specular_probability(p)
                  ? microfacet_reflect(wo, microfacet_sample_normal(wo, p->alpha, p->distribution, u))
                  : sample_cosine_hemisphere(u);
    if (wi.z <= 0.0f) return 0;
    return continuous_sample(wi, pplastic_eval(p, wo, wi), pplastic_pdf(p, wo, wi), s);
}

#endif
