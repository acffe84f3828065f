/* Layered BSDFs by a stochastic random walk: a dielectric interface over a base (a conductor or a Lambertian
 * reflector) with a slab of participating medium between them, pbrt-v4's LayeredBxDF (Pharr, Jakob & Humphreys,
 * "Physically Based Rendering", 4th ed., sec. 14.3, after Guo, Hašan & Zhao 2018, "Position-Free Monte Carlo
 * Simulation for Arbitrary Layered BSDFs"). Its coatedconductor and coateddiffuse are bsdf_coatedconductor.cl and
 * bsdf_coateddiffuse.cl; this file is the walk they share.
 *
 * Geometry, local frame (+z the surface normal): the interface lies at z = thickness, the base at z = 0; the slab
 * between has σt = 1 per unit thickness and single-scattering albedo `albedo` (0: it only absorbs, exp(−thickness
 * / |cos θ|) per crossing), scattering by Henyey-Greenstein of mean cosine g. eta is the coat's index over the
 * outside's; the conductor's η + ik is relative to the coat (the host's values over eta). Roughnesses are GGX α
 * (Trowbridge-Reitz, as pbrt-v4), a delta lobe below GGX_SMOOTH_ALPHA.
 *
 * Estimators (each an unbiased estimate of the layered BSDF, truncated after max_depth scattering events at the
 * interfaces or in the slab, with Russian roulette after 3):
 *   eval  the reflection at the interface plus `samples` walks from ωo into the slab, each joined to ωi at every
 *         vertex through a direction presampled through the interface from ωi (next-event estimation, combined
 *         by the power heuristic with the walk's own next direction where both are non-delta; the weight of
 *         the walk's direction w takes the density with which ωi's presampling would have drawn −w, where
 *         pbrt-v4 takes the interface's density of ωi given −w, which differs through a rough interface and
 *         leaves the two weights not summing to 1: ~10 % too bright for a rough coat over a rough metal);
 *   sample one walk from ωo that leaves through the interface: its weight f·cos/pdf is an estimate of the true
 *         weight, exact in expectation;
 *   pdf   a stochastic estimate of the sampling density (the TRT term by MIS), mixed 0.9 : 0.1 with the uniform
 *         density 1/4π, so it is positive wherever f is: MIS needs only a positive function that both strategies
 *         evaluate alike, and a sample reports this function at its direction (pbrt's pdfIsProportional).
 * The walk's random numbers come from a hash of its arguments (directions quantised to 2⁻²⁰, so a direction turned
 * to world space and back hashes alike; a sample's own uc, u), so eval and pdf are functions of (ωo, ωi) and a
 * render stays deterministic however it is split. The walk's directions do not depend on λ (a constant coat
 * index; the base's Fresnel term and the slab's albedo only weigh): the four wavelengths share one walk.
 *
 * Transport: the layered BSDF is reciprocal (a reflection between one medium and itself), so importance transport
 * takes the same estimates; inside the walk each crossing of the interface carries radiance's 1/e² (entering) or
 * importance's 1 (the presampled direction from ωi, traced the other way), as pbrt-v4's `mode` and `!mode`.
 *
 * Only reflection: wo.z > 0 (material.cl turns the frame toward ωo) and directions below give 0. */
#ifndef SPECTRACE_LAYERED_CL
#define SPECTRACE_LAYERED_CL

#include "bsdf_sample.cl"
#include "fresnel.cl"
#include "hash.cl"
#include "medium.cl"
#include "microfacet.cl"
#include "sampling.cl"
#include "spectrum.cl"
#include "texture.cl"
/* The interface is bsdf_dielectric.cl's rough and smooth dielectric, which material_list.h includes before the
 * coated BSDFs (its code is lower in spectrace.materials.MATERIALS; kernel files include no BSDF of another). */
#ifndef SPECTRACE_BSDF_DIELECTRIC_CL
#error "layered.cl needs bsdf_dielectric.cl included first (material_list.h)"
#endif

#define LAYERED_CONDUCTOR 0
#define LAYERED_DIFFUSE 1
/* Which lobes an interface's sample may take (pbrt-v4's BxDFReflTransFlags). */
#define LAYERED_ANY 0
#define LAYERED_REFLECTION 1
#define LAYERED_TRANSMISSION 2
#define LAYERED_INV_4PI 0.07957747154594767f

typedef struct {
    float eta;           /* coat index / outside index */
    float alpha;         /* interface's GGX α */
    int base;            /* LAYERED_CONDUCTOR or LAYERED_DIFFUSE */
    float4 base_eta;     /* conductor: η relative to the coat, per wavelength */
    float4 base_k;       /* conductor: k relative to the coat */
    float4 reflectance;  /* diffuse base: albedo */
    float base_alpha;    /* conductor: GGX α */
    float thickness;     /* slab thickness in units of its mean free path (σt = 1) */
    float4 albedo;       /* slab's single-scattering albedo */
    float g;             /* slab's Henyey-Greenstein mean cosine */
    int max_depth;       /* scattering events a walk may take */
    int samples;         /* walks eval averages */
} LayeredParams;

/* One interface event: pbrt-v4's BSDFSample with f (not times the cosine) and pdf kept apart, as the walk needs. */
typedef struct {
    float3 wi;
    float4 f;
    float pdf;
    int is_delta;
    int transmits;
} LayerSample;

/* The walk's parameters a coated material's row (bsdf_coatedconductor.cl) holds besides its base. */
inline LayeredParams layered_row_params(__global const Material *m, const SurfaceContext *sc,
                                        const SampledWavelengths *w)
{
    LayeredParams p;
    p.eta = m->ior;
    p.alpha = surface_scalar(sc, m->roughness_texture, m->alpha, w);
    p.thickness = fmax(m->ior_coefficients_b.x, FLT_MIN); /* the interface and the base stay apart (pbrt-v4) */
    p.g = m->ior_coefficients_b.y;
    p.base_alpha = m->ior_coefficients_b.z;
    p.max_depth = (int)m->ior_coefficients_c.x;
    p.samples = (int)m->ior_coefficients_c.y;
    p.albedo = m->transmittance_offset == MATERIAL_NO_SPECTRUM
                   ? (float4)(0.0f)
                   : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    p.base_eta = p.base_k = p.reflectance = (float4)(0.0f);
    return p;
}

/* The coat's lobe flags: a delta lobe where smooth or index-matched (layered_top_smooth), ggx_lobe_flags' for a
 * rough or textured α. */
inline int layered_coat_flags(__global const Material *m)
{
    return fabs(m->ior - 1.0f) < 1e-4f ? BSDF_DELTA : ggx_lobe_flags(m);
}

/* ---------------------------------------------------------------- random numbers */

inline uint layered_mix(uint a, uint b)
{
    return hash_u32(a ^ (hash_u32(b) + 0x9e3779b9U + (a << 6) + (a >> 2)));
}

inline uint layered_hash_direction(uint seed, float3 v)
{
    const float q = 1048576.0f; /* 2^20 */
    seed = layered_mix(seed, (uint)(int)rint(v.x * q));
    seed = layered_mix(seed, (uint)(int)rint(v.y * q));
    return layered_mix(seed, (uint)(int)rint(v.z * q));
}

/* Uniform in [0, 1): the next value of a counter hashed with the walk's seed. */
inline float layered_random(uint *state)
{
    *state += 0x6d2b79f5U;
    return (float)(hash_u32(*state) >> 8) * 5.9604645e-8f;
}

inline float2 layered_random2(uint *state)
{
    float a = layered_random(state);
    return (float2)(a, layered_random(state));
}

/* Transmittance of the slab (σt = 1) over a height dz along w. */
inline float layered_tr(float dz, float3 w)
{
    if (fabs(dz) <= FLT_MIN) return 1.0f;
    return exp(-fabs(dz / w.z));
}

inline float layered_max(float4 v)
{
    return fmax(fmax(v.x, v.y), fmax(v.z, v.w));
}

inline int layered_nonzero(float4 v)
{
    return v.x != 0.0f || v.y != 0.0f || v.z != 0.0f || v.w != 0.0f;
}

/* ---------------------------------------------------------------- the interface: a dielectric, either side */

/* Smooth, or index-matched (a rough interface's refraction half vector vanishes as the indices meet: light then
 * passes straight, as pbrt-v4's dielectric of index 1). */
inline int layered_top_smooth(const LayeredParams *p)
{
    return ggx_is_smooth(p->alpha) || fabs(p->eta - 1.0f) < 1e-4f;
}

/* f of the interface (not times the cosine); `importance`: the adjoint, whose refraction lacks radiance's 1/e². */
inline float layered_top_f(const LayeredParams *p, float3 wo, float3 wi, int importance)
{
    if (layered_top_smooth(p) || wi.z == 0.0f) return 0.0f;
    float f = rough_dielectric_eval(wo, wi, p->eta, p->alpha, MICROFACET_GGX) / fabs(wi.z);
    if (importance && wo.z * wi.z < 0.0f) {
        float e = dielectric_eta_from(wo.z, p->eta);
        f *= e * e;
    }
    return f;
}

/* The density of layered_top_sample restricted to `lobes`. */
inline float layered_top_pdf(const LayeredParams *p, float3 wo, float3 wi, int lobes)
{
    if (layered_top_smooth(p)) return 0.0f;
    int reflection = wo.z * wi.z > 0.0f;
    if ((lobes == LAYERED_REFLECTION && !reflection) || (lobes == LAYERED_TRANSMISSION && reflection)) return 0.0f;
    RoughDielectricPair q;
    if (!rough_dielectric_pair(wo, wi, p->eta, &q)) return 0.0f;
    float pdf = rough_dielectric_pdf(wo, wi, p->eta, p->alpha, MICROFACET_GGX);
    if (lobes == LAYERED_ANY) return pdf;
    /* rough_dielectric_pdf chose the lobe with F or 1 − F; a restricted sample takes its one lobe always. */
    float choice = reflection ? q.fresnel : 1.0f - q.fresnel;
    return choice > 0.0f ? pdf / choice : 0.0f;
}

inline int layered_top_sample(const LayeredParams *p, float3 wo, float uc, float2 u, int lobes, int importance,
                              LayerSample *s)
{
    if (wo.z == 0.0f) return 0;
    float e = dielectric_eta_from(wo.z, p->eta);
    int flipped = wo.z < 0.0f;
    float3 v = flipped ? mirror_z(wo) : wo;
    float3 h = (float3)(0.0f, 0.0f, 1.0f);
    int smooth = layered_top_smooth(p);
    if (!smooth) h = microfacet_sample_normal(v, p->alpha, MICROFACET_GGX, u);
    float v_h = dot(v, h);
    if (v_h <= 0.0f) return 0;
    float cos_t;
    float fresnel = fresnel_dielectric_refracting(v_h, e, &cos_t);
    float pr = lobes == LAYERED_TRANSMISSION ? 0.0f : fresnel;
    float pt = lobes == LAYERED_REFLECTION ? 0.0f : 1.0f - fresnel;
    if (!(pr + pt > 0.0f)) return 0;
    int reflection = uc * (pr + pt) < pr;
    float3 wi = reflection ? 2.0f * v_h * h - v : normalize((v_h / e - cos_t) * h - v / e);
    if (reflection ? wi.z <= 0.0f : wi.z >= 0.0f) return 0;
    s->wi = flipped ? mirror_z(wi) : wi;
    s->transmits = !reflection;
    s->is_delta = smooth;
    if (smooth) {
        float lobe = reflection ? pr : pt;
        float scale = reflection || importance ? 1.0f : 1.0f / (e * e);
        s->f = (float4)(lobe * scale / fabs(wi.z));
        s->pdf = lobe / (pr + pt);
    } else {
        s->f = (float4)(layered_top_f(p, wo, s->wi, importance));
        s->pdf = layered_top_pdf(p, wo, s->wi, lobes);
    }
    return s->pdf > 0.0f && layered_nonzero(s->f);
}

/* ---------------------------------------------------------------- the base: reflects from above only */

inline int layered_base_smooth(const LayeredParams *p)
{
    return p->base == LAYERED_CONDUCTOR && ggx_is_smooth(p->base_alpha);
}

inline float4 layered_base_f(const LayeredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    if (p->base == LAYERED_DIFFUSE) return p->reflectance * INV_PI;
    if (layered_base_smooth(p)) return (float4)(0.0f);
    float3 h = reflection_half_vector(wo, wi);
    return fresnel_conductor(dot(wo, h), p->base_eta, p->base_k) *
           (microfacet_reflection_cos(wo, wi, p->base_alpha, MICROFACET_GGX) / wi.z);
}

inline float layered_base_pdf(const LayeredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    if (p->base == LAYERED_DIFFUSE) return wi.z * INV_PI;
    if (layered_base_smooth(p)) return 0.0f;
    return microfacet_reflection_pdf(wo, reflection_half_vector(wo, wi), p->base_alpha, MICROFACET_GGX);
}

inline int layered_base_sample(const LayeredParams *p, float3 wo, float2 u, LayerSample *s)
{
    if (wo.z <= 0.0f) return 0;
    s->transmits = 0;
    s->is_delta = 0;
    if (p->base == LAYERED_DIFFUSE) {
        s->wi = sample_cosine_hemisphere(u);
    } else if (layered_base_smooth(p)) {
        s->wi = reflect_local(wo);
        s->f = fresnel_conductor(wo.z, p->base_eta, p->base_k) / wo.z;
        s->pdf = 1.0f;
        s->is_delta = 1;
        return 1;
    } else {
        s->wi = microfacet_reflect(wo, microfacet_sample_normal(wo, p->base_alpha, MICROFACET_GGX, u));
    }
    if (s->wi.z <= 0.0f) return 0;
    s->f = layered_base_f(p, wo, s->wi);
    s->pdf = layered_base_pdf(p, wo, s->wi);
    return s->pdf > 0.0f;
}

/* ---------------------------------------------------------------- the walk */

/* Only delta lobes: a smooth interface over a smooth base with a slab that does not scatter. */
inline int layered_delta_only(int top_smooth, int base_smooth, int scatters)
{
    return top_smooth && base_smooth && !scatters;
}

/* f(ωo, ωi)·cos θi, estimated. */
inline float4 layered_eval(const LayeredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    int scatters = layered_nonzero(p->albedo);
    int top_smooth = layered_top_smooth(p), base_smooth = layered_base_smooth(p);
    if (layered_delta_only(top_smooth, base_smooth, scatters)) return (float4)(0.0f);
    float4 f = (float4)(p->samples * layered_top_f(p, wo, wi, 0));
    uint rng = layered_hash_direction(layered_hash_direction(0x1a7e12edU, wo), wi);
    const float exit_z = p->thickness;
    for (int sample = 0; sample < p->samples; ++sample) {
        LayerSample wos, wis;
        float uc = layered_random(&rng);
        if (!layered_top_sample(p, wo, uc, layered_random2(&rng), LAYERED_TRANSMISSION, 0, &wos)) continue;
        uc = layered_random(&rng);
        if (!layered_top_sample(p, wi, uc, layered_random2(&rng), LAYERED_TRANSMISSION, 1, &wis)) continue;
        float4 beta = wos.f * (fabs(wos.wi.z) / wos.pdf);
        float4 exit_weight = wis.f / wis.pdf; /* light leaving toward ωi from -wis.wi inside */
        float z = p->thickness;
        float3 w = wos.wi;
        for (int depth = 0; depth < p->max_depth; ++depth) {
            if (depth > 3 && layered_max(beta) < 0.25f) {
                float q = fmax(0.0f, 1.0f - layered_max(beta));
                if (layered_random(&rng) < q) break;
                beta /= 1.0f - q;
            }
            if (!scatters) {
                z = z == p->thickness ? 0.0f : p->thickness;
                beta *= layered_tr(p->thickness, w);
            } else {
                float dz = -log1p(-layered_random(&rng)) * fabs(w.z);
                float zp = w.z > 0.0f ? z + dz : z - dz;
                if (zp == z) continue;
                if (0.0f < zp && zp < p->thickness) {
                    /* Scattered in the slab: join to ωi, then go on along a direction drawn from the phase. */
                    float weight = 1.0f;
                    float phase_exit = henyey_greenstein(dot(w, -wis.wi), p->g);
                    if (!top_smooth) weight = power_heuristic(wis.pdf, phase_exit);
                    f += beta * p->albedo * exit_weight *
                         (phase_exit * weight * layered_tr(zp - exit_z, wis.wi));
                    float3 next = sample_henyey_greenstein(w, p->g, layered_random2(&rng));
                    float phase_pdf = henyey_greenstein(dot(w, next), p->g);
                    if (!(phase_pdf > 0.0f) || next.z == 0.0f) continue;
                    beta *= p->albedo;
                    w = next;
                    z = zp;
                    if (z < exit_z && w.z > 0.0f && !top_smooth) {
                        float f_exit = layered_top_f(p, -w, wi, 0);
                        if (f_exit > 0.0f) {
                            float exit_pdf = layered_top_pdf(p, wi, -w, LAYERED_TRANSMISSION);
                            f += beta * (layered_tr(zp - exit_z, w) * f_exit *
                                         power_heuristic(phase_pdf, exit_pdf));
                        }
                    }
                    continue;
                }
                z = clamp(zp, 0.0f, p->thickness);
            }
            LayerSample bs;
            if (z == exit_z) {
                /* At the interface from inside: only its reflection keeps the walk (leaving is joined above). */
                float uc2 = layered_random(&rng);
                if (!layered_top_sample(p, -w, uc2, layered_random2(&rng), LAYERED_REFLECTION, 0, &bs)) break;
                beta *= bs.f * (fabs(bs.wi.z) / bs.pdf);
                w = bs.wi;
            } else {
                if (!base_smooth) {
                    float weight = 1.0f;
                    if (!top_smooth) weight = power_heuristic(wis.pdf, layered_base_pdf(p, -w, -wis.wi));
                    f += beta * layered_base_f(p, -w, -wis.wi) * exit_weight *
                         (fabs(wis.wi.z) * weight * layered_tr(p->thickness, wis.wi));
                }
                if (!layered_base_sample(p, -w, layered_random2(&rng), &bs)) break;
                beta *= bs.f * (fabs(bs.wi.z) / bs.pdf);
                w = bs.wi;
                if (!top_smooth) {
                    float f_exit = layered_top_f(p, -w, wi, 0);
                    if (f_exit > 0.0f) {
                        float weight = 1.0f;
                        if (!base_smooth)
                            weight = power_heuristic(bs.pdf, layered_top_pdf(p, wi, -w, LAYERED_TRANSMISSION));
                        f += beta * (layered_tr(p->thickness, bs.wi) * f_exit * weight);
                    }
                }
            }
        }
    }
    return f * (wi.z / (float)p->samples);
}

/* The density the MIS weights use, estimated (see the header). */
inline float layered_pdf(const LayeredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    int top_smooth = layered_top_smooth(p), base_smooth = layered_base_smooth(p);
    if (layered_delta_only(top_smooth, base_smooth, layered_nonzero(p->albedo))) return 0.0f;
    uint rng = layered_hash_direction(layered_hash_direction(0x5eed9df1U, wi), wo);
    float sum = p->samples * layered_top_pdf(p, wo, wi, LAYERED_REFLECTION);
    for (int sample = 0; sample < p->samples; ++sample) {
        LayerSample wos, wis, rs;
        float uc = layered_random(&rng);
        int entered = layered_top_sample(p, wo, uc, layered_random2(&rng), LAYERED_TRANSMISSION, 0, &wos);
        uc = layered_random(&rng);
        int joined = layered_top_sample(p, wi, uc, layered_random2(&rng), LAYERED_TRANSMISSION, 1, &wis);
        if (!entered || !joined) continue;
        if (top_smooth) {
            sum += layered_base_pdf(p, -wos.wi, -wis.wi);
            continue;
        }
        if (!layered_base_sample(p, -wos.wi, layered_random2(&rng), &rs)) continue;
        if (base_smooth) {
            sum += layered_top_pdf(p, -rs.wi, wi, LAYERED_ANY);
        } else {
            float r_pdf = layered_base_pdf(p, -wos.wi, -wis.wi);
            sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
            float t_pdf = layered_top_pdf(p, -rs.wi, wi, LAYERED_ANY);
            sum += power_heuristic(rs.pdf, t_pdf) * t_pdf;
        }
    }
    return mix(LAYERED_INV_4PI, sum / (float)p->samples, 0.9f);
}

/* One walk from ωo out through the interface. A non-delta sample reports layered_pdf at its direction. */
inline int layered_sample(const LayeredParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z <= 0.0f) return 0;
    LayerSample bs;
    if (!layered_top_sample(p, wo, uc, u, LAYERED_ANY, 0, &bs)) return 0;
    if (!bs.transmits) {
        if (bs.is_delta) return delta_sample(bs.wi, bs.f * (fabs(bs.wi.z) / bs.pdf), bs.pdf, s);
        return continuous_sample(bs.wi, bs.f * fabs(bs.wi.z) * (layered_pdf(p, wo, bs.wi) / bs.pdf),
                                 layered_pdf(p, wo, bs.wi), s);
    }
    uint rng = layered_mix(layered_hash_direction(0x3c6ef372U, wo),
                           layered_mix(as_uint(uc), layered_mix(as_uint(u.x), as_uint(u.y))));
    int scatters = layered_nonzero(p->albedo);
    float3 w = bs.wi;
    int specular = bs.is_delta;
    /* f·cos / pdf of the walk so far, kept as one ratio (a long walk's f and pdf apart would underflow), and the
     * product of the choices' probabilities, a delta path's pick. */
    float4 beta = bs.f * (fabs(bs.wi.z) / bs.pdf);
    float pick = bs.pdf;
    float z = p->thickness;
    for (int depth = 0; depth < p->max_depth; ++depth) {
        float rr_beta = layered_max(beta);
        if (depth > 3 && rr_beta < 0.25f) {
            float q = fmax(0.0f, 1.0f - rr_beta);
            if (layered_random(&rng) < q) return 0;
            beta /= 1.0f - q;
            pick *= 1.0f - q;
        }
        if (w.z == 0.0f) return 0;
        if (scatters) {
            float dz = -log1p(-layered_random(&rng)) * fabs(w.z);
            float zp = w.z > 0.0f ? z + dz : z - dz;
            if (zp == z) return 0;
            if (0.0f < zp && zp < p->thickness) {
                /* Drawn from the phase function exactly: the ratio gains the albedo alone. */
                float3 next = sample_henyey_greenstein(w, p->g, layered_random2(&rng));
                if (next.z == 0.0f) return 0;
                beta *= p->albedo;
                specular = 0;
                w = next;
                z = zp;
                continue;
            }
            z = clamp(zp, 0.0f, p->thickness);
        } else {
            z = z == p->thickness ? 0.0f : p->thickness;
            beta *= layered_tr(p->thickness, w);
        }
        float uc2 = layered_random(&rng);
        float2 u2 = layered_random2(&rng);
        int ok = z == 0.0f ? layered_base_sample(p, -w, u2, &bs)
                           : layered_top_sample(p, -w, uc2, u2, LAYERED_ANY, 0, &bs);
        if (!ok) return 0;
        beta *= bs.f * (fabs(bs.wi.z) / bs.pdf);
        pick *= bs.pdf;
        specular = specular && bs.is_delta;
        w = bs.wi;
        if (bs.transmits) {
            if (w.z <= 0.0f || !(layered_max(beta) > 0.0f) || !isfinite(layered_max(beta))) return 0;
            if (specular) return delta_sample(w, beta, pick, s);
            float reported = layered_pdf(p, wo, w);
            return continuous_sample(w, beta * reported, reported, s);
        }
    }
    return 0;
}

#endif
