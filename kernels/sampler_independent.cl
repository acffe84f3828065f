/* Independent sampler: every random number is a hash of (seed, pixel, sample index, dimension), with no
 * stratification between the samples of a pixel. */
#ifndef SPECTRACE_SAMPLER_INDEPENDENT_CL
#define SPECTRACE_SAMPLER_INDEPENDENT_CL

#include "hash.cl"

typedef struct {
    uint stream;     /* hash of seed, pixel and sample index */
    uint dimension;  /* next dimension to draw */
} IndependentSampler;

inline IndependentSampler independent_start(uint seed, uint pixel, uint sample_index)
{
    IndependentSampler s;
    s.stream = hash_u32(hash_u32(hash_u32(seed ^ 0x5bd1e995U) ^ pixel) ^ (sample_index * 0x9e3779b9U + 0x632be5abU));
    s.dimension = 0;
    return s;
}

/* Uniform in [0, 1): the top 24 bits, so the value is exactly representable and never rounds up to 1. */
inline float independent_1d(IndependentSampler *s)
{
    uint h = hash_u32(s->stream ^ hash_u32(s->dimension * 0x85ebca6bU + 0xc2b2ae35U));
    s->dimension += 1;
    return (float)(h >> 8) * 0x1.0p-24f;
}

inline float2 independent_2d(IndependentSampler *s)
{
    float u = independent_1d(s);
    return (float2)(u, independent_1d(s));
}

#endif
