/* What every BSDF file shares: the sample it returns (inside a bsdf_*.cl file `wi` is in the local shading frame;
 * material.cl turns it into world space before the integrators see it) and the flags it states for itself. */
#ifndef SPECTRACE_BSDF_SAMPLE_CL
#define SPECTRACE_BSDF_SAMPLE_CL

/* What kind of lobes a material has, as its <name>_flags(m) states from its Material row alone (no spectra), so
 * the integrators can decide what to do at a vertex before evaluating anything. */
#define BSDF_DELTA 1         /* a delta lobe: found only by sampling it, so no next-event estimation or MIS for it */
#define BSDF_NON_DELTA 2     /* a lobe with a density: next-event estimation and MIS apply */
#define BSDF_TRANSMISSION 4  /* light crosses the surface: the shading frame keeps the geometric normal, whose side
                                says which medium is where, instead of turning toward the viewer */
#define BSDF_DISPERSIVE 8    /* the index of refraction depends on the wavelength: refraction sends each wavelength
                                its own way */

typedef struct {
    float3 wi;                /* sampled direction, unit */
    float4 weight;            /* f(wo,wi)·|cos θi| / pdf per wavelength: the throughput multiplier */
    float pdf;                /* solid-angle pdf of wi (for MIS); for a delta lobe, the probability of picking it */
    int is_delta;             /* 1 when wi came from a specular (delta) lobe: no MIS, no NEE at this event */
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
    s->radiance_scale = 1.0f;
    return pick > 0.0f;
}

/* A sample of a non-delta lobe: weight = f·cos / pdf, or nothing when the pdf or the cosine vanishes. */
inline int continuous_sample(float3 wi, float4 f_cos, float pdf, BSDFSample *s)
{
    s->wi = wi;
    s->pdf = pdf;
    s->is_delta = 0;
    s->radiance_scale = 1.0f;
    s->weight = pdf > 0.0f ? f_cos / pdf : (float4)(0.0f);
    return pdf > 0.0f;
}

#endif
