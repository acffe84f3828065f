/* Owen-scrambled Sobol sampler with hash-based scrambling and shuffling, after B. Burley 2020, "Practical
 * Hash-based Owen Scrambling", JCGT 9(4).
 *
 * Each draw of a sample (one sample_1d or sample_2d call) is its own low-dimensional group: a 1D draw takes Sobol's
 * first dimension (the van der Corput sequence), a 2D draw its first two, which together are a (0,2)-sequence in
 * base 2. Per pixel and group, seeded by hashes of (seed, pixel, group):
 * - the sample index is shuffled by a nested uniform (Owen) scramble of its bits. That maps every aligned block of
 *   2^k indices onto another aligned block, so the first 2^k samples of a pixel (and any aligned 2^k of them) are
 *   a whole block of the sequence: a 1D draw has one point in each [i/2^k, (i+1)/2^k), a 2D draw is a
 *   (0,k,2)-net. Different shuffles per group decorrelate the groups, which would otherwise all walk the same
 *   sequence in step;
 * - each coordinate is Owen-scrambled, which keeps those nets and makes every single sample uniformly distributed
 *   (Owen 1995), so an estimate is unbiased for any sample count, a power of two or not; a count that is not a
 *   power of two is just less evenly stratified.
 * The index is the sample's index within its pixel, the same however the render is split into passes. */
#ifndef SPECTRACE_SAMPLER_SOBOL_CL
#define SPECTRACE_SAMPLER_SOBOL_CL

#include "hash.cl"

typedef struct {
    uint pixel_seed;      /* hash of seed and pixel */
    uint reversed_index;  /* the sample index with its bits reversed: the form the shuffle works on */
    uint group;           /* next draw */
} SobolSampler;

inline uint reverse_bits(uint x)
{
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffU) << 8) | ((x >> 8) & 0x00ff00ffU);
    x = ((x & 0x0f0f0f0fU) << 4) | ((x >> 4) & 0x0f0f0f0fU);
    x = ((x & 0x33333333U) << 2) | ((x >> 2) & 0x33333333U);
    x = ((x & 0x55555555U) << 1) | ((x >> 1) & 0x55555555U);
    return x;
}

/* A seeded bijection of 32-bit words in which bit k of the result is bit k of x flipped by a function of bits
 * 0..k-1 only: adding the seed, and xoring x with even multiples of itself, carry information upward only
 * (Laine & Karras 2011; the multipliers are those Burley 2020 found to scramble best). On a bit-reversed word this
 * is a nested uniform (Owen) scramble: each binary digit of a point in [0, 1) is flipped by a function of the
 * digits before it. The added seed alone makes the result uniform over all words whatever x is. */
inline uint upward_scramble(uint x, uint seed)
{
    x += seed;
    x ^= x * 0x6c50b47cU;
    x ^= x * 0xb82f1e52U;
    x ^= x * 0xc7afe638U;
    x ^= x * 0x8d22f6e6U;
    return x;
}

/* Sobol's second dimension, in bit-reversed form, of the index `shuffled`. Its generator matrix is Pascal's
 * triangle mod 2 (primitive polynomial x + 1): reversed, the column of index bit j is (1 + x)^j, whose bit i is
 * C(j, i) mod 2 = [the binary digits of i are a subset of those of j] (Lucas' theorem). So bit i of the result is
 * the parity of the set index bits j whose positions are supersets of i's: a superset-sum transform over the five
 * bits of a bit position, one shift-and-xor per position bit. */
inline uint sobol_second_dimension_reversed(uint shuffled)
{
    uint r = shuffled;
    r ^= (r >> 1) & 0x55555555U;
    r ^= (r >> 2) & 0x33333333U;
    r ^= (r >> 4) & 0x0f0f0f0fU;
    r ^= (r >> 8) & 0x00ff00ffU;
    r ^= (r >> 16) & 0x0000ffffU;
    return r;
}

/* [0, 1) from the top 24 bits, exactly representable, never rounding up to 1. */
inline float sobol_unit_float(uint x)
{
    return (float)(x >> 8) * 0x1.0p-24f;
}

inline SobolSampler sobol_start(uint seed, uint pixel, uint sample_index)
{
    SobolSampler s;
    s.pixel_seed = hash_u32(hash_u32(seed ^ 0x3c6ef372U) ^ (pixel * 0x9e3779b9U + 0x1b873593U));
    s.reversed_index = reverse_bits(sample_index);
    s.group = 0;
    return s;
}

inline uint sobol_group_seed(SobolSampler *s)
{
    uint seed = hash_u32(s->pixel_seed + s->group * 0x9e3779b9U);
    s->group += 1;
    return seed;
}

/* The van der Corput point of the shuffled index is the reversed shuffled index itself: the shuffle's output
 * before its final reversal. */
inline float sobol_1d(SobolSampler *s)
{
    uint seed = sobol_group_seed(s);
    uint van_der_corput = upward_scramble(s->reversed_index, seed);
    return sobol_unit_float(reverse_bits(upward_scramble(reverse_bits(van_der_corput), hash_u32(seed ^ 0x68e31da4U))));
}

inline float2 sobol_2d(SobolSampler *s)
{
    uint seed = sobol_group_seed(s);
    uint van_der_corput = upward_scramble(s->reversed_index, seed);
    uint shuffled = reverse_bits(van_der_corput);
    uint x = reverse_bits(upward_scramble(shuffled, hash_u32(seed ^ 0x68e31da4U)));
    uint y = reverse_bits(upward_scramble(sobol_second_dimension_reversed(shuffled), hash_u32(seed ^ 0xb5297a4dU)));
    return (float2)(sobol_unit_float(x), sobol_unit_float(y));
}

#endif
