/* Test harness: the scene's closest-hit and any-hit queries (kernels/scene.cl trace_scene, instances included) on
 * given rays, and the surface a path sees at each hit (path_state.cl path_vertex), so tests can compare a scene of
 * instanced objects with the same scene expanded into copies and with a brute-force intersection. */
#include "kernel_entry.h"
#include "path_state.cl"

/* hit: (t, u, v, material) with t = INFINITY on a miss; point, normal, shading: the vertex's world-space p, geometric
 * n and shading ns (xyz); occluded: whether anything lies before t_max along the ray (the any-hit query). */
KERNEL void scene_hits(SCENE_KERNEL_PARAMS, __global const float4 *origins, __global const float4 *directions,
                       __global const float *t_max, __global float4 *hit, __global float4 *point,
                       __global float4 *normal, __global float4 *shading, __global int *occluded, int ray_count)
{
    int i = get_global_id(0);
    if (i >= ray_count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    Ray ray;
    ray.origin = origins[i].xyz;
    ray.direction = directions[i].xyz;
    occluded[i] = trace_scene(&scene, ray, t_max[i], 1).triangle >= 0;
    Hit h = trace_scene(&scene, ray, INFINITY, 0);
    if (h.triangle < 0) {
        hit[i] = (float4)(INFINITY, 0.0f, 0.0f, -1.0f);
        point[i] = normal[i] = shading[i] = (float4)(0.0f);
        return;
    }
    PathVertex v = path_vertex(&scene, h, ray);
    hit[i] = (float4)(h.t, v.uv, (float)v.info.material);
    point[i] = (float4)(v.p, 0.0f);
    normal[i] = (float4)(v.n, 0.0f);
    shading[i] = (float4)(v.ns, 0.0f);
}
