/* Integer hashing shared by the samplers. */
#ifndef SPECTRACE_HASH_CL
#define SPECTRACE_HASH_CL

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

#endif
