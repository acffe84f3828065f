/* Principled: Mitsuba 3's principled BSDF (Burley 2012, "Physically Based Shading at Disney"; Burley 2015,
 * "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering"), the material of glTF 2.0's
 * metallic-roughness and Blender's Principled BSDF, in the local shading frame. With b the base colour, m metallic,
 * s spec_trans, the lobes are weighted by brdf = (1 − m)(1 − s) and bsdf = (1 − m) s:
 *   specular reflection  F_p(ωo·h) D(h) G2 / (4 |cos θo|) with, seen from outside,
 *       F_p = (1 − m)(1 − t) F_d + m Schlick(b) + (1 − m) t Schlick(c_tint R0(η))   (t = spec_tint),
 *       and bsdf F_d from inside; F_d the exact dielectric Fresnel term of index η (fresnel.cl);
 *   transmission         bsdf √b (1 − F_d) D G2 |ωi·h| |ωo·h| / (|cos θo| (ωo·h + e ωi·h)²)   (Walter et al. 2007
 *       eq. 21 with the radiance's 1/e², e the index seen from ωo, as the dielectric);
 *   clearcoat            0.25 c F_cc D_cc G_cc cos θi, Schlick F0 = 0.04, Burley's GTR1 D_cc of
 *       α = lerp(0.1, 0.001, clearcoat_gloss), G_cc = G1(ωo) G1(ωi) the separable GGX masking of α = 0.25: Mitsuba
 *       3's clearcoat, which leaves out a microfacet lobe's 1/(4 cos θo cos θi) (Burley's reference code has it,
 *       folded into its G); so exported scenes look as their author saw them in Mitsuba. Its albedo is at most
 *       0.035 c, at normal incidence, falling to 0 at grazing (Burley's: 0.009 c there, 0.047 c at grazing);
 *   diffuse              brdf b/π ((1 − Fi/2)(1 − Fo/2) + Rr (Fi + Fo + Fi Fo (Rr − 1))) cos θi,
 *       F = (1 − cos θ)⁵, Rr = 2 r cos²θd (Burley's retro-reflection);
 *   sheen                brdf sheen (1 − cos θd)⁵ lerp(1, c_tint, sheen_tint) cos θi.
 * D and G2 are the anisotropic GGX of microfacet_anisotropic.cl with αx = max(0.001, r²/a), αy = max(0.001, r² a),
 * a = √(1 − 0.9 anisotropic), r the perceptual roughness; c_tint = b / lum(b). Every lobe is reciprocal (the
 * transmission in the generalised sense of the dielectric). Diffuse, sheen and clearcoat are added to the specular
 * lobe without taking its Fresnel reflection away, as in Burley's model: a white base seen at grazing angles
 * reflects more than it receives (docs/materials.md measures it).
 * Parameters: base colour in the row's reflectance fields, η in its index fields (kernels/ior.cl: dispersive where
 * it names a glass, steered by the hero wavelength), the weights in a block of the spectrum table
 * (Material.coat_table_offset; host: spectrace.materials.principled): weight k at 2k, its texture at 2k + 1.
 * A textured specular level s (Burley's; glTF's specularTexture) sits in the row's roughness_texture and gives η
 * per hit as principled_eta_from_specular; the index fields then hold its largest value's η for the host's use.
 * Sampling: a lobe with probability proportional to brdf max(b̄, 0.05) (cosine-weighted hemisphere, for diffuse and
 * sheen), 0.25 clearcoat (GTR1's D cos θh) and 1 − brdf (1 − F_d(cos θo)) (visible normals, then reflection with
 * probability 1 − bsdf (1 − F_d(ωo·h)), else refraction); from inside only the last, reflecting with F_d. The
 * reported pdf is the mixture's (one-sample MIS of the lobes). */
#ifndef SPECTRACE_BSDF_PRINCIPLED_CL
#define SPECTRACE_BSDF_PRINCIPLED_CL

#include "bsdf_sample.cl"
#include "burley.cl"
#include "fresnel.cl"
#include "ior.cl"
#include "microfacet_anisotropic.cl"
#include "spectrum.cl"
#include "texture.cl"

/* The weights' slots in the parameter block (spectrace.materials.principled.SCALARS), and the base colour's
 * luminance (negative: take the mean over the path's wavelengths, for a texture). */
#define PRINCIPLED_ROUGHNESS 0
#define PRINCIPLED_ANISOTROPIC 1
#define PRINCIPLED_METALLIC 2
#define PRINCIPLED_SPEC_TRANS 3
#define PRINCIPLED_SPEC_TINT 4
#define PRINCIPLED_SHEEN 5
#define PRINCIPLED_SHEEN_TINT 6
#define PRINCIPLED_CLEARCOAT 7
#define PRINCIPLED_CLEARCOAT_GLOSS 8
#define PRINCIPLED_LUMINANCE 18
#define PRINCIPLED_MIN_ALPHA 1e-3f
#define PRINCIPLED_COAT_ALPHA 0.25f

/* The index whose Schlick F0 = ((η − 1)/(η + 1))² is 0.08 s (spectrace.materials.principled.eta_from_specular),
 * kept above 1 so that a texel of 0 (no specular reflection) stays a valid interface. */
inline float principled_eta_from_specular(float s)
{
    return fmax(2.0f / (1.0f - sqrt(0.08f * s)) - 1.0f, 1.0f + 1e-4f);
}

typedef struct {
    float4 base;
    float4 tint;      /* c_tint = b / lum(b) */
    float2 alpha;     /* αx, αy of the specular lobe */
    float roughness;  /* r, perceptual */
    float metallic, spec_trans, spec_tint, sheen, sheen_tint, clearcoat;
    float coat_alpha; /* GTR1 α of the clearcoat */
    float eta;        /* interior over exterior at the hero wavelength */
} PrincipledParams;

inline int principled_flags(__global const Material *m)
{
    if (!m->nonlinear) return BSDF_NON_DELTA;
    return BSDF_NON_DELTA | BSDF_TRANSMISSION | (material_ior_is_dispersive(m) ? BSDF_DISPERSIVE : 0);
}

inline PrincipledParams principled_params(__global const Material *m, const SurfaceContext *sc,
                                          const SampledWavelengths *w)
{
    __global const float *block = sc->buffers.spectra + m->coat_table_offset;
    PrincipledParams p;
    p.base = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    float lum = block[PRINCIPLED_LUMINANCE] >= 0.0f ? block[PRINCIPLED_LUMINANCE] : dot(p.base, (float4)(0.25f));
    p.tint = lum > 0.0f ? p.base / lum : (float4)(1.0f);
    p.roughness = principled_weight(sc, block, PRINCIPLED_ROUGHNESS, w);
    float aspect = sqrt(1.0f - 0.9f * principled_weight(sc, block, PRINCIPLED_ANISOTROPIC, w));
    float r2 = p.roughness * p.roughness;
    p.alpha = (float2)(fmax(PRINCIPLED_MIN_ALPHA, r2 / aspect), fmax(PRINCIPLED_MIN_ALPHA, r2 * aspect));
    p.metallic = principled_weight(sc, block, PRINCIPLED_METALLIC, w);
    p.spec_trans = m->nonlinear ? principled_weight(sc, block, PRINCIPLED_SPEC_TRANS, w) : 0.0f;
    p.spec_tint = principled_weight(sc, block, PRINCIPLED_SPEC_TINT, w);
    p.sheen = principled_weight(sc, block, PRINCIPLED_SHEEN, w);
    p.sheen_tint = principled_weight(sc, block, PRINCIPLED_SHEEN_TINT, w);
    p.clearcoat = principled_weight(sc, block, PRINCIPLED_CLEARCOAT, w);
    p.coat_alpha = mix(0.1f, 0.001f, principled_weight(sc, block, PRINCIPLED_CLEARCOAT_GLOSS, w));
    p.eta = (SCENE_HAS_TEXTURES && m->roughness_texture != NO_TEXTURE)
                ? principled_eta_from_specular(surface_scalar(sc, m->roughness_texture, 0.5f, w))
                : material_ior(m, w->lambda.x);
    return p;
}

/* Burley's GTR1 ("Berry") distribution, normalised so that ∫ D cos θh dh = 1. */
inline float gtr1_d(float3 h, float alpha)
{
    if (h.z <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    return (a2 - 1.0f) / (M_PI_F * log(a2) * (1.0f + (a2 - 1.0f) * h.z * h.z));
}

/* A normal with density gtr1_d(h) cos θh. */
inline float3 gtr1_sample_normal(float alpha, float2 u)
{
    float a2 = alpha * alpha;
    float cos2 = (1.0f - pow(a2, 1.0f - u.x)) / (1.0f - a2);
    float cos_theta = sqrt(clamp(cos2, 0.0f, 1.0f));
    float sin_theta = sqrt(fmax(1.0f - cos_theta * cos_theta, 0.0f));
    float2 cs = cos_sin_turns(u.y);
    return (float3)(sin_theta * cs.x, sin_theta * cs.y, cos_theta);
}

inline float brdf_weight(const PrincipledParams *p)
{
    return (1.0f - p->metallic) * (1.0f - p->spec_trans);
}

inline float bsdf_weight(const PrincipledParams *p)
{
    return (1.0f - p->metallic) * p->spec_trans;
}

/* Lobe probabilities for light leaving toward wo (wo.z > 0): diffuse and sheen, clearcoat, specular. */
inline float3 principled_lobe_probabilities(const PrincipledParams *p, float3 wo)
{
    float brdf = brdf_weight(p);
    float diffuse = brdf * fmax(dot(p->base, (float4)(0.25f)), 0.05f);
    float coat = 0.25f * p->clearcoat;
    float specular = 1.0f - brdf * (1.0f - fresnel_dielectric(wo.z, p->eta));
    float total = diffuse + coat + specular;
    return (float3)(diffuse, coat, specular) / total;
}

/* The probability that a specular sample about h (seen from outside, wo·h > 0) reflects. */
inline float principled_reflect_probability(const PrincipledParams *p, float fresnel)
{
    return 1.0f - bsdf_weight(p) * (1.0f - fresnel);
}

/* The microfacet normal linking wo and wi (pointing up), e the index seen from wo; 0 when the pair is
 * incompatible (wo must see the microfacet's front, wi lie on the side its lobe sends light to). */
inline float3 principled_half_vector(float3 wo, float3 wi, float e)
{
    int reflection = wo.z * wi.z > 0.0f;
    float3 h = reflection ? wo + wi : wo + e * wi;
    float len2 = dot(h, h);
    if (!(len2 > 0.0f)) return (float3)(0.0f);
    h *= rsqrt(len2);
    if (h.z < 0.0f) h = -h;
    float side = wo.z > 0.0f ? 1.0f : -1.0f;
    if (dot(wo, h) * side <= 0.0f) return (float3)(0.0f);
    if (reflection ? dot(wi, h) * side <= 0.0f : dot(wi, h) * side >= 0.0f) return (float3)(0.0f);
    return h;
}

inline float4 principled_eval(const PrincipledParams *p, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f) return (float4)(0.0f);
    int front = wo.z > 0.0f;
    int reflection = wo.z * wi.z > 0.0f;
    float e = front ? p->eta : 1.0f / p->eta;
    float3 h = principled_half_vector(wo, wi, e);
    float4 value = (float4)(0.0f);
    if (h.z > 0.0f) {
        float wo_h = dot(wo, h), wi_h = dot(wi, h);
        float f_d = fresnel_dielectric(fabs(wo_h), wo_h >= 0.0f ? p->eta : 1.0f / p->eta);
        float dg = ggx_aniso_d(h, p->alpha) * ggx_aniso_g2(wo, wi, p->alpha);
        if (reflection) {
            float4 f;
            if (front) {
                float fw = schlick_weight(wo_h);
                float r0 = (p->eta - 1.0f) / (p->eta + 1.0f);
                float4 metal = p->base + (1.0f - p->base) * fw;
                float4 tinted = p->tint * (r0 * r0);
                tinted = tinted + (1.0f - tinted) * fw;
                f = (1.0f - p->metallic) * (1.0f - p->spec_tint) * f_d + p->metallic * metal +
                    (1.0f - p->metallic) * p->spec_tint * tinted;
            } else {
                f = (float4)(bsdf_weight(p) * f_d);
            }
            value += f * (dg / (4.0f * fabs(wo.z)));
        } else if (bsdf_weight(p) > 0.0f) {
            float denominator = wo_h + e * wi_h;
            float t = bsdf_weight(p) * (1.0f - f_d) * dg * fabs(wi_h * wo_h) /
                      (fabs(wo.z) * denominator * denominator);
            value += sqrt(p->base) * t;
        }
    }
    if (!front || !reflection) return value;
    float3 hr = reflection_half_vector(wo, wi);
    float cos_d = dot(hr, wi);
    if (p->clearcoat > 0.0f && h.z > 0.0f) {
        float f_cc = 0.04f + 0.96f * schlick_weight(cos_d);
        float d_cc = gtr1_d(hr, p->coat_alpha);
        float g_cc = ggx_g1(wo, PRINCIPLED_COAT_ALPHA) * ggx_g1(wi, PRINCIPLED_COAT_ALPHA);
        value += (float4)(0.25f * p->clearcoat * f_cc * d_cc * g_cc * wi.z);
    }
    float brdf = brdf_weight(p);
    if (brdf > 0.0f)
        value = burley_diffuse_sheen(value, p->base, p->tint, p->roughness, p->sheen, p->sheen_tint, brdf, wo.z, wi.z,
                                     cos_d);
    return value;
}

inline float principled_pdf(const PrincipledParams *p, float3 wo, float3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f) return 0.0f;
    int front = wo.z > 0.0f;
    float e = front ? p->eta : 1.0f / p->eta;
    float3 lobes = front ? principled_lobe_probabilities(p, wo) : (float3)(0.0f, 0.0f, 1.0f);
    /* From inside, mirror both so that wo is above: the same sampler with the inverse index. */
    float3 o = front ? wo : (float3)(wo.x, wo.y, -wo.z);
    float3 i = front ? wi : (float3)(wi.x, wi.y, -wi.z);
    float pdf = 0.0f;
    float3 h = principled_half_vector(o, i, e);
    if (h.z > 0.0f) {
        float o_h = dot(o, h), i_h = dot(i, h);
        float f_d = fresnel_dielectric(o_h, e);
        float reflect = front ? principled_reflect_probability(p, f_d) : f_d;
        float visible = ggx_aniso_visible_pdf(o, h, p->alpha);
        if (i.z > 0.0f) {
            pdf += lobes.z * visible * reflect / (4.0f * o_h);
        } else {
            float denominator = o_h + e * i_h;
            pdf += lobes.z * visible * (1.0f - reflect) * e * e * fabs(i_h) / (denominator * denominator);
        }
    }
    if (front && wi.z > 0.0f) {
        pdf += lobes.x * wi.z * INV_PI;
        float3 hr = reflection_half_vector(wo, wi);
        float wo_h = dot(wo, hr);
        if (lobes.y > 0.0f && wo_h > 0.0f) pdf += lobes.y * gtr1_d(hr, p->coat_alpha) * hr.z / (4.0f * wo_h);
    }
    return pdf;
}

inline int principled_sample(const PrincipledParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z == 0.0f) return 0;
    int front = wo.z > 0.0f;
    float e = front ? p->eta : 1.0f / p->eta;
    float3 lobes = front ? principled_lobe_probabilities(p, wo) : (float3)(0.0f, 0.0f, 1.0f);
    float3 o = front ? wo : (float3)(wo.x, wo.y, -wo.z);
    float3 wi;
    int refracted = 0;
    if (uc < lobes.x) {
        wi = sample_cosine_hemisphere(u);
    } else if (uc < lobes.x + lobes.y) {
        wi = microfacet_reflect(wo, gtr1_sample_normal(p->coat_alpha, u));
        if (wi.z <= 0.0f) return 0;
    } else {
        float v = lobes.z > 0.0f ? clamp((uc - lobes.x - lobes.y) / lobes.z, 0.0f, 1.0f) : 0.0f;
        float3 h = ggx_aniso_sample_visible_normal(o, p->alpha, u);
        float o_h = dot(o, h);
        if (o_h <= 0.0f) return 0;
        float cos_t;
        float f_d = fresnel_dielectric_refracting(o_h, e, &cos_t);
        float reflect = front ? principled_reflect_probability(p, f_d) : f_d;
        if (v < reflect) {
            wi = 2.0f * o_h * h - o;
            if (wi.z <= 0.0f) return 0;
        } else {
            wi = normalize((o_h / e - cos_t) * h - o / e);
            if (wi.z >= 0.0f) return 0;
            refracted = 1;
        }
        if (!front) wi.z = -wi.z;
    }
    if (!continuous_sample(wi, principled_eval(p, wo, wi), principled_pdf(p, wo, wi), s)) return 0;
    if (refracted) s->radiance_scale = 1.0f / (e * e);
    return 1;
}

#endif
