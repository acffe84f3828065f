/* Test harness: closest hit of each ray against the BVH, so tests can compare with a brute-force reference. */
#include "kernel_entry.h"
#include "bvh.cl"

KERNEL void closest_hit(__global const BVHNode *nodes, __global const float4 *triangle_vertices,
                          __global const float4 *origins, __global const float4 *directions,
                          __global float *hit_t, __global int *hit_triangle, int ray_count)
{
    int i = get_global_id(0);
    if (i >= ray_count) return;
    Ray ray;
    ray.origin = origins[i].xyz;
    ray.direction = directions[i].xyz;
    Hit hit = trace_bvh(nodes, triangle_vertices, ray, INFINITY, 0);
    hit_t[i] = hit.t;
    hit_triangle[i] = hit.triangle;
}

/* Any-hit query up to t_max: 1 when something is closer, for shadow-ray tests. */
KERNEL void any_hit(__global const BVHNode *nodes, __global const float4 *triangle_vertices,
                      __global const float4 *origins, __global const float4 *directions,
                      __global const float *t_max, __global int *occluded, int ray_count)
{
    int i = get_global_id(0);
    if (i >= ray_count) return;
    Ray ray;
    ray.origin = origins[i].xyz;
    ray.direction = directions[i].xyz;
    occluded[i] = trace_bvh(nodes, triangle_vertices, ray, t_max[i], 1).triangle >= 0;
}
