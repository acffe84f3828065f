/* The watertight ray/triangle test of triangle.cl on four triangles at once: a leaf block of the 4-wide BVH
 * (host/spectrace/geometry/triangle_blocks.py) holds each coordinate of each vertex for four triangles in one
 * float4, so every step of the test runs on the four lanes together. Each lane computes exactly what
 * intersect_triangle computes for its triangle, and the nearest lane (the first of equal ones) wins, so a leaf
 * gives the hit the one-by-one loop gives. */
#ifndef SPECTRACE_TRIANGLE4_CL
#define SPECTRACE_TRIANGLE4_CL

#pragma OPENCL FP_CONTRACT OFF

#include "triangle.cl"

/* A block is LEAF_BLOCK_FLOAT4S float4 (a build define from spectrace.core.contract; spectrace.geometry.triangle_blocks
 * packs the blocks). */

/* Tests one block against hits closer than *t_hit; on a hit updates *t_hit, *triangle and *b12 and returns 1.
 * origin_k: the ray origin's coordinates in the shear's order (kx, ky, kz). */
inline int intersect_triangles4(__global const float4 *block, float3 origin_k, const RayShear *s, int4 meta,
                                float *t_hit, int *triangle, float2 *b12)
{
    uint kx = s->permutation.x, ky = s->permutation.y, kz = s->permutation.z;
    float4 ox = (float4)(origin_k.x), oy = (float4)(origin_k.y), oz = (float4)(origin_k.z);
    float4 sx = (float4)(s->shear.x), sy = (float4)(s->shear.y), sz = (float4)(s->shear.z);
    float4 a_x = block[kx] - ox, a_y = block[ky] - oy, a_z = block[kz] - oz;
    float4 b_x = block[3 + kx] - ox, b_y = block[3 + ky] - oy, b_z = block[3 + kz] - oz;
    float4 c_x = block[6 + kx] - ox, c_y = block[6 + ky] - oy, c_z = block[6 + kz] - oz;
    float4 ax = mad(sx, a_z, a_x), ay = mad(sy, a_z, a_y);
    float4 bx = mad(sx, b_z, b_x), by = mad(sy, b_z, b_y);
    float4 cx = mad(sx, c_z, c_x), cy = mad(sy, c_z, c_y);
    float4 u = cx * by - cy * bx;
    float4 v = ax * cy - ay * cx;
    float4 w = bx * ay - by * ax;
    float4 zero = (float4)(0.0f);
    int4 outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
    float4 det = u + v + w;
    float4 t = (u * (sz * a_z) + v * (sz * b_z) + w * (sz * c_z)) / det;
    int4 hit = ~outside & (det != zero) & (t > zero) & (t < (float4)(*t_hit)) & ((int4)(0, 1, 2, 3) < (int4)(meta.y));
    if (!any(hit)) return 0;
    float4 t_lanes = select((float4)(INFINITY), t, hit);
    float t_min = fmin(fmin(t_lanes.s0, t_lanes.s1), fmin(t_lanes.s2, t_lanes.s3));
    int lane = t_lanes.s0 == t_min ? 0 : t_lanes.s1 == t_min ? 1 : t_lanes.s2 == t_min ? 2 : 3;
    float v_hit = lane == 0 ? v.s0 : lane == 1 ? v.s1 : lane == 2 ? v.s2 : v.s3;
    float w_hit = lane == 0 ? w.s0 : lane == 1 ? w.s1 : lane == 2 ? w.s2 : w.s3;
    float det_hit = lane == 0 ? det.s0 : lane == 1 ? det.s1 : lane == 2 ? det.s2 : det.s3;
    *t_hit = t_min;
    *triangle = meta.x + lane;
    *b12 = (float2)(v_hit, w_hit) / det_hit;
    return 1;
}

#endif
