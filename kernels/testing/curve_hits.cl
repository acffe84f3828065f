/* Test harness: rays against one linear curve segment (kernels/curve.cl). Per ray: (t, u, h, hit) and the normal;
 * the segment is (a, ra) and (b, rb) in xyz, w. */
#include "kernel_entry.h"
#include "curve.cl"

KERNEL void curve_segment_hits(__global const float4 *origins, __global const float4 *directions, float4 a, float4 b,
                               __global float4 *result, __global float4 *normal)
{
    int i = get_global_id(0);
    CurveHit hit = intersect_curve_segment(origins[i].xyz, directions[i].xyz, 0.0f, INFINITY, a.xyz, a.w, b.xyz, b.w);
    int found = hit.t < INFINITY;
    result[i] = found ? (float4)(hit.t, hit.u, hit.h, 1.0f) : (float4)(0.0f);
    normal[i] = found ? (float4)(hit.n, 0.0f) : (float4)(0.0f);
}
