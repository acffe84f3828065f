/* Measurement sensors: irradiance, radiance and flux meters, spectral and in SI units.
 *
 * Each work-item measures one wavelength (all four lanes carry it, so a dispersive event's termination of the
 * secondary lanes leaves the lane average unbiased) over `samples_per_item` samples with its own random stream;
 * the host combines the items of each wavelength into a mean and its standard error. The program is built without
 * SAMPLER_SOBOL, so sensors use the independent sampler (rng.cl). */
#include "kernel_entry.h"
#include "path_tracer.cl"

/* E(p, n) = ∫ L cos θ dω over the hemisphere of n = π × the radiance an albedo-1, one-sided Lambertian surface at p
 * would reflect: next-event estimation plus a cosine-sampled path, weighted by MIS as on any diffuse surface. This
 * is the first part, the light point's share (the sum so far of that radiance); the path leaving along the
 * cosine-sampled direction is *path (throughput 1: albedo 1, f cos / pdf = 1), to follow when *follow. The caller
 * traces it, so the program holds one copy of the path tracer for every kind of meter: each inlined call is
 * another, and the build's time grows faster than the program (three copies took 124 s on PoCL). */
inline float4 irradiance_start(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, float3 p,
                               float3 n, uint *rays_traced, PathState *path, int *follow)
{
    __global const RenderParams *params = scene->params;
    float4 reflected = (float4)(0.0f);
    float u_pick = sample_1d(sampler);
    float2 u_light = sample_2d(sampler);
    if (params->light_count > 0) {
        __global const Light *light = &scene->lights[pick_light(scene->light_cdf, params->light_count, u_pick)];
        LightSample ls;
        LightBuffers buffers = light_buffers(scene);
        if (sample_light(light, &buffers, w, p, u_light, &ls)) {
            float cos_i = dot(n, ls.wi);
            float3 to = LIGHT_ON_SURFACE(light) ? offset_ray_origin(ls.point, ls.normal, -ls.wi) : ls.point;
            float4 transmittance = cos_i > 0.0f
                                 ? scene_transmittance(scene, w, -1, p, to, ls.wi, isinf(ls.distance),
                                                       opacity_query(sampler, 0u, QUERY_SHADOW), rays_traced)
                                 : (float4)(0.0f);
            if (any(transmittance != (float4)(0.0f))) {
                float weight = ls.is_delta ? 1.0f : power_heuristic(ls.pdf, cos_i * INV_PI);
                reflected += transmittance * ls.arriving * (cos_i * INV_PI * weight / ls.pdf);
            }
        }
    }
    float3 wi = sample_cosine_about(n, sample_2d(sampler));
    float pdf = cosine_hemisphere_pdf(dot(n, wi));
    Ray ray;
    ray.origin = p;
    ray.direction = wi;
    *path = camera_path(ray);
    path->previous_pdf = pdf;
    path->previous_delta = 0;
    *follow = pdf > 0.0f;
    return reflected;
}

KERNEL void measure(SCENE_KERNEL_PARAMS, __global const MeterParams *meter, __global const float *wavelengths,
                      int wavelength_count, __global float *item_means)
{
    int item = get_global_id(0);
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = fixed_wavelengths((float4)(wavelengths[item % wavelength_count]));
    uint rays_traced = 0;
    float sum = 0.0f;
    for (int s = 0; s < meter->samples_per_item; ++s) {
        Sampler sampler = sampler_start((uint)meter->seed, (uint)item, (uint)s);
        /* A sensor's rays can repeat exactly from sample to sample; its cut-out choices still differ, since each
         * query's identity holds the sample's (opacity_query). */
        PathState path;
        int follow = 1;
        float4 direct = (float4)(0.0f);
        float area = 0.0f; /* the flux meter's sphere; 0: irradiance at the meter's point */
        if (meter->type == METER_RADIANCE) {
            Ray ray;
            ray.origin = meter->point.xyz;
            ray.direction = normalize(meter->direction.xyz);
            path = camera_path(ray);
        } else {
            float3 p = meter->point.xyz;
            float3 n = normalize(meter->direction.xyz);
            if (meter->type != METER_IRRADIANCE) {
                float radius = meter->point.w;
                float3 outward = sample_uniform_sphere(sample_2d(&sampler));
                p = meter->point.xyz + radius * outward;
                n = -outward;
                area = 4.0f * M_PI_F * radius * radius;
            }
            direct = irradiance_start(&scene, &w, &sampler, p, n, &rays_traced, &path, &follow);
        }
        float4 value = follow ? continue_path(&scene, &w, &sampler, path, &rays_traced) : (float4)(0.0f);
        if (meter->type != METER_RADIANCE) {
            /* As E = π (direct + path) was summed: the light point's share first. */
            float4 reflected = direct;
            if (follow) reflected += value;
            value = M_PI_F * reflected;
            if (meter->type != METER_IRRADIANCE) value = area * value;
        }
        sum += 0.25f * (value.x + value.y + value.z + value.w);
    }
    item_means[item] = sum / (float)meter->samples_per_item;
}
