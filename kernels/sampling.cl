/* Warps from the unit square to the domains the integrator samples, with their densities. */
#ifndef SPECTRACE_SAMPLING_CL
#define SPECTRACE_SAMPLING_CL

#define INV_PI 0.31830988618379067f
#define TWO_PI 6.283185307179586f

/* Orthonormal basis around a unit normal (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"). */
inline void orthonormal_basis(float3 n, float3 *tangent, float3 *bitangent)
{
    float sign = copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    *tangent = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *bitangent = (float3)(b, sign + n.y * n.y * a, -n.y);
}

/* (cos 2πt, sin 2πt): cospi and sinpi reduce their argument exactly and cheaply, where cos and sin of 2πt would
 * each run a general argument reduction. */
inline float2 cos_sin_turns(float t)
{
    return (float2)(cospi(2.0f * t), sinpi(2.0f * t));
}

/* Cosine-weighted direction about +z (Malley's method: uniform disk point lifted to the hemisphere);
 * pdf = cos θ / π per steradian. */
inline float3 sample_cosine_hemisphere(float2 u)
{
    float r = sqrt(u.x);
    float2 disk = r * cos_sin_turns(u.y);
    float z = sqrt(fmax(0.0f, 1.0f - u.x));
    return (float3)(disk.x, disk.y, z);
}

/* Cosine-weighted direction about the unit vector n, world space; pdf = cos θ / π (cosine_hemisphere_pdf). */
inline float3 sample_cosine_about(float3 n, float2 u)
{
    float3 t, b;
    orthonormal_basis(n, &t, &b);
    float3 d = sample_cosine_hemisphere(u);
    return d.x * t + d.y * b + d.z * n;
}

inline float cosine_hemisphere_pdf(float cos_theta)
{
    return cos_theta > 0.0f ? cos_theta * INV_PI : 0.0f;
}

/* Uniform point on a triangle, as barycentrics of (v1, v2); pdf = 1 / area. */
inline float2 sample_triangle_uniform(float2 u)
{
    float s = sqrt(u.x);
    return (float2)(u.y * s, 1.0f - s);
}

inline float power_heuristic(float pdf_a, float pdf_b)
{
    float a = pdf_a * pdf_a;
    float b = pdf_b * pdf_b;
    return (a + b) > 0.0f ? a / (a + b) : 0.0f;
}

#endif
