/* Counter-based sampler: every random number is a hash of (seed, pixel, sample index, dimension), so a pixel's
 * samples are the same however the render is split into passes or work-items. */
#ifndef SPECTRACE_RNG_CL
#define SPECTRACE_RNG_CL

/* 32-bit integer finaliser with low avalanche bias ("lowbias32", C. Wellons, public-domain constants). */
inline uint hash_u32(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

typedef struct {
    uint stream;     /* hash of seed, pixel and sample index */
    uint dimension;  /* next dimension to draw */
} Sampler;

inline Sampler sampler_start(uint seed, uint pixel, uint sample_index)
{
    Sampler s;
    s.stream = hash_u32(hash_u32(hash_u32(seed ^ 0x5bd1e995U) ^ pixel) ^ (sample_index * 0x9e3779b9U + 0x632be5abU));
    s.dimension = 0;
    return s;
}

/* Uniform in [0, 1): the top 24 bits, so the value is exactly representable and never rounds up to 1. */
inline float sample_1d(Sampler *s)
{
    uint h = hash_u32(s->stream ^ hash_u32(s->dimension * 0x85ebca6bU + 0xc2b2ae35U));
    s->dimension += 1;
    return (float)(h >> 8) * 0x1.0p-24f;
}

inline float2 sample_2d(Sampler *s)
{
    float u = sample_1d(s);
    return (float2)(u, sample_1d(s));
}

#endif
