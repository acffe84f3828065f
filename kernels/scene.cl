/* The scene as the integrators see it: the device buffers of one render, bundled. */
#ifndef SPECTRACE_SCENE_CL
#define SPECTRACE_SCENE_CL

#include "types.h"
#include "bvh.cl"
#include "lights.cl"

typedef struct {
    __global const RenderParams *params;
    __global const BVHNode *nodes;
    __global const float4 *triangle_vertices;
    __global const float2 *triangle_uvs;
    __global const TriangleInfo *triangle_info;
    __global const Material *materials;
    __global const Light *lights;
    __global const float *light_cdf;
    __global const float *spectra;
    __global const float4 *texels;  /* images of environment maps and textured emitters (a dummy texel if none) */
    __global const float *map_cdf;
} Scene;

inline LightBuffers light_buffers(const Scene *scene)
{
    LightBuffers b = {scene->triangle_vertices, scene->triangle_uvs, scene->spectra, scene->texels, scene->map_cdf};
    return b;
}

/* The closest surface along the ray (none in a scene without triangles). */
inline Hit scene_intersect(const Scene *scene, Ray ray, uint *rays_traced)
{
    *rays_traced += 1;
    if (scene->params->triangle_count == 0) {
        Hit miss;
        miss.t = INFINITY;
        miss.triangle = -1;
        miss.b12 = (float2)(0.0f);
        return miss;
    }
    return trace_bvh(scene->nodes, scene->triangle_vertices, ray, INFINITY, 0);
}

/* Whether anything blocks the segment from `from` (already offset off its surface) to `to`; `to` may be at
 * infinity (distant and environment lights), then `direction` is used. */
inline int scene_occluded(const Scene *scene, float3 from, float3 to, float3 direction, int to_infinity,
                          uint *rays_traced)
{
    if (scene->params->triangle_count == 0) return 0;
    *rays_traced += 1;
    Ray shadow;
    shadow.origin = from;
    float t_max = INFINITY;
    if (to_infinity) {
        shadow.direction = direction;
    } else {
        float3 d = to - from;
        float length_d = length(d);
        if (!(length_d > 0.0f)) return 0;
        shadow.direction = d / length_d;
        t_max = length_d * 0.9999f;  /* stop just short of the light's own surface */
    }
    return trace_bvh(scene->nodes, scene->triangle_vertices, shadow, t_max, 1).triangle >= 0;
}

#endif
