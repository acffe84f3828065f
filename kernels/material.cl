/* Material dispatch: the integrators see every BSDF through these four functions.
 * (Diffuse only so far; the BSDF library adds its types here.) */
#ifndef SPECTRACE_MATERIAL_CL
#define SPECTRACE_MATERIAL_CL

#include "types.h"
#include "spectrum.cl"
#include "bsdf_diffuse.cl"

typedef struct {
    float3 wi;                /* sampled direction, world space, unit */
    float4 weight;            /* f(wo,wi)·|cos θi| / pdf per wavelength: the throughput multiplier */
    float pdf;                /* solid-angle pdf of wi (for MIS); for a delta lobe, the probability of picking it */
    int is_delta;             /* 1 when wi came from a specular (delta) lobe: no MIS, no NEE at this event */
    int terminate_secondary;  /* 1 when the event was dispersive: keep only the hero wavelength */
} BSDFSample;

/* n faces wo for two-sided reflectors. */
inline float3 facing(float3 n, float3 wo)
{
    return dot(n, wo) >= 0.0f ? n : -n;
}

inline float4 material_eval(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                            float3 n, float3 wo, float3 wi)
{
    float3 nf = facing(n, wo);
    float cos_i = dot(nf, wi);
    return diffuse_eval(spectrum_at(spectra, m->reflectance_offset, w), cos_i) * fmax(cos_i, 0.0f);
}

inline float material_pdf(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                          float3 n, float3 wo, float3 wi)
{
    return diffuse_pdf(dot(facing(n, wo), wi));
}

inline int material_sample(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                           float3 n, float3 wo, float uc, float2 u, BSDFSample *s)
{
    float3 nf = facing(n, wo);
    s->wi = diffuse_sample(nf, u);
    s->pdf = diffuse_pdf(dot(nf, s->wi));
    s->weight = spectrum_at(spectra, m->reflectance_offset, w);
    s->is_delta = 0;
    s->terminate_secondary = 0;
    return s->pdf > 0.0f;
}

inline int material_has_non_delta_lobe(__global const Material *m)
{
    return 1;
}

#endif
