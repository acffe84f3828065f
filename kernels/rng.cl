/* The sampler the kernels draw from: `sampler_start(seed, pixel, sample_index)`, then `sample_1d` and `sample_2d`
 * in a fixed order. A draw depends only on (seed, pixel, sample index, draw number), so a pixel's samples are the
 * same however the render is split into passes or work-items.
 *
 * The sampler is chosen when the program is built: SAMPLER_SOBOL=1 selects the Owen-scrambled Sobol sampler
 * (sampler_sobol.cl), anything else the independent one (sampler_independent.cl). */
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

#else

#include "sampler_independent.cl"
typedef IndependentSampler Sampler;

inline Sampler sampler_start(uint seed, uint pixel, uint sample_index)
{
    return independent_start(seed, pixel, sample_index);
}

inline float sample_1d(Sampler *s) { return independent_1d(s); }
inline float2 sample_2d(Sampler *s) { return independent_2d(s); }

#endif

#endif
