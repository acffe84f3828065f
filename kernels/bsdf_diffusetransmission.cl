/* Lambertian reflection and Lambertian transmission together (a sheet of paper, a lampshade, a leaf): f = R(λ)/π
 * between directions on the same side of the surface, f = T(λ)/π between directions on opposite sides. A
 * surface that is not there in between (no refraction, no medium change): light leaving through the back leaves
 * in a cosine distribution whatever its arrival. pbrt-v4's DiffuseTransmissionBxDF is this model (pbrt-v4,
 * src/pbrt/bxdfs.h; Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., sec. 9.3 exercise and the
 * DiffuseTransmissionMaterial); it is the same from both faces. Energy: R + T ≤ 1 per wavelength. */
#ifndef SPECTRACE_BSDF_DIFFUSETRANSMISSION_CL
#define SPECTRACE_BSDF_DIFFUSETRANSMISSION_CL

#include "bsdf_sample.cl"
#include "sampling.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 reflectance;   /* R(λ), dimensionless, per sampled wavelength */
    float4 transmittance; /* T(λ), dimensionless, per sampled wavelength */
} DiffusetransmissionParams;

/* Light crosses the surface: the frame keeps the winding's normal (either side works: the model is symmetric). */
inline int diffusetransmission_flags(__global const Material *m)
{
    return BSDF_NON_DELTA | BSDF_TRANSMISSION;
}

inline DiffusetransmissionParams diffusetransmission_params(__global const Material *m, const SurfaceContext *sc,
                                                            const SampledWavelengths *w)
{
    DiffusetransmissionParams p;
    p.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    p.transmittance = spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    return p;
}

/* Probability of sampling the reflection lobe: its largest value against the transmission's, as pbrt-v4 picks
 * (any positive split is unbiased; this one keeps the weights bounded by R + T over the chosen side's share).
 * Returns -1 when both lobes are black. */
inline float diffusetransmission_reflect_probability(const DiffusetransmissionParams *p)
{
    float pr = fmax(fmax(p->reflectance.x, p->reflectance.y), fmax(p->reflectance.z, p->reflectance.w));
    float pt = fmax(fmax(p->transmittance.x, p->transmittance.y), fmax(p->transmittance.z, p->transmittance.w));
    pr = fmax(pr, 0.0f);
    pt = fmax(pt, 0.0f);
    return pr + pt > 0.0f ? pr / (pr + pt) : -1.0f;
}

inline float4 diffusetransmission_eval(const DiffusetransmissionParams *p, float3 wo, float3 wi)
{
    float4 lobe = wo.z * wi.z > 0.0f ? p->reflectance : p->transmittance;
    return lobe * (INV_PI * fabs(wi.z));
}

inline float diffusetransmission_pdf(const DiffusetransmissionParams *p, float3 wo, float3 wi)
{
    float pr = diffusetransmission_reflect_probability(p);
    if (pr < 0.0f || wi.z == 0.0f) return 0.0f;
    return (wo.z * wi.z > 0.0f ? pr : 1.0f - pr) * fabs(wi.z) * INV_PI;
}

/* uc picks the side (reflection with diffusetransmission_reflect_probability), u a cosine-weighted direction on
 * it; the weight f·|cos| / pdf is then the chosen lobe's value over the probability of choosing it. */
inline int diffusetransmission_sample(const DiffusetransmissionParams *p, float3 wo, float uc, float2 u,
                                      BSDFSample *s)
{
    float pr = diffusetransmission_reflect_probability(p);
    if (pr < 0.0f) return 0;
    float3 wi = sample_cosine_hemisphere(u);
    int reflect = uc < pr;
    float side = wo.z >= 0.0f ? 1.0f : -1.0f;
    wi.z *= reflect ? side : -side;
    float pick = reflect ? pr : 1.0f - pr;
    s->wi = wi;
    s->pdf = pick * fabs(wi.z) * INV_PI;
    s->weight = (reflect ? p->reflectance : p->transmittance) / pick;
    s->is_delta = 0;
    s->radiance_scale = 1.0f;
    return s->pdf > 0.0f;
}

#endif
