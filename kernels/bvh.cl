/* Closest-hit and any-hit traversal of the flattened BVH (see types.h for the node layout). */
#ifndef SPECTRACE_BVH_CL
#define SPECTRACE_BVH_CL

#include "types.h"
#include "triangle.cl"

#define BVH_STACK_SIZE 64

typedef struct {
    float t;         /* distance along the ray; t_max when nothing was hit */
    int triangle;    /* slot in the triangle arrays, or -1 */
    float2 b12;      /* barycentric coordinates of v1 and v2 */
} Hit;

/* Distance at which the ray enters the box, or INFINITY when it misses it before t_max. The exit distance is widened by 2γ₃
 * (Ize 2013, "Robust BVH Ray Traversal") so rounding never rejects a box the ray touches, e.g. a flat box
 * hit exactly on its edge, where a shared triangle edge lies. */
inline float ray_box_entry(__global const BVHNode *node, float3 origin, float3 inv_direction, float t_max)
{
    float3 lo = ((float3)(node->bmin[0], node->bmin[1], node->bmin[2]) - origin) * inv_direction;
    float3 hi = ((float3)(node->bmax[0], node->bmax[1], node->bmax[2]) - origin) * inv_direction;
    float3 near = fmin(lo, hi), far = fmax(lo, hi);
    float enter = fmax(fmax(near.x, near.y), fmax(near.z, 0.0f));
    float leave = fmin(fmin(far.x, far.y), far.z) * 1.0000004f;
    leave = fmin(leave, t_max);
    return enter <= leave ? enter : INFINITY;
}

/* any_hit: stop at the first hit closer than t_max (shadow rays).
 * Both children's boxes are tested from the parent and the nearer is entered first; the farther one is pushed
 * with its entry distance, so a pop drops it without reading its box again once a closer hit is known.
 * Scalar reads of the node on purpose: reading it as two float4, or carrying the child's node data down from the
 * parent's test, measured slower on at least one CPU runtime (docs/performance.md). */
inline Hit trace_bvh(__global const BVHNode *nodes, __global const float4 *triangle_vertices, Ray ray, float t_max,
                     int any_hit)
{
    Hit hit;
    hit.t = t_max;
    hit.triangle = -1;
    hit.b12 = (float2)(0.0f);
    /* A zero direction component would give 0 * inf = NaN for an origin on a slab plane; a tiny one of the same
     * sign keeps every product finite and treats the ray as leaning to that side, which the edge-inclusive
     * triangle test agrees with. */
    float3 tiny = copysign((float3)(1.0e-30f), ray.direction);
    float3 inv_direction = 1.0f / select(ray.direction, tiny, fabs(ray.direction) < (float3)(1.0e-30f));
    float4 origin4 = (float4)(ray.origin, 0.0f);
    RayShear shear = ray_shear(ray.direction);
    int stack[BVH_STACK_SIZE];
    float stack_entry[BVH_STACK_SIZE];  /* where the ray enters each pushed node's box */
    int top = 0;
    int index = 0;
    if (ray_box_entry(&nodes[0], ray.origin, inv_direction, t_max) == INFINITY) return hit;
    while (true) {
        __global const BVHNode *node = &nodes[index];
        if (node->count > 0) {
            for (int i = node->left_first; i < node->left_first + node->count; ++i) {
                float2 b12;
                float t = intersect_triangle(origin4, &shear, triangle_vertices[3 * i], triangle_vertices[3 * i + 1],
                                             triangle_vertices[3 * i + 2], hit.t, &b12);
                if (t < hit.t) {
                    hit.t = t;
                    hit.triangle = i;
                    hit.b12 = b12;
                    if (any_hit) return hit;
                }
            }
        } else {
            int left = node->left_first;
            float t_left = ray_box_entry(&nodes[left], ray.origin, inv_direction, hit.t);
            float t_right = ray_box_entry(&nodes[left + 1], ray.origin, inv_direction, hit.t);
            if (t_left != INFINITY || t_right != INFINITY) {
                int near_child = t_left <= t_right ? left : left + 1;
                int far_child = t_left <= t_right ? left + 1 : left;
                if (fmax(t_left, t_right) != INFINITY) {
                    stack[top] = far_child;
                    stack_entry[top] = fmax(t_left, t_right);
                    ++top;
                }
                index = near_child;
                continue;
            }
        }
        /* Pop, skipping nodes that a closer hit found since has made irrelevant. Entering before hit.t is the
         * whole test: the box's exit was checked against a t_max no smaller than hit.t when it was pushed. */
        while (true) {
            if (top == 0) return hit;
            --top;
            if (stack_entry[top] <= hit.t) { index = stack[top]; break; }
        }
    }
}

#endif
