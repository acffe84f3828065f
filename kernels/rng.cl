/* The sampler the kernels draw from: `sampler_start(seed, pixel, sample_index)`, then `sample_1d` and `sample_2d`
 * in a fixed order. A draw depends only on (seed, pixel, sample index, draw number), so a pixel's samples are the
 * same however the render is split into passes or work-items.
 *
 * The sampler is chosen when the program is built: SAMPLER_SOBOL=1 selects the Owen-scrambled Sobol sampler
 * (sampler_sobol.cl), anything else the independent one (sampler_independent.cl).
 *
 * `sampler_identity(s)` names the point a sample has reached (seed, pixel, sample index and draws made so far) by
 * a hash of the state, without drawing: for choices that must not take a dimension of the sequence (a cut-out's,
 * scene.cl's surface_met). */
#ifndef SPECTRACE_RNG_CL
#define SPECTRACE_RNG_CL

#if defined(SAMPLER_SOBOL) && SAMPLER_SOBOL

#include "sampler_sobol.cl"
typedef SobolSampler Sampler;

inline Sampler sampler_start(uint seed, uint pixel, uint sample_index)
{
    return sobol_start(seed, pixel, sample_index);
}

inline float sample_1d(Sampler *s) { return sobol_1d(s); }
inline float2 sample_2d(Sampler *s) { return sobol_2d(s); }

inline uint sampler_identity(const Sampler *s)
{
    return hash_u32(hash_u32(s->pixel_seed ^ hash_u32(s->reversed_index)) ^ s->group);
}

#else

#include "sampler_independent.cl"
typedef IndependentSampler Sampler;

inline Sampler sampler_start(uint seed, uint pixel, uint sample_index)
{
    return independent_start(seed, pixel, sample_index);
}

inline float sample_1d(Sampler *s) { return independent_1d(s); }
inline float2 sample_2d(Sampler *s) { return independent_2d(s); }

inline uint sampler_identity(const Sampler *s)
{
    return hash_u32(s->stream ^ hash_u32(s->dimension));
}

#endif

#endif
