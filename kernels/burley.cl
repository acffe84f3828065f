/* What the two principled BSDFs (bsdf_principled.cl, bsdf_principledthin.cl) share: Schlick's weight
 * (1 − cos θ)⁵ of Burley's diffuse, sheen and Fresnel terms (Burley 2012, "Physically Based Shading at Disney",
 * sec. 5.3), and the read of a weight from their parameter blocks. Dimensionless. */
#ifndef SPECTRACE_BURLEY_CL
#define SPECTRACE_BURLEY_CL

#include "texture.cl"

/* (1 − c)⁵ for c the cosine of an angle, clamped to [0, 1]. */
inline float schlick_weight(float c)
{
    float x = clamp(1.0f - c, 0.0f, 1.0f);
    float x2 = x * x;
    return x2 * x2 * x;
}

/* Weight k of a parameter block (its value at 2k, its texture's index at 2k + 1: spectrace.materials.principled's
 * write_row), clamped to [0, 1]. */
inline float principled_weight(const SurfaceContext *sc, __global const float *block, int k,
                               const SampledWavelengths *w)
{
    return clamp(surface_scalar(sc, (int)block[2 * k + 1], block[2 * k], w), 0.0f, 1.0f);
}

#endif
