/* Metal: reflection weighted by the exact conductor Fresnel term of a complex index of refraction η(λ) + i k(λ)
 * (fresnel.cl), per wavelength, times an optional specular tint. Smooth (α < GGX_SMOOTH_ALPHA): a delta lobe,
 * f = F(cos θo) δ(ωi − reflect(ωo)) / cos θi. Rough: the microfacet BRDF (GGX or Beckmann)
 *     f = F(ωo·h) D(h) G2(ωo, ωi) / (4 cos θo cos θi),   h = (ωo + ωi) / |ωo + ωi|,
 * sampled as microfacet.cl samples normals. Single scattering only: light that would bounce between
 * microfacets is lost, so a rough conductor with F = 1 reflects less than 1 (increasingly with α).
 * Anisotropic (a row with Material.tangent_frame): α along the frame's x (dp/du) is Material.alpha, α along y
 * Material.ior (its texture in transmittance_offset), each at least GGX_SMOOTH_ALPHA, and the lobe is
 * microfacet_anisotropic.cl's; a delta lobe where both lie below that limit. An isotropic row keeps the isotropic
 * code, so its renders do not change. */
#ifndef SPECTRACE_BSDF_CONDUCTOR_CL
#define SPECTRACE_BSDF_CONDUCTOR_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "fresnel.cl"
#include "microfacet.cl"
#include "microfacet_anisotropic.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 eta;
    float4 k;
    float4 tint;
    float alpha;
    int distribution;  /* MICROFACET_* */
#if SCENE_HAS_TANGENT_FRAMES
    int anisotropic;   /* 1: alpha along x and alpha_v along y */
    float alpha_v;
#endif
} ConductorParams;

inline int conductor_flags(__global const Material *m)
{
#if SCENE_HAS_TANGENT_FRAMES
    if (m->tangent_frame) {
        /* As ggx_lobe_flags, with the larger of the two (largest) widths. */
        if (ggx_is_smooth(fmax(m->alpha, m->ior))) return BSDF_DELTA;
        int textured = SCENE_HAS_TEXTURES && (m->roughness_texture != NO_TEXTURE ||
                                              m->transmittance_offset != NO_TEXTURE);
        return textured ? BSDF_NON_DELTA | BSDF_DELTA : BSDF_NON_DELTA;
    }
#endif
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
#if SCENE_HAS_TANGENT_FRAMES
    p.anisotropic = m->tangent_frame;
    p.alpha_v = p.anisotropic ? surface_scalar(sc, m->transmittance_offset, m->ior, w) : p.alpha;
#endif
    return p;
}

/* 1 where the lobe is a delta lobe (every width below the smooth limit). */
inline int conductor_is_smooth(const ConductorParams *p)
{
#if SCENE_HAS_TANGENT_FRAMES
    if (p->anisotropic) return ggx_is_smooth(fmax(p->alpha, p->alpha_v));
#endif
    return ggx_is_smooth(p->alpha);
}

#if SCENE_HAS_TANGENT_FRAMES
inline float2 conductor_alphas(const ConductorParams *p)
{
    return fmax((float2)(p->alpha, p->alpha_v), (float2)(GGX_SMOOTH_ALPHA));
}
#endif

inline float4 conductor_fresnel(const ConductorParams *p, float cos_i)
{
    return p->tint * fresnel_conductor(cos_i, p->eta, p->k);
}

inline float4 conductor_eval(const ConductorParams *p, float3 wo, float3 wi)
{
    if (conductor_is_smooth(p) || wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    float3 h = reflection_half_vector(wo, wi);
#if SCENE_HAS_TANGENT_FRAMES
    if (p->anisotropic)
        return conductor_fresnel(p, dot(wo, h)) *
               microfacet_aniso_reflection_cos(wo, wi, conductor_alphas(p), p->distribution);
#endif
    return conductor_fresnel(p, dot(wo, h)) * microfacet_reflection_cos(wo, wi, p->alpha, p->distribution);
}

inline float conductor_pdf(const ConductorParams *p, float3 wo, float3 wi)
{
    if (conductor_is_smooth(p) || wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
#if SCENE_HAS_TANGENT_FRAMES
    if (p->anisotropic)
        return microfacet_aniso_reflection_pdf(wo, reflection_half_vector(wo, wi), conductor_alphas(p),
                                               p->distribution);
#endif
    return microfacet_reflection_pdf(wo, reflection_half_vector(wo, wi), p->alpha, p->distribution);
}

inline int conductor_sample(const ConductorParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (conductor_is_smooth(p)) return delta_sample(reflect_local(wo), conductor_fresnel(p, wo.z), 1.0f, s);
    if (wo.z <= 0.0f) return 0;
#if SCENE_HAS_TANGENT_FRAMES
    float3 h = p->anisotropic ? microfacet_aniso_sample_normal(wo, conductor_alphas(p), p->distribution, u)
                              : microfacet_sample_normal(wo, p->alpha, p->distribution, u);
#else
    float3 h = microfacet_sample_normal(wo, p->alpha, p->distribution, u);
#endif
    float3 wi = microfacet_reflect(wo, h);
    if (wi.z <= 0.0f) return 0;
    return continuous_sample(wi, conductor_eval(p, wo, wi), conductor_pdf(p, wo, wi), s);
}

#endif
