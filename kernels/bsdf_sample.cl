/* What sampling a BSDF returns. Inside a bsdf_*.cl file `wi` is in the local shading frame; material.cl turns it
 * into world space before the integrators see it. */
#ifndef SPECTRACE_BSDF_SAMPLE_CL
#define SPECTRACE_BSDF_SAMPLE_CL

typedef struct {
    float3 wi;                /* sampled direction, unit */
    float4 weight;            /* f(wo,wi)·|cos θi| / pdf per wavelength: the throughput multiplier */
    float pdf;                /* solid-angle pdf of wi (for MIS); for a delta lobe, the probability of picking it */
    int is_delta;             /* 1 when wi came from a specular (delta) lobe: no MIS, no NEE at this event */
    int terminate_secondary;  /* 1 when the event was dispersive: keep only the hero wavelength */
    float radiance_scale;     /* the (n_o/n_i)² in `weight` from refraction into another index (1 otherwise): the
                                 radiance compression, which Russian roulette divides out (as Mitsuba 3 does) */
} BSDFSample;

/* A sample of a delta lobe picked with probability `pick`, carrying f·cos/pdf = `weight`. */
inline int delta_sample(float3 wi, float4 weight, float pick, BSDFSample *s)
{
    s->wi = wi;
    s->weight = weight;
    s->pdf = pick;
    s->is_delta = 1;
    s->terminate_secondary = 0;
    s->radiance_scale = 1.0f;
    return pick > 0.0f;
}

/* A sample of a non-delta lobe: weight = f·cos / pdf, or nothing when the pdf or the cosine vanishes. */
inline int continuous_sample(float3 wi, float4 f_cos, float pdf, BSDFSample *s)
{
    s->wi = wi;
    s->pdf = pdf;
    s->is_delta = 0;
    s->terminate_secondary = 0;
    s->radiance_scale = 1.0f;
    s->weight = pdf > 0.0f ? f_cos / pdf : (float4)(0.0f);
    return pdf > 0.0f;
}

#endif
