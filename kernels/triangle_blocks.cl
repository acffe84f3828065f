/* The watertight ray/triangle test of triangle.cl on a leaf block of four or eight triangles at once: a block of the
 * 4- or 8-wide BVH (host/spectrace/geometry/triangle_blocks.py) holds each coordinate of each vertex for its
 * triangles in one float4 or float8, so every step of the test runs on all lanes together. Each lane computes exactly
 * what intersect_triangle computes for its triangle, and the nearest lane (the first of equal ones) wins, so a leaf
 * gives the hit the one-by-one loop gives. */
#ifndef SPECTRACE_TRIANGLE_BLOCKS_CL
#define SPECTRACE_TRIANGLE_BLOCKS_CL

#pragma OPENCL FP_CONTRACT OFF

#include "triangle.cl"

/* A block of L lanes is nine vectors of L floats, vertex a's x, y, z, then b's, then c's, and one whose first four
 * ints are (first triangle slot, triangles in the block, 1 when another block of the leaf follows, 0): for four
 * lanes LEAF_BLOCK_FLOAT4S float4 (a build define from spectrace.core.contract), for eight LEAF_BLOCK8_FLOAT8S
 * float8. spectrace.geometry.triangle_blocks packs them. */
#define LEAF_BLOCK8_FLOAT8S 10

#define TRIANGLE_LANE_INDEX4 ((int4)(0, 1, 2, 3))
#define TRIANGLE_LANE_INDEX8 ((int8)(0, 1, 2, 3, 4, 5, 6, 7))

/* The pick of the hit: the nearest lane of t_lanes (INFINITY where a lane missed), the first of equal ones as the
 * one-by-one loop's strict "closer than" keeps it, written to *t_hit, *triangle (first: the block's first triangle
 * slot) and *b12 = (v, w) / det of that lane. Per width: scalar compares for four lanes, halving reductions and a
 * read back through private memory for eight. */
inline void nearest_lane4(float4 t_lanes, float4 v, float4 w, float4 det, int first, float *t_hit, int *triangle,
                          float2 *b12)
{
    float t_min = fmin(fmin(t_lanes.s0, t_lanes.s1), fmin(t_lanes.s2, t_lanes.s3));
    int lane = t_lanes.s0 == t_min ? 0 : t_lanes.s1 == t_min ? 1 : t_lanes.s2 == t_min ? 2 : 3;
    float v_hit = lane == 0 ? v.s0 : lane == 1 ? v.s1 : lane == 2 ? v.s2 : v.s3;
    float w_hit = lane == 0 ? w.s0 : lane == 1 ? w.s1 : lane == 2 ? w.s2 : w.s3;
    float det_hit = lane == 0 ? det.s0 : lane == 1 ? det.s1 : lane == 2 ? det.s2 : det.s3;
    *t_hit = t_min;
    *triangle = first + lane;
    *b12 = (float2)(v_hit, w_hit) / det_hit;
}

inline void nearest_lane8(float8 t_lanes, float8 v, float8 w, float8 det, int first, float *t_hit, int *triangle,
                          float2 *b12)
{
    float4 t_half = fmin(t_lanes.lo, t_lanes.hi);
    float2 t_quarter = fmin(t_half.lo, t_half.hi);
    float t_min = fmin(t_quarter.x, t_quarter.y);
    int8 candidates = select((int8)(8), TRIANGLE_LANE_INDEX8, t_lanes == (float8)(t_min));
    int4 lane_half = min(candidates.lo, candidates.hi);
    int2 lane_quarter = min(lane_half.lo, lane_half.hi);
    int lane = min(lane_quarter.x, lane_quarter.y);
    float values[3][8];
    vstore8(v, 0, values[0]);
    vstore8(w, 0, values[1]);
    vstore8(det, 0, values[2]);
    *t_hit = t_min;
    *triangle = first + lane;
    *b12 = (float2)(values[0][lane], values[1][lane]) / values[2][lane];
}

/* intersect_triangles4 and intersect_triangles8, one definition written out for each width L by the preprocessor
 * (OpenCL C 1.2 has no generic vector width): tests one block of L lanes against hits closer than *t_hit; on a hit
 * updates *t_hit, *triangle and *b12 and returns 1. origin_k: the ray origin's coordinates in the shear's order
 * (kx, ky, kz); meta: the block's last vector as ints. */
#define INTERSECT_TRIANGLES(L)                                                                                      \
    inline int intersect_triangles##L(__global const float##L *block, float3 origin_k, const RayShear *s, int4 meta, \
                                      float *t_hit, int *triangle, float2 *b12)                                     \
    {                                                                                                               \
        uint kx = s->permutation.x, ky = s->permutation.y, kz = s->permutation.z;                                   \
        float##L ox = (float##L)(origin_k.x), oy = (float##L)(origin_k.y), oz = (float##L)(origin_k.z);             \
        float##L sx = (float##L)(s->shear.x), sy = (float##L)(s->shear.y), sz = (float##L)(s->shear.z);             \
        float##L a_x = block[kx] - ox, a_y = block[ky] - oy, a_z = block[kz] - oz;                                  \
        float##L b_x = block[3 + kx] - ox, b_y = block[3 + ky] - oy, b_z = block[3 + kz] - oz;                      \
        float##L c_x = block[6 + kx] - ox, c_y = block[6 + ky] - oy, c_z = block[6 + kz] - oz;                      \
        float##L ax = mad(sx, a_z, a_x), ay = mad(sy, a_z, a_y);                                                    \
        float##L bx = mad(sx, b_z, b_x), by = mad(sy, b_z, b_y);                                                    \
        float##L cx = mad(sx, c_z, c_x), cy = mad(sy, c_z, c_y);                                                    \
        float##L u = cx * by - cy * bx;                                                                             \
        float##L v = ax * cy - ay * cx;                                                                             \
        float##L w = bx * ay - by * ax;                                                                             \
        float##L zero = (float##L)(0.0f);                                                                           \
        int##L outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));           \
        float##L det = u + v + w;                                                                                   \
        float##L t = (u * (sz * a_z) + v * (sz * b_z) + w * (sz * c_z)) / det;                                      \
        int##L hit = ~outside & (det != zero) & (t > zero) & (t < (float##L)(*t_hit))                               \
                     & (TRIANGLE_LANE_INDEX##L < (int##L)(meta.y));                                                 \
        if (!any(hit)) return 0;                                                                                    \
        nearest_lane##L(select((float##L)(INFINITY), t, hit), v, w, det, meta.x, t_hit, triangle, b12);             \
        return 1;                                                                                                   \
    }

INTERSECT_TRIANGLES(4)
INTERSECT_TRIANGLES(8)

#endif
