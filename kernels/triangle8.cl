/* The watertight ray/triangle test of triangle.cl on eight triangles at once: a leaf block of the 8-wide BVH
 * (host/spectrace/geometry/triangle_blocks.py, eight lanes) holds each coordinate of each vertex for eight triangles
 * in one float8, so every step of the test runs on the eight lanes together. Each lane computes exactly what
 * intersect_triangle computes for its triangle (triangle4.cl's steps, in float8), and the nearest lane (the first of
 * equal ones) wins, so a leaf gives the hit the one-by-one loop gives. */
#ifndef SPECTRACE_TRIANGLE8_CL
#define SPECTRACE_TRIANGLE8_CL

#pragma OPENCL FP_CONTRACT OFF

#include "triangle.cl"

/* A block is 10 float8: nine of coordinates, then one whose first four ints are (first triangle slot, triangles in
 * the block, 1 when another block of the leaf follows, 0). */
#define LEAF_BLOCK8_FLOAT8S 10

/* Tests one block against hits closer than *t_hit; on a hit updates *t_hit, *triangle and *b12 and returns 1.
 * origin_k: the ray origin's coordinates in the shear's order (kx, ky, kz). */
inline int intersect_triangles8(__global const float8 *block, float3 origin_k, const RayShear *s, int4 meta,
                                float *t_hit, int *triangle, float2 *b12)
{
    uint kx = s->permutation.x, ky = s->permutation.y, kz = s->permutation.z;
    float8 ox = (float8)(origin_k.x), oy = (float8)(origin_k.y), oz = (float8)(origin_k.z);
    float8 sx = (float8)(s->shear.x), sy = (float8)(s->shear.y), sz = (float8)(s->shear.z);
    float8 a_x = block[kx] - ox, a_y = block[ky] - oy, a_z = block[kz] - oz;
    float8 b_x = block[3 + kx] - ox, b_y = block[3 + ky] - oy, b_z = block[3 + kz] - oz;
    float8 c_x = block[6 + kx] - ox, c_y = block[6 + ky] - oy, c_z = block[6 + kz] - oz;
    float8 ax = mad(sx, a_z, a_x), ay = mad(sy, a_z, a_y);
    float8 bx = mad(sx, b_z, b_x), by = mad(sy, b_z, b_y);
    float8 cx = mad(sx, c_z, c_x), cy = mad(sy, c_z, c_y);
    float8 u = cx * by - cy * bx;
    float8 v = ax * cy - ay * cx;
    float8 w = bx * ay - by * ax;
    float8 zero = (float8)(0.0f);
    int8 outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
    float8 det = u + v + w;
    float8 t = (u * (sz * a_z) + v * (sz * b_z) + w * (sz * c_z)) / det;
    int8 lane_index = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    int8 hit = ~outside & (det != zero) & (t > zero) & (t < (float8)(*t_hit)) & (lane_index < (int8)(meta.y));
    if (!any(hit)) return 0;
    float8 t_lanes = select((float8)(INFINITY), t, hit);
    float4 t_half = fmin(t_lanes.lo, t_lanes.hi);
    float2 t_quarter = fmin(t_half.lo, t_half.hi);
    float t_min = fmin(t_quarter.x, t_quarter.y);
    /* The first lane at the nearest distance, as the one-by-one loop's strict "closer than" keeps it. */
    int8 candidates = select((int8)(8), lane_index, t_lanes == (float8)(t_min));
    int4 lane_half = min(candidates.lo, candidates.hi);
    int2 lane_quarter = min(lane_half.lo, lane_half.hi);
    int lane = min(lane_quarter.x, lane_quarter.y);
    float values[3][8];
    vstore8(v, 0, values[0]);
    vstore8(w, 0, values[1]);
    vstore8(det, 0, values[2]);
    *t_hit = t_min;
    *triangle = meta.x + lane;
    *b12 = (float2)(values[0][lane], values[1][lane]) / values[2][lane];
    return 1;
}

#endif
