/* Lambertian reflection f = R(λ)/π. Both faces reflect: the shading normal is flipped to the side the light
 * arrives from, so meshes work whatever their winding (Mitsuba 3 needs a `twosided` wrapper for this). */
#ifndef SPECTRACE_BSDF_DIFFUSE_CL
#define SPECTRACE_BSDF_DIFFUSE_CL

#include "sampling.cl"

/* n faces the outgoing direction; cos_i = dot(n, ωi). Returns f(ωo, ωi) without the cosine. */
inline float4 diffuse_eval(float4 reflectance, float cos_i)
{
    return cos_i > 0.0f ? reflectance * INV_PI : (float4)(0.0f);
}

inline float diffuse_pdf(float cos_i)
{
    return cos_i > 0.0f ? cos_i * INV_PI : 0.0f;
}

/* Samples ωi about n; the weight f cos / pdf of a Lambertian surface is its reflectance. */
inline float3 diffuse_sample(float3 n, float2 u)
{
    float3 t, b;
    orthonormal_basis(n, &t, &b);
    float3 d = sample_cosine_hemisphere(u);
    return d.x * t + d.y * b + d.z * n;
}

#endif
