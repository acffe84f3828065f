/* The render-pass kernel shared by the integrators: the including file defines TRACE_RADIANCE(scene, w,
 * sampler, ray, rays_traced) first.
 *
 * One work-item per pixel runs the pass's samples in sample-index order and adds each to the film one at a
 * time, so the float sums do not depend on how a render is split into passes. */
#include "kernel_entry.h"
#include "pixel_sample.cl"

/* film: per pixel (ΣX, ΣY, ΣZ, number of dropped non-finite samples); ray_counts: rays traced per pixel, for
 * the benchmark's rays/s; spectral_film, response_film: film.cl's optional per-pixel sums. */
KERNEL void render_pass(SCENE_KERNEL_PARAMS, __global const float4 *cmf, __global float4 *film,
                          __global uint *ray_counts, __global float *spectral_film, __global float *response_film)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;

    float4 accumulated = film[pixel];
    uint rays_traced = 0;
    for (int s = params->sample_begin; s < params->sample_begin + params->sample_count; ++s) {
        Sampler sampler;
        SampledWavelengths w;
        Ray ray = start_pixel_sample(params, cmf, pixel, s, &sampler, &w);
        float4 radiance = TRACE_RADIANCE(&scene, &w, &sampler, ray, &rays_traced);
        add_pixel_sample(&accumulated, spectral_film, response_film, pixel, radiance, cmf, &w);
    }
    film[pixel] = accumulated;
    ray_counts[pixel] += rays_traced;
}
