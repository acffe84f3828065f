/* Watertight ray/triangle intersection (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection",
 * JCGT 2(1)): the ray is sheared so that it runs along +z through the origin, and the 2D edge functions of the
 * projected triangle decide the hit. Edges shared by two triangles are never missed by both. */
#ifndef SPECTRACE_TRIANGLE_CL
#define SPECTRACE_TRIANGLE_CL

/* The edge functions must be evaluated as written: fused multiply-adds round differently for the two products
 * of each edge function, so a triangle collapsed to a point would get non-zero edge values and report hits. */
#pragma OPENCL FP_CONTRACT OFF

#include "ray.cl"

/* Per-ray constants of the shear, computed once per ray. */
typedef struct {
    uint4 permutation;  /* (kx, ky, kz, 3) for shuffle */
    float3 shear;       /* (Sx, Sy, Sz) */
} RayShear;

inline RayShear ray_shear(float3 direction)
{
    float3 a = fabs(direction);
    uint kz = (a.x > a.y) ? ((a.x > a.z) ? 0u : 2u) : ((a.y > a.z) ? 1u : 2u);
    uint kx = (kz + 1u) % 3u;
    uint ky = (kx + 1u) % 3u;
    float4 d4 = (float4)(direction, 0.0f);
    float4 dz = shuffle(d4, (uint4)(kz, kz, kz, 3u));
    if (dz.x < 0.0f) {  /* keep the winding: swap x and y when the ray runs toward -z */
        uint t = kx; kx = ky; ky = t;
    }
    RayShear s;
    s.permutation = (uint4)(kx, ky, kz, 3u);
    float4 d = shuffle(d4, s.permutation);
    s.shear = (float3)(-d.x / d.z, -d.y / d.z, 1.0f / d.z);
    return s;
}

/* Returns the hit distance in (0, t_max), or t_max when there is none; barycentrics of v1 and v2 in *b12. */
inline float intersect_triangle(float4 origin4, const RayShear *s, float4 v0, float4 v1, float4 v2,
                                float t_max, float2 *b12)
{
    float4 a = shuffle(v0 - origin4, s->permutation);
    float4 b = shuffle(v1 - origin4, s->permutation);
    float4 c = shuffle(v2 - origin4, s->permutation);
    float ax = mad(s->shear.x, a.z, a.x), ay = mad(s->shear.y, a.z, a.y);
    float bx = mad(s->shear.x, b.z, b.x), by = mad(s->shear.y, b.z, b.y);
    float cx = mad(s->shear.x, c.z, c.x), cy = mad(s->shear.y, c.z, c.y);
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return t_max;
    float det = u + v + w;
    if (det == 0.0f) return t_max;
    float t_scaled = u * (s->shear.z * a.z) + v * (s->shear.z * b.z) + w * (s->shear.z * c.z);
    float t = t_scaled / det;
    if (!(t > 0.0f && t < t_max)) return t_max;
    *b12 = (float2)(v, w) / det;
    return t;
}

#endif
