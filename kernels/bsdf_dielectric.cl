/* Dielectric interfaces (glass, water): a smooth one with two delta lobes, Fresnel reflection and Snell
 * refraction, and a rough one, the GGX microfacet BSDF of Walter et al. 2007 sampled through the visible normals
 * (Heitz 2018).
 *
 * Frame: local, +z is the geometric normal pointing to the exterior; ωo and ωi both point away from the surface
 * and may lie on either side. eta = n_interior / n_exterior at the wavelength that steers the path (the hero).
 * Transport: radiance (camera paths). Refraction from index n_i into n_o compresses solid angle, so radiance
 * arriving along ωo is (n_o/n_i)² times that leaving ωi: the BTDF carries that factor, and obeys the generalised
 * reciprocity f_t(ωo, ωi) / n_o² = f_t(ωi, ωo) / n_i² (Veach 1997, sec. 5.2), where n_o is the index of the medium
 * ωo lies in.
 *
 * Every function first turns the frame so ωo lies in z > 0 (the microfacet model is symmetric under that mirror)
 * and works with e = n(side ωo does not lie in) / n(ωo's side). */
#ifndef SPECTRACE_BSDF_DIELECTRIC_CL
#define SPECTRACE_BSDF_DIELECTRIC_CL

#include "bsdf_sample.cl"
#include "fresnel.cl"
#include "ior.cl"
#include "microfacet.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float3 wi;      /* local frame, unit */
    float weight;   /* f(ωo, ωi) |cos θi| / pdf */
    float pdf;      /* solid-angle pdf; for a delta lobe the probability of choosing that lobe */
    int is_delta;
    float radiance_scale;  /* the 1/e² that `weight` carries after refraction, 1 after reflection */
} DielectricSample;

/* e seen from ωo: n on the far side over n on ωo's side. */
inline float dielectric_eta_from(float cos_o, float eta)
{
    return cos_o >= 0.0f ? eta : 1.0f / eta;
}

inline float3 mirror_z(float3 v)
{
    return (float3)(v.x, v.y, -v.z);
}

/* ---------------------------------------------------------------- smooth: two delta lobes */

/* Reflection with probability F, else refraction; each lobe's weight is then f|cos|/pdf = 1 for reflection and
 * (n_o/n_i)² = 1/e² for refraction. */
inline int smooth_dielectric_sample(float3 wo, float eta, float uc, DielectricSample *s)
{
    if (wo.z == 0.0f) return 0;
    float e = dielectric_eta_from(wo.z, eta);
    float cos_t;
    float f = fresnel_dielectric_refracting(fabs(wo.z), e, &cos_t);
    s->is_delta = 1;
    if (uc < f) {
        s->wi = (float3)(-wo.x, -wo.y, wo.z);
        s->weight = 1.0f;
        s->pdf = f;
        s->radiance_scale = 1.0f;
    } else {
        /* Snell: the tangential component shrinks by 1/e, the path crosses to the other side. */
        s->wi = (float3)(-wo.x / e, -wo.y / e, wo.z > 0.0f ? -cos_t : cos_t);
        s->weight = 1.0f / (e * e);
        s->pdf = 1.0f - f;
        s->radiance_scale = s->weight;
    }
    return 1;
}

/* ---------------------------------------------------------------- rough: GGX microfacets (Walter et al. 2007) */

/* The microfacet normal that turns ωo into ωi, in the frame with ωo.z > 0; 0 when the pair cannot be linked
 * (grazing, or a microfacet seen from behind). For refraction h ∝ −(n_o ωo + n_i ωi) (Walter eq. 16). */
inline float3 dielectric_half_vector(float3 wo, float3 wi, float e, int *ok)
{
    int reflection = wi.z > 0.0f;
    float3 h = reflection ? wo + wi : wo + e * wi;
    float len2 = dot(h, h);
    *ok = 0;
    if (wo.z <= 0.0f || wi.z == 0.0f || !(len2 > 0.0f)) return (float3)(0.0f);
    h *= rsqrt(len2);
    if (h.z < 0.0f) h = -h;
    float wo_h = dot(wo, h);
    float wi_h = dot(wi, h);
    /* ωo must see the front of the microfacet, and ωi lie on the microfacet's side its lobe sends it to. */
    if (wo_h <= 0.0f || (reflection ? wi_h <= 0.0f : wi_h >= 0.0f)) return h;
    *ok = 1;
    return h;
}

/* What eval and pdf share for a pair (ωo, ωi): the frame turned so ωo.z > 0, e, the linking microfacet normal
 * and the Fresnel reflectance on it. */
typedef struct {
    float3 wo, wi, h;
    float e;
    float wo_h, wi_h;
    float fresnel;
} RoughDielectricPair;

/* 0 when the pair cannot be linked by a microfacet (then f and pdf are 0). */
inline int rough_dielectric_pair(float3 wo, float3 wi, float eta, RoughDielectricPair *q)
{
    q->e = dielectric_eta_from(wo.z, eta);
    if (wo.z < 0.0f) {
        wo = mirror_z(wo);
        wi = mirror_z(wi);
    }
    int ok;
    q->h = dielectric_half_vector(wo, wi, q->e, &ok);
    if (!ok) return 0;
    q->wo = wo;
    q->wi = wi;
    q->wo_h = dot(wo, q->h);
    q->wi_h = dot(wi, q->h);
    float cos_t;
    q->fresnel = fresnel_dielectric_refracting(q->wo_h, q->e, &cos_t);
    return 1;
}

/* f(ωo, ωi) |cos θi|. Reflection: D G F / (4 |cos θo|) (Walter eq. 20 times cos θi); refraction (eq. 21 times
 * |cos θi|, its n_o² over the squared denominator divided through by n_o²):
 *     D G (1 − F) |ωi·h| (ωo·h) / (|cos θo| (ωo·h + e ωi·h)²). */
inline float rough_dielectric_eval(float3 wo, float3 wi, float eta, float alpha, int distribution)
{
    RoughDielectricPair q;
    if (!rough_dielectric_pair(wo, wi, eta, &q)) return 0.0f;
    float dg = microfacet_d(q.h, alpha, distribution) * microfacet_g2(q.wo, q.wi, alpha, distribution);
    if (q.wi.z > 0.0f) return dg * q.fresnel / (4.0f * q.wo.z);
    float denominator = q.wo_h + q.e * q.wi_h;
    return dg * (1.0f - q.fresnel) * fabs(q.wi_h) * q.wo_h / (q.wo.z * denominator * denominator);
}

/* pdf of rough_dielectric_sample: the density of the sampled normal (GGX: the visible normals' D_wo(h), Heitz 2018)
 * times the lobe choice (F or 1 − F) times the Jacobian of h → ωi: 1 / (4 ωo·h) for reflection,
 * e² |ωi·h| / (ωo·h + e ωi·h)² for refraction (Walter eq. 14, 17). */
inline float rough_dielectric_pdf(float3 wo, float3 wi, float eta, float alpha, int distribution)
{
    RoughDielectricPair q;
    if (!rough_dielectric_pair(wo, wi, eta, &q)) return 0.0f;
    float visible = microfacet_normal_pdf(q.wo, q.h, q.wo_h, alpha, distribution);
    if (q.wi.z > 0.0f) return visible * q.fresnel / (4.0f * q.wo_h);
    float denominator = q.wo_h + q.e * q.wi_h;
    return visible * (1.0f - q.fresnel) * q.e * q.e * fabs(q.wi_h) / (denominator * denominator);
}

/* A microfacet normal (GGX: from the visible normals), then reflection off it with probability F(ωo·h), else
 * refraction through it. The weight f|cos θi|/pdf reduces to G2/G1(ωo) for GGX, times 1/e² for refraction. Returns 0 when the sampled normal faces away from ωo or the sampled direction leaves on the
 * wrong side of the macro-surface (the sample then carries no light). */
inline int rough_dielectric_sample(float3 wo, float eta, float alpha, int distribution, float uc, float2 u,
                                   DielectricSample *s)
{
    if (wo.z == 0.0f) return 0;
    float e = dielectric_eta_from(wo.z, eta);
    int flipped = wo.z < 0.0f;
    if (flipped) wo = mirror_z(wo);

    float3 h = microfacet_sample_normal(wo, alpha, distribution, u);
    float wo_h = dot(wo, h);
    if (wo_h <= 0.0f) return 0;
    float cos_t;
    float f = fresnel_dielectric_refracting(wo_h, e, &cos_t);
    float3 wi;
    int reflection = uc < f;
    if (reflection) {
        wi = 2.0f * wo_h * h - wo;
        if (wi.z <= 0.0f) return 0;
    } else {
        wi = normalize((wo_h / e - cos_t) * h - wo / e);
        if (wi.z >= 0.0f) return 0;
    }
    float weight = ggx_g2(wo, wi, alpha) / ggx_g1(wo, alpha);
    float radiance_scale = reflection ? 1.0f : 1.0f / (e * e);
    weight *= radiance_scale;

    /* In the turned frame ωo.z > 0, so e is the eta the pdf expects. */
    float pdf = rough_dielectric_pdf(wo, wi, e, alpha, distribution);
    /* Beckmann's normals are not the visible ones, so D and G1 do not cancel: the weight is f|cos θi|/pdf itself
     * (radiance factor included), evaluated on the normal that links ωo and ωi as eval and pdf see it. */
    if (microfacet_is_beckmann(distribution))
        weight = pdf > 0.0f ? rough_dielectric_eval(wo, wi, e, alpha, distribution) / pdf : 0.0f;
    s->wi = flipped ? mirror_z(wi) : wi;
    s->weight = weight;
    s->pdf = pdf;
    s->is_delta = 0;
    s->radiance_scale = radiance_scale;
    return pdf > 0.0f;
}

/* ---------------------------------------------------------------- the material: Material row → BSDF */

typedef struct {
    float eta;    /* n_interior / n_exterior at the hero wavelength, which steers the path */
    float alpha;
    float4 tint;  /* optional specular tint on both lobes (1 without one) */
    int distribution;  /* MICROFACET_* */
} DielectricParams;

/* Dispersive when the index depends on λ: then the four wavelengths of a path would leave the surface in different
 * directions, and only the hero may go on (Wilkie et al. 2014; the integrators see to it). */
inline int dielectric_flags(__global const Material *m)
{
    return ggx_lobe_flags(m) | BSDF_TRANSMISSION
         | (material_ior_is_dispersive(m) ? BSDF_DISPERSIVE : 0);
}

inline DielectricParams dielectric_params(__global const Material *m, const SurfaceContext *sc,
                                          const SampledWavelengths *w)
{
    DielectricParams p;
    p.eta = material_ior(m, w->lambda.x);
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    p.tint = m->reflectance_offset == MATERIAL_NO_SPECTRUM
                 ? (float4)(1.0f)
                 : surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.distribution = m->distribution;
    return p;
}

inline float4 dielectric_eval(const DielectricParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha)) return (float4)(0.0f);
    return p->tint * rough_dielectric_eval(wo, wi, p->eta, p->alpha, p->distribution);
}

inline float dielectric_pdf(const DielectricParams *p, float3 wo, float3 wi)
{
    if (ggx_is_smooth(p->alpha)) return 0.0f;
    return rough_dielectric_pdf(wo, wi, p->eta, p->alpha, p->distribution);
}

inline int dielectric_sample(const DielectricParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    DielectricSample d;
    int ok = ggx_is_smooth(p->alpha) ? smooth_dielectric_sample(wo, p->eta, uc, &d)
                                     : rough_dielectric_sample(wo, p->eta, p->alpha, p->distribution, uc, u, &d);
    if (!ok) return 0;
    s->wi = d.wi;
    s->weight = p->tint * d.weight;
    s->pdf = d.pdf;
    s->is_delta = d.is_delta;
    s->radiance_scale = d.radiance_scale;
    return 1;
}

#endif
