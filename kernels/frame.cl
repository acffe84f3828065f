/* The local shading frame BSDFs work in: the normal is +z, so cos θ of a direction is its z component and a
 * BSDF needs no world-space vectors. */
#ifndef SPECTRACE_FRAME_CL
#define SPECTRACE_FRAME_CL

#include "sampling.cl"

typedef struct {
    float3 tangent;
    float3 bitangent;
    float3 normal;
} ShadingFrame;

inline ShadingFrame shading_frame(float3 normal)
{
    ShadingFrame f;
    f.normal = normal;
    orthonormal_basis(normal, &f.tangent, &f.bitangent);
    return f;
}

inline float3 to_local(const ShadingFrame *f, float3 v)
{
    return (float3)(dot(v, f->tangent), dot(v, f->bitangent), dot(v, f->normal));
}

inline float3 to_world(const ShadingFrame *f, float3 v)
{
    return v.x * f->tangent + v.y * f->bitangent + v.z * f->normal;
}

/* Mirror reflection about the local normal (+z). */
inline float3 reflect_local(float3 v)
{
    return (float3)(-v.x, -v.y, v.z);
}

#endif
