/* Thin principled: Mitsuba 3's `principledthin` BSDF (Burley 2015, "Extending the Disney BRDF to a BSDF with
 * Integrated Subsurface Scattering", sec. 5.2 and fig. 15), a sheet with no interior (a leaf, paper, a curtain, a
 * window pane): light that crosses it leaves on the other side without bending and without entering a medium. In
 * the local shading frame, with both directions turned so that ωo lies above (the model is the same from both
 * faces), b the base colour, s spec_trans, t diff_trans / 2 (Mitsuba's diff_trans runs over [0, 2]), η the sheet's
 * index relative to the outside, ωi' = (ωi.x, ωi.y, |ωi.z|) and h = normalize(ωo + ωi'):
 *   specular reflection    s F_thin D(h) G2 / (4 cos θo), F_thin = lerp(F_d, Schlick(c_tint R0(η)), spec_tint),
 *       F_d the exact dielectric Fresnel term at ωo·h (fresnel.cl), R0(η) = ((η − 1)/(η + 1))²;
 *   specular transmission  s b (1 − F_d) D_t(h) G2_t / (4 cos θo): the reflection lobe about h mirrored through
 *       the sheet, of the roughness (0.65 η − 0.35) r (Burley 2015, fig. 15: the two refractions through a thin
 *       slab widen the lobe less than one refraction would); it needs ωi·h < 0 (ωi behind the microfacet), the
 *       test Mitsuba makes of the light's side alone. The value is symmetric where the test passes both ways,
 *       but the test is not: f(ωo, ωi) and f(ωi, ωo) differ where only one passes (rough sheets seen at grazing
 *       angles). So f is radiance's (ωo the viewer's side, as every caller of eval passes it), and importance
 *       transport (SurfaceContext.adjoint) weighs its samples with the directions swapped;
 *   diffuse reflection     (1 − s)(1 − t) b/π ((1 − Fi/2)(1 − Fo/2) + Rr (Fi + Fo + Fi Fo (Rr − 1))) cos θi,
 *       Burley's retro-reflection as in bsdf_principled.cl, Rr = 2 r cos²θd, θd the angle of ωi to h;
 *   sheen                  (1 − s)(1 − t) sheen (1 − cos θd)⁵ lerp(1, c_tint, sheen_tint) cos θi;
 *   diffuse transmission   (1 − s) t b/π |cos θi|.
 * D and G2 are the anisotropic GGX of microfacet_anisotropic.cl with αx = max(0.001, r²/a), αy = max(0.001, r² a),
 * a = √(1 − 0.9 anisotropic), r the roughness (scaled for the transmission); c_tint = b / lum(b). The other lobes
 * are symmetric in ωi and ωo (the sheet has the same medium on both sides, so no η² factor either way). Mitsuba's
 * masking is the separable G1 G1; this is the height-correlated G2, as bsdf_principled.cl.
 * Parameters: base colour in the row's reflectance fields; the weights and η in a block of the spectrum table
 * (Material.coat_table_offset; host: spectrace.materials.principledthin): weight k at 2k, its texture at 2k + 1.
 * Sampling: Mitsuba's lobe choice, specular reflection and transmission each with probability s/2 (visible normals
 * about ωo), diffuse reflection (1 − s)(1 − t), diffuse transmission (1 − s) t (cosine-weighted); the reported pdf
 * is the mixture's. */
#ifndef SPECTRACE_BSDF_PRINCIPLEDTHIN_CL
#define SPECTRACE_BSDF_PRINCIPLEDTHIN_CL

#include "bsdf_sample.cl"
#include "burley.cl"
#include "fresnel.cl"
#include "microfacet_anisotropic.cl"
#include "spectrum.cl"
#include "texture.cl"

/* The parameter block's slots (spectrace.materials.principledthin.SCALARS), then η and the base colour's
 * luminance (negative: the mean over the path's wavelengths, for a texture). */
#define PRINCIPLEDTHIN_ROUGHNESS 0
#define PRINCIPLEDTHIN_ANISOTROPIC 1
#define PRINCIPLEDTHIN_SPEC_TRANS 2
#define PRINCIPLEDTHIN_SPEC_TINT 3
#define PRINCIPLEDTHIN_SHEEN 4
#define PRINCIPLEDTHIN_SHEEN_TINT 5
#define PRINCIPLEDTHIN_DIFF_TRANS 6
#define PRINCIPLEDTHIN_ETA 14
#define PRINCIPLEDTHIN_LUMINANCE 15
#define PRINCIPLEDTHIN_MIN_ALPHA 1e-3f /* Mitsuba's clamp, as principled's */

typedef struct {
    float4 base;
    float4 tint;        /* c_tint = b / lum(b) */
    float2 alpha;       /* αx, αy of the specular reflection */
    float2 alpha_trans; /* of the specular transmission */
    float roughness;
    float spec_trans, spec_tint, sheen, sheen_tint;
    float diff_trans; /* t = Mitsuba's diff_trans / 2, in [0, 1] */
    float eta;
    int adjoint; /* importance transport: a sample weighs the value with its directions swapped */
} PrincipledthinParams;

inline int principledthin_flags(__global const Material *m)
{
    return m->nonlinear ? BSDF_NON_DELTA | BSDF_TRANSMISSION : BSDF_NON_DELTA;
}

inline float2 principledthin_alpha(float roughness, float aspect)
{
    float r2 = roughness * roughness;
    return (float2)(fmax(PRINCIPLEDTHIN_MIN_ALPHA, r2 / aspect), fmax(PRINCIPLEDTHIN_MIN_ALPHA, r2 * aspect));
}

inline PrincipledthinParams principledthin_params(__global const Material *m, const SurfaceContext *sc,
                                                  const SampledWavelengths *w)
{
    __global const float *block = sc->buffers.spectra + m->coat_table_offset;
    PrincipledthinParams p;
    p.base = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    float lum = block[PRINCIPLEDTHIN_LUMINANCE] >= 0.0f ? block[PRINCIPLEDTHIN_LUMINANCE]
                                                        : dot(p.base, (float4)(0.25f));
    p.tint = lum > 0.0f ? p.base / lum : (float4)(1.0f);
    p.eta = block[PRINCIPLEDTHIN_ETA];
    p.roughness = principled_weight(sc, block, PRINCIPLEDTHIN_ROUGHNESS, w);
    float aspect = sqrt(1.0f - 0.9f * principled_weight(sc, block, PRINCIPLEDTHIN_ANISOTROPIC, w));
    p.alpha = principledthin_alpha(p.roughness, aspect);
    p.alpha_trans = principledthin_alpha((0.65f * p.eta - 0.35f) * p.roughness, aspect);
    p.spec_trans = principled_weight(sc, block, PRINCIPLEDTHIN_SPEC_TRANS, w);
    p.spec_tint = principled_weight(sc, block, PRINCIPLEDTHIN_SPEC_TINT, w);
    p.sheen = principled_weight(sc, block, PRINCIPLEDTHIN_SHEEN, w);
    p.sheen_tint = principled_weight(sc, block, PRINCIPLEDTHIN_SHEEN_TINT, w);
    int k = PRINCIPLEDTHIN_DIFF_TRANS;
    p.diff_trans = 0.5f * clamp(surface_scalar(sc, (int)block[2 * k + 1], block[2 * k], w), 0.0f, 2.0f);
    if (!m->nonlinear) p.spec_trans = p.diff_trans = 0.0f;
    p.adjoint = sc->adjoint;
    return p;
}

/* The lobe probabilities: specular reflection, specular transmission, diffuse reflection (diffuse transmission
 * takes the rest). */
inline float3 principledthin_lobe_probabilities(const PrincipledthinParams *p)
{
    float s = p->spec_trans;
    return (float3)(0.5f * s, 0.5f * s, (1.0f - s) * (1.0f - p->diff_trans));
}

/* The half vector of wo (above) and wi mirrored above the sheet; 0 when wo or wi' sees the microfacet's back. */
inline float3 principledthin_half_vector(float3 wo, float3 wi)
{
    float3 h = wo + (float3)(wi.x, wi.y, fabs(wi.z));
    float len2 = dot(h, h);
    if (!(len2 > 0.0f)) return (float3)(0.0f);
    h *= rsqrt(len2);
    if (h.z <= 0.0f || dot(wo, h) <= 0.0f) return (float3)(0.0f);
    /* Reflection needs wi in front of the microfacet, transmission behind it. */
    if (wi.z > 0.0f ? dot(wi, h) <= 0.0f : dot(wi, h) >= 0.0f) return (float3)(0.0f);
    return h;
}

/* Both directions turned so that wo lies above: the model is the same from both faces. */
inline void principledthin_turn(float3 *wo, float3 *wi)
{
    if (wo->z < 0.0f) {
        *wo = -*wo;
        *wi = -*wi;
    }
}

inline float4 principledthin_eval(const PrincipledthinParams *p, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f) return (float4)(0.0f);
    principledthin_turn(&wo, &wi);
    int reflection = wi.z > 0.0f;
    float3 h = principledthin_half_vector(wo, wi);
    float4 value = (float4)(0.0f);
    float s = p->spec_trans;
    if (s > 0.0f && h.z > 0.0f) {
        float wo_h = dot(wo, h);
        float f_d = fresnel_dielectric(wo_h, p->eta);
        float3 mirrored = (float3)(wi.x, wi.y, fabs(wi.z));
        if (reflection) {
            float r0 = (p->eta - 1.0f) / (p->eta + 1.0f);
            float4 tinted = p->tint * (r0 * r0);
            tinted = tinted + (1.0f - tinted) * schlick_weight(wo_h);
            float4 f = mix((float4)(f_d), tinted, p->spec_tint);
            value += f * (s * ggx_aniso_d(h, p->alpha) * ggx_aniso_g2(wo, mirrored, p->alpha) / (4.0f * wo.z));
        } else {
            float dg = ggx_aniso_d(h, p->alpha_trans) * ggx_aniso_g2(wo, mirrored, p->alpha_trans);
            value += p->base * (s * (1.0f - f_d) * dg / (4.0f * wo.z));
        }
    }
    float diffuse = 1.0f - s;
    if (diffuse <= 0.0f) return value;
    if (!reflection) return value + p->base * (diffuse * p->diff_trans * INV_PI * -wi.z);
    float3 hr = reflection_half_vector(wo, wi);
    float cos_d = dot(hr, wi);
    float weight = diffuse * (1.0f - p->diff_trans);
    return burley_diffuse_sheen(value, p->base, p->tint, p->roughness, p->sheen, p->sheen_tint, weight, wo.z, wi.z,
                                cos_d);
}

inline float principledthin_pdf(const PrincipledthinParams *p, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f) return 0.0f;
    principledthin_turn(&wo, &wi);
    float3 lobes = principledthin_lobe_probabilities(p);
    int reflection = wi.z > 0.0f;
    float pdf = reflection ? lobes.z * wi.z * INV_PI
                           : (1.0f - p->spec_trans) * p->diff_trans * -wi.z * INV_PI;
    float3 h = principledthin_half_vector(wo, wi);
    if (p->spec_trans > 0.0f && h.z > 0.0f) {
        float2 alpha = reflection ? p->alpha : p->alpha_trans;
        pdf += (reflection ? lobes.x : lobes.y) * ggx_aniso_visible_pdf(wo, h, alpha) / (4.0f * dot(wo, h));
    }
    return pdf;
}

inline int principledthin_sample(const PrincipledthinParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z == 0.0f) return 0;
    float side = wo.z > 0.0f ? 1.0f : -1.0f;
    float3 o = wo * side;
    float3 lobes = principledthin_lobe_probabilities(p);
    float3 wi;
    if (uc < lobes.x + lobes.y) {
        int transmit = uc >= lobes.x;
        float3 h = ggx_aniso_sample_visible_normal(o, transmit ? p->alpha_trans : p->alpha, u);
        float o_h = dot(o, h);
        if (o_h <= 0.0f) return 0;
        wi = 2.0f * o_h * h - o;
        if (wi.z <= 0.0f) return 0;
        if (transmit) {
            wi.z = -wi.z;
            if (dot(wi, h) >= 0.0f) return 0;
        }
    } else {
        wi = sample_cosine_hemisphere(u);
        if (uc >= lobes.x + lobes.y + lobes.z) wi.z = -wi.z;
    }
    wi *= side;
    /* Importance flows from wo (the light's side) to wi (the viewer's): its weight is f(wi, wo) |cos θi| / pdf,
     * radiance's value with the directions swapped, which differs from f(wo, wi) where only one of the pair
     * passes the transmission's test. */
    float4 f_cos = p->adjoint ? principledthin_eval(p, wi, wo) * (fabs(wi.z) / fabs(wo.z))
                              : principledthin_eval(p, wo, wi);
    return continuous_sample(wi, f_cos, principledthin_pdf(p, wo, wi), s);
}

#endif
