/* Hair and fur: the fibre scattering model of Chiang, Bitterli, Tappan & Burley 2016 ("A Practical and Controllable
 * Hair and Fur Model for Production Path Tracing", Computer Graphics Forum 35(2)), in the form pbrt-v4 gives it
 * (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., sec. 9.9: its HairBxDF). A fibre is a
 * dielectric cylinder of index eta with an absorbing interior; light leaves it after p internal paths: R (p = 0,
 * reflection at the surface), TT (1), TRT (2) and a residual for p ≥ 3. Each lobe is a product
 *   Mp(θi, θo)  longitudinal: d'Eon et al. 2011's normalised von Mises-Fisher marginal, variance v_p from β_m,
 *               its peak shifted by the cuticle scales' tilt α (R by −2α, TT by α, TRT by 4α);
 *   Ap(θo, h)   attenuation: Fresnel at the entry point and exp(−σa · 2 cos γt / cos θt) per crossing;
 *   Np(φ)       azimuthal: a logistic of scale s (from β_n) about the deflection Φ(p, γo, γt) of a ray entering at
 *               offset h = sin γo, trimmed to [−π, π].
 * The residual is Mp with v_2 (untilted) times A_3 / 2π. Σ Ap = 1 when σa = 0, and every Mp, Np integrates to 1, so
 * a white fibre scatters all the light it meets (the paper's white furnace).
 *
 * Frame: x along the fibre (the surface's dp/du, Material.tangent_frame), z the surface normal. The fibre's
 * scattering S(ωo, ωi) depends only on angles about x (θ from the normal plane of the fibre: sin θ = ω.x; φ about x)
 * and on h, so it is the same whichever way the frame turns about the fibre. S is what the integrators see as
 * f·|cos θi| (pbrt's f is S / |cos θi|). h ∈ [−1, 1] comes from the v texture coordinate, h = 2v − 1, as pbrt's
 * curves set it (its ribbons' v runs across the fibre); on a curve with Mitsuba 3's coordinates (v along it) from
 * ωo's offset across the fibre in the cross-section, −ωo.y / |(ωo.y, ωo.z)|, as Mitsuba 3's hair takes it
 * (hair_from_wo): the same h as the v of a curve with pbrt's coordinates (shape_curve.cl, curve_texture_uv).
 *
 * S is not reciprocal (Ap and Np depend on ωo alone): importance transport (SurfaceContext.adjoint) weighs its
 * samples by S with the directions swapped, as the adjoint BSDF is defined. σa is per unit fibre radius (the path
 * through the fibre is 2 cos γt radii long); eta is the fibre's index relative to the outside; angles in radians. */
#ifndef SPECTRACE_BSDF_HAIR_CL
#define SPECTRACE_BSDF_HAIR_CL

#include "bsdf_sample.cl"
#include "fresnel.cl"
#include "spectrum.cl"
#include "texture.cl"

#define HAIR_P_MAX 3

typedef struct {
    float4 sigma_a;      /* absorption per unit fibre radius, per sampled wavelength */
    float eta;           /* fibre index of refraction relative to the outside */
    float h;             /* offset across the fibre, [−1, 1] */
    float gamma_o;       /* asin h */
    float v[HAIR_P_MAX + 1];  /* longitudinal variances of R, TT, TRT and the residual */
    float s;             /* logistic scale of the azimuthal lobes */
    float sin2k_alpha[3];  /* sin(2^k α), k = 0, 1, 2: the scale tilt's shifts */
    float cos2k_alpha[3];
    int adjoint;         /* importance transport: a sample weighs S with its directions swapped */
#if SCENE_HAS_MITSUBA_CURVE_UV
    int h_from_wo;       /* SurfaceContext.fibre_h_from_geometry: h from ωo, not from v (hair_from_wo) */
#endif
} HairParams;

/* Light crosses the fibre: its frame keeps the surface's own normal (S does not depend on it, but turning it
 * toward the viewer would be meaningless for a model with transmission). Its frame follows dp/du. */
inline int hair_flags(__global const Material *m)
{
    return BSDF_NON_DELTA | BSDF_TRANSMISSION;
}

inline HairParams hair_params(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w)
{
    HairParams p;
    p.sigma_a = spectrum_at(sc->buffers.spectra, m->reflectance_offset, w);
    p.eta = m->ior;
    p.h = clamp(2.0f * sc->uv.y - 1.0f, -1.0f, 1.0f);
    p.gamma_o = asin(p.h);
    float beta_m = m->ior_coefficients_b.x, beta_n = m->ior_coefficients_b.y, alpha = m->ior_coefficients_b.z;
    /* The paper's fits of the lobes' variance and scale to the perceptual roughnesses β_m, β_n (its sec. 4.2). */
    float bm2 = beta_m * beta_m;
    float sd = 0.726f * beta_m + 0.812f * bm2 + 3.7f * pown(beta_m, 20);
    p.v[0] = sd * sd;
    p.v[1] = 0.25f * p.v[0];
    p.v[2] = 4.0f * p.v[0];
    p.v[3] = p.v[2];
    float bn2 = beta_n * beta_n;
    p.s = 0.626657069f * (0.265f * beta_n + 1.194f * bn2 + 5.372f * pown(beta_n, 22)); /* √(π/8) · fit */
    p.sin2k_alpha[0] = sin(alpha);
    p.cos2k_alpha[0] = sqrt(fmax(0.0f, 1.0f - p.sin2k_alpha[0] * p.sin2k_alpha[0]));
    for (int k = 1; k < 3; ++k) {
        p.sin2k_alpha[k] = 2.0f * p.cos2k_alpha[k - 1] * p.sin2k_alpha[k - 1];
        p.cos2k_alpha[k] = p.cos2k_alpha[k - 1] * p.cos2k_alpha[k - 1] - p.sin2k_alpha[k - 1] * p.sin2k_alpha[k - 1];
    }
    p.adjoint = sc->adjoint;
#if SCENE_HAS_MITSUBA_CURVE_UV
    p.h_from_wo = sc->fibre_h_from_geometry;
#endif
    return p;
}

#if SCENE_HAS_MITSUBA_CURVE_UV
/* p with h (and γo) taken from ωo where p says so: the entry points below call it, so that an adjoint sample, which
 * weighs S with its directions swapped, keeps the h of the vertex's own ωo, as v would give it. */
inline HairParams hair_from_wo(const HairParams *p, float3 wo)
{
    HairParams q = *p;
    if (p->h_from_wo) {
        float across = sqrt(wo.y * wo.y + wo.z * wo.z);
        q.h = across > 0.0f ? clamp(-wo.y / across, -1.0f, 1.0f) : 0.0f;
        q.gamma_o = asin(q.h);
    }
    return q;
}
#define HAIR_H_FROM_WO(p, wo) HairParams p##_at_wo = hair_from_wo(p, wo); p = &p##_at_wo
#else
#define HAIR_H_FROM_WO(p, wo) ((void)0)
#endif

/* Modified Bessel function I0 by its power series Σ (x²/4)^i / (i!)², summed until the terms stop counting (at
 * most 40: x ≤ 12 here). pbrt-v4 stops at 10 terms, 2 % short at x = 12. */
inline float hair_i0(float x)
{
    float sum = 1.0f, term = 1.0f, x2 = 0.25f * x * x;
    for (int i = 1; i <= 40 && term > 1e-8f * sum; ++i) {
        term *= x2 / (float)(i * i);
        sum += term;
    }
    return sum;
}

/* log I0, above 12 by its asymptotic expansion, e^x / √(2πx) (1 + 1/(8x) + 9/(128x²) + 225/(3072x³)) (Abramowitz
 * & Stegun 9.7.1), where the series would leave float's range; pbrt-v4 halves the 1/(8x) term, 0.5 % low at 12. */
inline float hair_log_i0(float x)
{
    if (x > 12.0f) {
        float r = 1.0f / x;
        return x - 0.5f * log(2.0f * M_PI_F * x) + log(1.0f + r * (0.125f + r * (0.0703125f + r * 0.0732421875f)));
    }
    return log(hair_i0(x));
}

/* Mp: ∫ Mp cos θi dθi = 1. Small variances in log space, where csch(1/v) and I0 would leave float's range. */
inline float hair_mp(float cos_i, float cos_o, float sin_i, float sin_o, float v)
{
    float a = cos_i * cos_o / v, b = sin_i * sin_o / v;
    if (v <= 0.1f) return exp(hair_log_i0(a) - b - 1.0f / v + M_LN2_F - log(2.0f * v));
    return exp(-b) * hair_i0(a) / (sinh(1.0f / v) * 2.0f * v);
}

inline float hair_logistic(float x, float s)
{
    x = fabs(x);
    float e = exp(-x / s);
    return e / (s * (1.0f + e) * (1.0f + e));
}

inline float hair_logistic_cdf(float x, float s)
{
    return 1.0f / (1.0f + exp(-x / s));
}

/* The logistic restricted to [−π, π] and renormalised there. */
inline float hair_trimmed_logistic(float x, float s)
{
    return hair_logistic(x, s) / (hair_logistic_cdf(M_PI_F, s) - hair_logistic_cdf(-M_PI_F, s));
}

inline float hair_sample_trimmed_logistic(float u, float s)
{
    float lo = hair_logistic_cdf(-M_PI_F, s);
    float k = hair_logistic_cdf(M_PI_F, s) - lo;
    float x = -s * log(1.0f / (u * k + lo) - 1.0f);
    return clamp(x, -M_PI_F, M_PI_F);
}

/* The azimuthal deflection of path p entering at γo, refracted to γt. */
inline float hair_phi(int p, float gamma_o, float gamma_t)
{
    return 2.0f * p * gamma_t - 2.0f * gamma_o + p * M_PI_F;
}

inline float hair_np(float phi, int p, float s, float gamma_o, float gamma_t)
{
    float d = phi - hair_phi(p, gamma_o, gamma_t);
    /* Into [−π, π]: the deflection is many turns for large p. */
    d -= 2.0f * M_PI_F * floor((d + M_PI_F) / (2.0f * M_PI_F));
    return hair_trimmed_logistic(d, s);
}

/* Attenuations A_0..A_3 per wavelength for a ray at cos θo, h, with the transmittance T of one crossing. */
inline void hair_ap(float cos_theta_o, float eta, float h, float4 t, float4 ap[HAIR_P_MAX + 1])
{
    float cos_gamma_o = sqrt(fmax(0.0f, 1.0f - h * h));
    float f = fresnel_dielectric(cos_theta_o * cos_gamma_o, eta);
    ap[0] = (float4)(f);
    ap[1] = (1.0f - f) * (1.0f - f) * t;
    ap[2] = ap[1] * t * f;
    /* The geometric series of the p ≥ 3 paths. */
    ap[3] = ap[2] * f * t / ((float4)(1.0f) - t * f);
}

/* What every lobe of a given ωo shares: the refracted ray's γt and the attenuations. */
typedef struct {
    float sin_theta_o, cos_theta_o, phi_o, gamma_t;
    float4 ap[HAIR_P_MAX + 1];
} HairOutgoing;

inline HairOutgoing hair_outgoing(const HairParams *p, float3 wo)
{
    HairOutgoing o;
    o.sin_theta_o = clamp(wo.x, -1.0f, 1.0f);
    o.cos_theta_o = sqrt(fmax(0.0f, 1.0f - o.sin_theta_o * o.sin_theta_o));
    o.phi_o = atan2(wo.z, wo.y);
    float sin_theta_t = o.sin_theta_o / p->eta;
    float cos_theta_t = sqrt(fmax(0.0f, 1.0f - sin_theta_t * sin_theta_t));
    /* The modified index of the fibre's cross-section (Bravais) for a ray inclined by θo. */
    float etap = sqrt(fmax(0.0f, p->eta * p->eta - o.sin_theta_o * o.sin_theta_o)) / fmax(o.cos_theta_o, 1e-7f);
    float sin_gamma_t = clamp(p->h / etap, -1.0f, 1.0f);
    float cos_gamma_t = sqrt(fmax(0.0f, 1.0f - sin_gamma_t * sin_gamma_t));
    o.gamma_t = asin(sin_gamma_t);
    float4 t = exp(-p->sigma_a * (2.0f * cos_gamma_t / fmax(cos_theta_t, 1e-7f)));
    hair_ap(o.cos_theta_o, p->eta, p->h, t, o.ap);
    return o;
}

/* sin and cos of θo shifted by lobe p's tilt of the scales (−2α, α, 4α); the residual is not shifted. */
inline float2 hair_tilted(const HairParams *p, const HairOutgoing *o, int lobe)
{
    float s = o->sin_theta_o, c = o->cos_theta_o;
    if (lobe == 0) return (float2)(s * p->cos2k_alpha[1] - c * p->sin2k_alpha[1],
                                   fabs(c * p->cos2k_alpha[1] + s * p->sin2k_alpha[1]));
    if (lobe == 1) return (float2)(s * p->cos2k_alpha[0] + c * p->sin2k_alpha[0],
                                   fabs(c * p->cos2k_alpha[0] - s * p->sin2k_alpha[0]));
    if (lobe == 2) return (float2)(s * p->cos2k_alpha[2] + c * p->sin2k_alpha[2],
                                   fabs(c * p->cos2k_alpha[2] - s * p->sin2k_alpha[2]));
    return (float2)(s, c);
}

/* S(ωo, ωi) per wavelength: the integrators' f·|cos θi|. */
inline float4 hair_scattering(const HairParams *p, float3 wo, float3 wi)
{
    HairOutgoing o = hair_outgoing(p, wo);
    float sin_theta_i = clamp(wi.x, -1.0f, 1.0f);
    float cos_theta_i = sqrt(fmax(0.0f, 1.0f - sin_theta_i * sin_theta_i));
    float phi = atan2(wi.z, wi.y) - o.phi_o;
    float4 sum = (float4)(0.0f);
    for (int lobe = 0; lobe < HAIR_P_MAX; ++lobe) {
        float2 op = hair_tilted(p, &o, lobe);
        sum += hair_mp(cos_theta_i, op.y, sin_theta_i, op.x, p->v[lobe]) * o.ap[lobe] *
               hair_np(phi, lobe, p->s, p->gamma_o, o.gamma_t);
    }
    sum += hair_mp(cos_theta_i, o.cos_theta_o, sin_theta_i, o.sin_theta_o, p->v[HAIR_P_MAX]) * o.ap[HAIR_P_MAX] *
           (0.5f * M_1_PI_F);
    return sum;
}

/* The probabilities of sampling each lobe: its attenuation averaged over the path's wavelengths, normalised. */
inline void hair_lobe_probabilities(const HairOutgoing *o, float pick[HAIR_P_MAX + 1])
{
    float total = 0.0f;
    for (int lobe = 0; lobe <= HAIR_P_MAX; ++lobe) {
        float4 a = o->ap[lobe];
        pick[lobe] = fmax(0.25f * (a.x + a.y + a.z + a.w), 0.0f);
        total += pick[lobe];
    }
    for (int lobe = 0; lobe <= HAIR_P_MAX; ++lobe) pick[lobe] = total > 0.0f ? pick[lobe] / total : 0.0f;
}

inline float4 hair_eval(const HairParams *p, float3 wo, float3 wi)
{
    HAIR_H_FROM_WO(p, wo);
    return hair_scattering(p, wo, wi);
}

inline float hair_pdf_given(const HairParams *p, const HairOutgoing *o, float3 wi)
{
    float pick[HAIR_P_MAX + 1];
    hair_lobe_probabilities(o, pick);
    float sin_theta_i = clamp(wi.x, -1.0f, 1.0f);
    float cos_theta_i = sqrt(fmax(0.0f, 1.0f - sin_theta_i * sin_theta_i));
    float phi = atan2(wi.z, wi.y) - o->phi_o;
    float pdf = 0.0f;
    for (int lobe = 0; lobe < HAIR_P_MAX; ++lobe) {
        float2 op = hair_tilted(p, o, lobe);
        pdf += hair_mp(cos_theta_i, op.y, sin_theta_i, op.x, p->v[lobe]) * pick[lobe] *
               hair_np(phi, lobe, p->s, p->gamma_o, o->gamma_t);
    }
    pdf += hair_mp(cos_theta_i, o->cos_theta_o, sin_theta_i, o->sin_theta_o, p->v[HAIR_P_MAX]) * pick[HAIR_P_MAX] *
           (0.5f * M_1_PI_F);
    return pdf;
}

inline float hair_pdf(const HairParams *p, float3 wo, float3 wi)
{
    HAIR_H_FROM_WO(p, wo);
    HairOutgoing o = hair_outgoing(p, wo);
    return hair_pdf_given(p, &o, wi);
}

/* uc picks a lobe by its share of the attenuation and, rescaled, draws its azimuth; u draws the longitudinal angle
 * from Mp exactly (d'Eon et al. 2013's sampling of the von Mises-Fisher lobe). The pdf is the mixture's. */
inline int hair_sample(const HairParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    HAIR_H_FROM_WO(p, wo);
    HairOutgoing o = hair_outgoing(p, wo);
    float pick[HAIR_P_MAX + 1];
    hair_lobe_probabilities(&o, pick);
    int lobe = 0;
    while (lobe < HAIR_P_MAX && uc >= pick[lobe]) {
        uc -= pick[lobe];
        ++lobe;
    }
    if (!(pick[lobe] > 0.0f)) return 0;
    uc = fmin(uc / pick[lobe], 0x1.fffffep-1f);
    float2 op = hair_tilted(p, &o, lobe);
    float v = p->v[lobe];
    float cos_theta = 1.0f + v * log(fmax(u.x, 1e-5f) + (1.0f - u.x) * exp(-2.0f / v));
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float cos_phi = cospi(2.0f * u.y);
    float sin_theta_i = clamp(-cos_theta * op.x + sin_theta * cos_phi * op.y, -1.0f, 1.0f);
    float cos_theta_i = sqrt(fmax(0.0f, 1.0f - sin_theta_i * sin_theta_i));
    float dphi = lobe < HAIR_P_MAX ? hair_phi(lobe, p->gamma_o, o.gamma_t) + hair_sample_trimmed_logistic(uc, p->s)
                                   : 2.0f * M_PI_F * uc;
    float cos_phi_i, sin_phi_i = sincos(o.phi_o + dphi, &cos_phi_i);
    float3 wi = (float3)(sin_theta_i, cos_theta_i * cos_phi_i, cos_theta_i * sin_phi_i);
    /* Importance flows from wo (the light's side) to wi: its weight is S(wi, wo) |cos θi| / |cos θo| / pdf, the
     * adjoint BSDF's value (f(wi, wo) = S(wi, wo) / |cos θo|) times wi's cosine. */
    float4 f_cos = hair_scattering(p, wo, wi);
    if (p->adjoint) f_cos = fabs(wo.z) > 0.0f ? hair_scattering(p, wi, wo) * (fabs(wi.z) / fabs(wo.z)) : 0.0f;
    return continuous_sample(wi, f_cos, hair_pdf_given(p, &o, wi), s);
}

#endif
