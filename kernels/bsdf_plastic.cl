/* Plastic: a diffuse base of albedo ρ(λ) under a clear dielectric coat of relative index η (outside → coat),
 * smooth or rough. The model is a sum of two reciprocal lobes,
 *     f = f_coat + c ρ/π (1 − F(cos θi)) (1 − F(cos θo)),   c = s / (1 − F̄),   F̄ = 2∫₀¹ F(μ) μ dμ,
 * where F is the smooth interface's Fresnel reflectance (fresnel_dielectric) and f_coat is the coat's specular
 * reflection: a delta lobe F(cos θo) when smooth, the GGX microfacet lobe F(ωo·h) D G2 / (4 cos θo cos θi) when
 * rough. The base term is symmetric in ωi and ωo, so f is reciprocal; its albedo is c ρ (1 − F(θo)) (1 − F̄).
 * Smooth: with s = 1 the albedo is F(θo) + ρ (1 − F(θo)), exactly 1 for ρ = 1 (a white plastic loses nothing)
 * and less otherwise. Rough: the microfacet coat's albedo can exceed F(θo) by up to 7e-4 near Brewster's angle
 * for small α (measured for η ∈ [1.2, 3], α ∈ [0.01, 1]; for larger α it is lower), so s = 0.998 keeps
 * ∫ f cos dωi ≤ 1. This is the energy-conserving symmetric coupling of Ashikhmin & Shirley 2000 ("An
 * anisotropic Phong BRDF model") with the exact Fresnel term and its exact hemispherical average in place of
 * Schlick's approximation and its 28/23 constant.
 *
 * Internal scattering: c = 1/(1 − F̄) is 1/(η² (1 − F_dr)), the series of light the coat reflects back down to the
 * base (F_dr = 1 − (1 − F̄)/η², its diffuse reflectance from inside) with the radiance's 1/η² on leaving, which is
 * Mitsuba 3's plastic. `nonlinear` (Mitsuba's too) lets the base's albedo into that series: ρ/(1 − ρ F_dr) for
 * ρ/(1 − F_dr). A rough coat with its own transmission (Material.coat_table_offset, spectrace.materials.coat)
 * replaces (1 − F(cos θ)) by the rough interface's tabulated t(cos θ) and F_dr by its R_int, with s = 1: Mitsuba's
 * roughplastic. An optional specular_reflectance (Material.transmittance_offset) multiplies f_coat: Mitsuba 3's
 * tint of the coat's reflection, which leaves the base term as it is.
 *
 * Sampling picks the coat with probability P = F(θo) / (F(θo) + (1 − F(θo)) ρ̄) (ρ̄: the mean base albedo over the
 * path's wavelengths), else the cosine-weighted base lobe; rough plastic reports the mixture pdf
 * P pdf_coat + (1 − P) pdf_base (the one-sample MIS of the two lobes) and weights by f cos / that pdf. */
#ifndef SPECTRACE_BSDF_PLASTIC_CL
#define SPECTRACE_BSDF_PLASTIC_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "fresnel.cl"
#include "microfacet.cl"
#include "spectrum.cl"
#include "texture.cl"

#define PLASTIC_ROUGH_BASE_SCALE 0.998f

typedef struct {
    float4 reflectance;
    float4 coat_tint;  /* multiplies the coat's reflection (Mitsuba 3's specular_reflectance); 1 when not given */
    float eta;
    float alpha;
    float base_scale;  /* c of the header comment */
    int distribution;  /* MICROFACET_* of the rough coat */
    __global const float *coat_table;  /* t(μ) of a rough coat that passes light by its own transmittance
                                          (Material.coat_table_offset), or 0: the smooth interface's 1 − F */
} PlasticParams;

/* The base is diffuse; a smooth coat (anywhere) adds a delta lobe. */
inline int plastic_flags(__global const Material *m)
{
    return ggx_lobe_flags(m) | BSDF_NON_DELTA;
}

inline PlasticParams plastic_params(__global const Material *m, const SurfaceContext *sc,
                                    const SampledWavelengths *w)
{
    PlasticParams p;
    p.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.coat_tint = m->transmittance_offset == MATERIAL_NO_SPECTRUM
                      ? (float4)(1.0f)
                      : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    p.eta = m->ior;
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    float s = ggx_is_smooth(p.alpha) ? 1.0f : PLASTIC_ROUGH_BASE_SCALE;
    float fresnel_average = fresnel_dielectric_average(m->ior);
    p.base_scale = s / (1.0f - fresnel_average);
    p.distribution = m->distribution;
    p.coat_table = 0;
    /* The coat's diffuse reflectance from inside: 1 − (1 − F̄)/η² for a smooth interface (reciprocity with F̄ from
     * outside), R_int of the rough one where its own transmittance is used. */
    float fdr_inside = 1.0f - (1.0f - fresnel_average) / (m->ior * m->ior);
    if (SCENE_HAS_ROUGH_COAT && m->coat_table_offset != MATERIAL_NO_SPECTRUM) {
        /* Light enters and leaves by the rough coat's t(μ), and the internal series sums to 1/(1 − R_int); with
         * the radiance's 1/η² on leaving, c = 1/(η² (1 − R_int)) (the smooth c is this with R_int = F_dr). */
        p.coat_table = sc->buffers.spectra + m->coat_table_offset;
        fdr_inside = m->coat_internal_reflectance;
        p.base_scale = 1.0f / (m->ior * m->ior * (1.0f - fdr_inside));
    }
    if (SCENE_HAS_NONLINEAR_PLASTIC && m->nonlinear) {
        /* Light reflected back down by the coat meets the base again: a geometric series in ρ F_dr, whose sum
         * ρ/(1 − ρ F_dr) replaces ρ/(1 − F_dr), so the base's albedo becomes ρ (1 − F_dr)/(1 − ρ F_dr). */
        p.reflectance = p.reflectance * (1.0f - fdr_inside) / (1.0f - p.reflectance * fdr_inside);
    }
    return p;
}

/* Probability of sampling the coat for light leaving toward wo. */
inline float plastic_coat_probability(const PlasticParams *p, float3 wo)
{
    float f = fresnel_dielectric(wo.z, p->eta);
    float base = (1.0f - f) * dot(p->reflectance, (float4)(0.25f));
    return f + base > 0.0f ? f / (f + base) : 1.0f;
}

/* t(μ) of a rough coat, interpolated linearly in its table. */
inline float plastic_coat_transmittance(const PlasticParams *p, float mu)
{
    float x = clamp(mu, 0.0f, 1.0f) * (float)(GRID_SAMPLES - 1);
    int i = min((int)x, GRID_SAMPLES - 2);
    return mix(p->coat_table[i], p->coat_table[i + 1], x - (float)i);
}

inline float4 plastic_base_eval(const PlasticParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    if (SCENE_HAS_ROUGH_COAT && p->coat_table) {
        float through = plastic_coat_transmittance(p, wi.z) * plastic_coat_transmittance(p, wo.z);
        return p->reflectance * (p->base_scale * through * INV_PI * wi.z);
    }
    float transmitted = (1.0f - fresnel_dielectric(wi.z, p->eta)) * (1.0f - fresnel_dielectric(wo.z, p->eta));
    return p->reflectance * (p->base_scale * transmitted * INV_PI * wi.z);
}

inline float4 plastic_coat_eval(const PlasticParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha) || wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    float3 h = reflection_half_vector(wo, wi);
    return p->coat_tint * (fresnel_dielectric(dot(wo, h), p->eta)
                           * microfacet_reflection_cos(wo, wi, p->alpha, p->distribution));
}

inline float4 plastic_eval(const PlasticParams *p, float3 wo, float3 wi)
{
    return plastic_base_eval(p, wo, wi) + plastic_coat_eval(p, wo, wi);
}

inline float plastic_pdf(const PlasticParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float coat = plastic_coat_probability(p, wo);
    float pdf = (1.0f - coat) * wi.z * INV_PI;
    if (!ggx_is_smooth(p->alpha))
        pdf += coat * microfacet_reflection_pdf(wo, reflection_half_vector(wo, wi), p->alpha, p->distribution);
    return pdf;
}

inline int plastic_sample(const PlasticParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z <= 0.0f) return 0;
    float coat = plastic_coat_probability(p, wo);
    float3 wi;
    if (uc < coat) {
        if (ggx_is_smooth(p->alpha)) {
            return delta_sample(reflect_local(wo), p->coat_tint * (fresnel_dielectric(wo.z, p->eta) / coat), coat, s);
        }
        wi = microfacet_reflect(wo, microfacet_sample_normal(wo, p->alpha, p->distribution, u));
        if (wi.z <= 0.0f) return 0;
    } else {
        wi = sample_cosine_hemisphere(u);
    }
    return continuous_sample(wi, plastic_eval(p, wo, wi), plastic_pdf(p, wo, wi), s);
}

#endif
