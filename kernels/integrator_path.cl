/* The global model: unidirectional path tracing with next-event estimation and multiple importance sampling
 * (power heuristic), Russian roulette, four wavelengths per path.
 *
 * Megakernel: one work-item per pixel runs the pass's samples in sample-index order and adds each to the film
 * one at a time, so the float sums do not depend on how a render is split into passes. */
#include "types.h"
#include "rng.cl"
#include "wavelengths.cl"
#include "spectrum.cl"
#include "camera.cl"
#include "bvh.cl"
#include "bsdf_diffuse.cl"
#include "lights.cl"

/* Longest path when max_depth is unbounded (-1): Russian roulette ends paths long before this. */
#define UNBOUNDED_DEPTH 1024

typedef struct {
    __global const RenderParams *params;
    __global const BVHNode *nodes;
    __global const float4 *triangle_vertices;
    __global const TriangleInfo *triangle_info;
    __global const Material *materials;
    __global const Light *lights;
    __global const float *light_cdf;
    __global const float *spectra;
} Scene;

/* Next-event estimate at a diffuse vertex: radiance arriving from one sampled light point, MIS-weighted against
 * BSDF sampling, times f cos / pdf. */
inline float4 estimate_direct_light(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, float3 p,
                                    float3 n, float4 reflectance, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    if (params->light_count == 0) return (float4)(0.0f);
    float u_pick = sample_1d(sampler);
    float2 u_point = sample_2d(sampler);
    __global const Light *light = &scene->lights[pick_light(scene->light_cdf, params->light_count, u_pick)];
    float3 q = triangle_point(scene->triangle_vertices, light->triangle, sample_triangle_uniform(u_point));
    float3 n_light = triangle_normal(scene->triangle_vertices, light->triangle);
    float3 to_light = q - p;
    float distance = length(to_light);
    if (!(distance > 0.0f)) return (float4)(0.0f);
    float3 wi = to_light / distance;
    float cos_surface = dot(n, wi);
    if (cos_surface <= 0.0f) return (float4)(0.0f);
    float4 emitted = light_emitted(light, scene->spectra, w, n_light, -wi);
    if (all(emitted == (float4)(0.0f))) return (float4)(0.0f);
    float pdf_light = light_pdf_solid_angle(light, distance, fabs(dot(n_light, wi)));
    if (!(pdf_light > 0.0f)) return (float4)(0.0f);

    /* The shadow ray joins the two offset points, stopping just short of the light's side: aimed along wi
     * instead, a ray grazing the light's face could cross it before its end and find the light itself. */
    Ray shadow;
    shadow.origin = offset_ray_origin(p, n, wi);
    float3 to_light_side = offset_ray_origin(q, n_light, -wi) - shadow.origin;
    float shadow_length = length(to_light_side);
    shadow.direction = to_light_side / shadow_length;
    *rays_traced += 1;
    Hit blocker = trace_bvh(scene->nodes, scene->triangle_vertices, shadow, shadow_length * 0.9999f, 1);
    if (blocker.triangle >= 0) return (float4)(0.0f);

    float weight = power_heuristic(pdf_light, diffuse_pdf(cos_surface));
    return diffuse_eval(reflectance, cos_surface) * emitted * (cos_surface * weight / pdf_light);
}

inline float4 trace_path(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray,
                         uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int max_segments = params->max_depth < 0 ? UNBOUNDED_DEPTH : params->max_depth;
    float4 radiance = (float4)(0.0f);
    float4 throughput = (float4)(1.0f);
    float previous_bsdf_pdf = 0.0f;  /* solid-angle pdf of the direction that produced `ray`; 0 for the camera */
    float3 previous_point = ray.origin;

    for (int segments = 1; segments <= max_segments; ++segments) {
        *rays_traced += 1;
        Hit hit = trace_bvh(scene->nodes, scene->triangle_vertices, ray, INFINITY, 0);
        if (hit.triangle < 0) break;

        TriangleInfo info = scene->triangle_info[hit.triangle];
        float3 p = triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
        float3 n_geometric = triangle_normal(scene->triangle_vertices, hit.triangle);
        float3 wo = -ray.direction;

        if (info.light >= 0) {
            __global const Light *light = &scene->lights[info.light];
            float4 emitted = light_emitted(light, scene->spectra, w, n_geometric, wo);
            float weight = 1.0f;
            if (previous_bsdf_pdf > 0.0f) {
                float pdf_light = light_pdf_solid_angle(light, distance(previous_point, p), fabs(dot(n_geometric, wo)));
                weight = power_heuristic(previous_bsdf_pdf, pdf_light);
            }
            radiance += throughput * emitted * weight;
        }
        if (segments >= max_segments) break;

        /* Shading frame on the side the path arrives from (two-sided surfaces). */
        float3 n = dot(n_geometric, wo) >= 0.0f ? n_geometric : -n_geometric;
        __global const Material *material = &scene->materials[info.material];
        float4 reflectance = spectrum_at(scene->spectra, material->reflectance_offset, w);

        radiance += throughput * estimate_direct_light(scene, w, sampler, p, n, reflectance, rays_traced);

        float3 wi = diffuse_sample(n, sample_2d(sampler));
        float cos_i = dot(n, wi);
        previous_bsdf_pdf = diffuse_pdf(cos_i);
        if (!(previous_bsdf_pdf > 0.0f)) break;
        throughput *= reflectance;  /* f cos / pdf of a Lambertian surface */

        /* Russian roulette once `segments` bounces have happened (Mitsuba 3's rr_depth). */
        float u_rr = sample_1d(sampler);
        if (segments >= params->rr_depth) {
            float q = fmin(fmax(fmax(throughput.x, throughput.y), fmax(throughput.z, throughput.w)), 0.95f);
            if (!(u_rr < q)) break;
            throughput /= q;
        }
        if (all(throughput == (float4)(0.0f))) break;

        previous_point = p;
        ray.origin = offset_ray_origin(p, n_geometric, wi);
        ray.direction = wi;
    }
    return radiance;
}

/* film: per pixel (ΣX, ΣY, ΣZ, number of dropped non-finite samples); ray_counts: rays traced per pixel, for
 * the benchmark's rays/s (wraps past 2³² rays per pixel, far beyond any render). */
__kernel void render_pass(__global const RenderParams *params, __global const BVHNode *nodes,
                          __global const float4 *triangle_vertices, __global const TriangleInfo *triangle_info,
                          __global const Material *materials, __global const Light *lights,
                          __global const float *light_cdf, __global const float *spectra,
                          __global const float4 *cmf, __global float4 *film, __global uint *ray_counts)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    Scene scene = {params, nodes, triangle_vertices, triangle_info, materials, lights, light_cdf, spectra};
    int pixel_x = pixel % params->width;
    int pixel_y = pixel / params->width;

    float4 accumulated = film[pixel];
    uint rays_traced = 0;
    for (int s = params->sample_begin; s < params->sample_begin + params->sample_count; ++s) {
        Sampler sampler = sampler_start((uint)params->seed, (uint)pixel, (uint)s);
        SampledWavelengths w = sample_wavelengths(sample_1d(&sampler));
        Ray ray = camera_ray(params, pixel_x, pixel_y, sample_2d(&sampler));
        float4 radiance = trace_path(&scene, &w, &sampler, ray, &rays_traced);
        float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, &w);
        if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) {
            accumulated += xyz;
        } else {
            accumulated.w += 1.0f;
        }
    }
    film[pixel] = accumulated;
    ray_counts[pixel] += rays_traced;
}
