/* Test harness: kernels/shapes.cl's intersection and surface of one analytic shape per ray, and its light sampling
 * (the sphere's cone, any shape's area), so tests can compare with Mitsuba 3 and with closed forms. */
#include "kernel_entry.h"
#include "shapes.cl"

/* hit: (t, u, v, unused) with t = INFINITY on a miss; p, n, dpdu, dpdv: the rebuilt surface (xyz; w: its area
 * stretch in p). */
KERNEL void shape_hits(__global const AnalyticShape *shapes, __global const float4 *origins,
                         __global const float4 *directions, __global float4 *hit, __global float4 *p,
                         __global float4 *n, __global float4 *dpdu, __global float4 *dpdv, int ray_count)
{
    int i = get_global_id(0);
    if (i >= ray_count) return;
    __global const AnalyticShape *s = &shapes[i];
    float2 uv = (float2)(0.0f);
    float t = intersect_shape(s, origins[i].xyz, directions[i].xyz, INFINITY, &uv);
    hit[i] = (float4)(t, uv, 0.0f);
    ShapeSurface g = shape_surface(s, uv);
    p[i] = (float4)(g.p, g.area_stretch);
    n[i] = (float4)(g.n, 0.0f);
    dpdu[i] = (float4)(g.dpdu, 0.0f);
    dpdv[i] = (float4)(g.dpdv, 0.0f);
}

/* Directions toward a sphere (centre, radius in sphere.xyz, w) from `from`, drawn in its cone from u: the direction
 * (xyz) and its solid-angle pdf (w); the sampled point (xyz) and 1 − cos θmax (w). */
KERNEL void sphere_cone_samples(float4 sphere, float4 from, __global const float2 *u, __global float4 *direction,
                                  __global float4 *point, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    float3 n;
    float pdf;
    float3 q = sample_sphere_cone(sphere.xyz, sphere.w, from.xyz, u[i], &n, &pdf);
    direction[i] = (float4)(normalize(q - from.xyz), pdf);
    point[i] = (float4)(q, sphere_cone_one_minus_cos(sphere.xyz, sphere.w, from.xyz));
}

/* Points drawn uniformly over the shape's object-space area from u: the point (xyz) and its density over world
 * area (w). */
KERNEL void shape_area_samples(__global const AnalyticShape *shape, __global const float2 *u,
                                 __global float4 *point, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    ShapeSurface g = shape_surface(shape, shape_sample_uv(shape, u[i]));
    point[i] = (float4)(g.p, shape_area_pdf(shape, g.area_stretch));
}
