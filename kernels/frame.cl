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

/* The frame whose tangent is d's part normal to `normal` (Gram-Schmidt), as Mitsuba 3 builds its shading frame
 * from dp/du (SurfaceInteraction::initialize_sh_frame), the bitangent completing a right-handed frame; the
 * normal's own basis where d has no such part (0, parallel to it, or not finite). */
inline ShadingFrame shading_frame_along(float3 normal, float3 d)
{
    float3 t = d - normal * dot(normal, d);
    float length_t = length(t);
    if (!(length_t > 0.0f) || !isfinite(length_t)) return shading_frame(normal);
    ShadingFrame f;
    f.normal = normal;
    f.tangent = t / length_t;
    f.bitangent = cross(normal, f.tangent);
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
