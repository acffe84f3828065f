/* The scene as the integrators see it: the device buffers of one render, bundled. */
#ifndef SPECTRACE_SCENE_CL
#define SPECTRACE_SCENE_CL

#include "types.h"
#include "bvh.cl"
#include "lights.cl"
#include "medium.cl"

typedef struct {
    __global const RenderParams *params;
    __global const BVHNode *nodes;
    __global const float4 *triangle_vertices;
    __global const float2 *triangle_uvs;
    __global const float4 *triangle_normals;  /* shading normals of the smooth triangles' corners (TriangleInfo) */
    __global const TriangleInfo *triangle_info;
    __global const Material *materials;
    __global const Light *lights;
    __global const float *light_cdf;
    __global const float *spectra;
    __global const float4 *texels;  /* images of environment maps and textured emitters (a dummy texel if none) */
    __global const float *map_cdf;
    __global const Medium *media;
} Scene;

/* The parameters every scene kernel starts with: the render's parameters, then the scene's buffers in the order
 * spectrace.engine.device_types.SCENE_KERNEL_BUFFERS names them (the host sets them from that list). A kernel
 * declared with them makes its Scene with `Scene scene = SCENE_FROM_KERNEL_PARAMS;`. */
#define SCENE_KERNEL_PARAMS                                                                                        \
    __global const RenderParams *params, __global const BVHNode *nodes, __global const float4 *triangle_vertices, \
        __global const float2 *triangle_uvs, __global const float4 *triangle_normals,                             \
        __global const TriangleInfo *triangle_info, __global const Material *materials,                           \
        __global const Light *lights, __global const float *light_cdf, __global const float *spectra,             \
        __global const float4 *texels, __global const float *map_cdf, __global const Medium *media
#define SCENE_FROM_KERNEL_PARAMS                                                                                   \
    {params, nodes, triangle_vertices, triangle_uvs, triangle_normals, triangle_info, materials, lights,           \
     light_cdf, spectra, texels, map_cdf, media}

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

/* The fraction of light per wavelength that crosses the same segment as scene_occluded: 0 when a surface blocks
 * it, else exp(−Σ σt·length) over the media whose material-less (index-matched) boundaries it passes, so shadow
 * rays see what a path would (Beer–Lambert). Each stretch's medium follows from the boundary that ends it:
 * leaving a shape along its outward normal means the stretch was inside the shape. */
inline float4 scene_transmittance(const Scene *scene, const SampledWavelengths *w, float3 from, float3 to,
                                  float3 direction, int to_infinity, uint *rays_traced)
{
    if (!SCENE_HAS_MEDIA || scene->params->medium_count == 0) {
        return scene_occluded(scene, from, to, direction, to_infinity, rays_traced) ? (float4)(0.0f)
                                                                                     : (float4)(1.0f);
    }
    if (scene->params->triangle_count == 0) return (float4)(1.0f);
    Ray segment;
    segment.origin = from;
    float t_end = INFINITY;  /* along the whole segment, from `from` */
    if (to_infinity) {
        segment.direction = direction;
    } else {
        float3 d = to - from;
        float length_d = length(d);
        if (!(length_d > 0.0f)) return (float4)(1.0f);
        segment.direction = d / length_d;
        t_end = length_d * 0.9999f;  /* stop just short of the light's own surface */
    }
    float4 optical_depth = (float4)(0.0f);
    int medium_ahead = -1;
    float t_origin = 0.0f;
    for (int crossing = 0; crossing <= MAX_NULL_CROSSINGS; ++crossing) {
        *rays_traced += 1;
        Hit hit = trace_bvh(scene->nodes, scene->triangle_vertices, segment, fmax(t_end - t_origin, 0.0f), 0);
        if (hit.triangle < 0) {
            if (medium_ahead < 0) return exp(-optical_depth);
            if (isinf(t_end)) return (float4)(0.0f);  /* a leak out of a closed medium: light cannot get through */
            float4 sigma_t = medium_sigma_t(&scene->media[medium_ahead], scene->spectra, w);
            return exp(-(optical_depth + sigma_t * fmax(t_end - t_origin, 0.0f)));
        }
        TriangleInfo info = scene->triangle_info[hit.triangle];
        if (info.material != TRIANGLE_NO_MATERIAL) return (float4)(0.0f);
        float3 n = triangle_normal(scene->triangle_vertices, hit.triangle);
        if (dot(n, segment.direction) > 0.0f && info.interior >= 0) {
            optical_depth += medium_sigma_t(&scene->media[info.interior], scene->spectra, w) * hit.t;
        }
        medium_ahead = medium_beyond(info.interior, n, segment.direction);
        float3 p = triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
        segment.origin = offset_ray_origin(p, n, segment.direction);
        t_origin = dot(segment.origin - from, segment.direction);
    }
    return (float4)(0.0f);
}

#endif
