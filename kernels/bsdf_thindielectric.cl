/* A thin dielectric sheet (a window pane, a soap film without interference): two parallel smooth interfaces of
 * relative index η so close together that a ray leaves where it entered. Light is reflected specularly or goes
 * straight through, undeviated (the two refractions cancel); the sheet does not absorb.
 *
 * With R = F(|cos θo|), the smooth interface's Fresnel reflectance (fresnel.cl), and T = 1 − R, the light bouncing
 * between the two faces sums to
 *     R' = R + T² R / (1 − R²) = 2R / (1 + R),     T' = 1 − R' = T / (1 + R)
 * (the incoherent sum of the multiple reflections in a slab; Born & Wolf, "Principles of Optics", sec. 1.6, for the
 * amplitudes; Mitsuba 3's thindielectric uses the same R'). Both lobes are delta lobes: reflection about the normal
 * with R', transmission along −ωo with T', each times an optional tint (specular_reflectance,
 * specular_transmittance). The sheet is the same from both sides. */
#ifndef SPECTRACE_BSDF_THINDIELECTRIC_CL
#define SPECTRACE_BSDF_THINDIELECTRIC_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "fresnel.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float eta;            /* index of the sheet relative to the outside, the same on both sides */
    float4 reflectance;   /* tint of the reflection (1 without one) */
    float4 transmittance; /* tint of the transmission (1 without one) */
} ThindielectricParams;

/* Light crosses the sheet; it is the same from both sides, so the frame's side decides nothing. */
inline int thindielectric_flags(__global const Material *m)
{
    return BSDF_DELTA | BSDF_TRANSMISSION;
}

inline ThindielectricParams thindielectric_params(__global const Material *m, const SurfaceContext *sc,
                                                  const SampledWavelengths *w)
{
    ThindielectricParams p;
    p.eta = m->ior;
    p.reflectance = m->reflectance_offset == MATERIAL_NO_SPECTRUM
                        ? (float4)(1.0f)
                        : surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.transmittance = m->transmittance_offset == MATERIAL_NO_SPECTRUM
                          ? (float4)(1.0f)
                          : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    return p;
}

/* R' = 2R / (1 + R) for light arriving at |cos θ| = cos_theta. */
inline float thindielectric_reflectance(float cos_theta, float eta)
{
    float r = fresnel_dielectric(fabs(cos_theta), eta);
    return 2.0f * r / (1.0f + r);
}

inline float4 thindielectric_eval(const ThindielectricParams *p, float3 wo, float3 wi)
{
    return (float4)(0.0f);
}

inline float thindielectric_pdf(const ThindielectricParams *p, float3 wo, float3 wi)
{
    return 0.0f;
}

/* Reflection picked with probability R', transmission with T': each lobe's weight is then its tint alone. */
inline int thindielectric_sample(const ThindielectricParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    float r = thindielectric_reflectance(wo.z, p->eta);
    if (uc < r) return delta_sample(reflect_local(wo), p->reflectance, r, s);
    return delta_sample(-wo, p->transmittance, 1.0f - r, s);
}

#endif
