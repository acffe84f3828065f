/* The render-pass kernel shared by the integrators: the including file defines TRACE_RADIANCE(scene, w,
 * sampler, ray, rays_traced) first, and TRACE_PATH_STATE(scene, w, sampler, PathState *, rays_traced), the same
 * for a path state it keeps, which renders with AOVs (FILM_AOVS, kernels/aov.cl) use.
 *
 * One work-item per pixel runs the pass's samples in sample-index order and adds each to the film one at a
 * time, so the float sums do not depend on how a render is split into passes. */
#include "kernel_entry.h"
#include "aov.cl"
#include "pixel_sample.cl"

/* film: per pixel (ΣX, ΣY, ΣZ, number of dropped non-finite samples); ray_counts: rays traced per pixel, for
 * the benchmark's rays/s; spectral_film, response_film: film.cl's optional per-pixel sums; aov_film:
 * AOV_FLOAT4S_PER_PIXEL sums per pixel (aov.cl; untouched without FILM_AOVS). */
KERNEL void render_pass(SCENE_KERNEL_PARAMS, __global const float4 *cmf, __global float4 *film,
                          __global uint *ray_counts, __global float *spectral_film, __global float *response_film,
                          __global float4 *aov_film)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
#if FILM_AOVS
    scene.film_cmf = cmf;
#endif

    float4 accumulated = film[pixel];
    uint rays_traced = 0;
#if FILM_AOVS
    float4 aov_sums[AOV_FLOAT4S_PER_PIXEL];
    for (int i = 0; i < AOV_FLOAT4S_PER_PIXEL; ++i) aov_sums[i] = aov_film[pixel * AOV_FLOAT4S_PER_PIXEL + i];
#endif
    for (int s = params->sample_begin; s < params->sample_begin + params->sample_count; ++s) {
        Sampler sampler;
        SampledWavelengths w;
        float weight;
        Ray ray = start_pixel_sample(params, cmf, pixel, s, &sampler, &w, &weight);
        /* weight: the pixel filter's sample weight, × 1 for box and tent filters, which changes no bits. */
#if FILM_AOVS || SCENE_POLARIZED
        PathState path = camera_path(ray);
        IF_POLARIZED(polarized_camera(&path.pol, params, ray.direction));
        float4 radiance = weight * TRACE_PATH_STATE(&scene, &w, &sampler, &path, &rays_traced);
#if FILM_STOKES
        add_stokes_sample(aov_sums, &path.pol, radiance, weight, cmf, &w);
#endif
        IF_POLARIZED(radiance = polarized_film_radiance(&path.pol, params, radiance, weight));
#if FILM_AOVS
        add_aov_sample(aov_sums, &path.aov, radiance, weight, cmf, &w);
#endif
#else
        float4 radiance = weight * TRACE_RADIANCE(&scene, &w, &sampler, ray, &rays_traced);
#endif
        add_pixel_sample(&accumulated, spectral_film, response_film, pixel, radiance, cmf, &w, params);
    }
    film[pixel] = accumulated;
#if FILM_AOVS
    for (int i = 0; i < AOV_FLOAT4S_PER_PIXEL; ++i) aov_film[pixel * AOV_FLOAT4S_PER_PIXEL + i] = aov_sums[i];
#endif
    ray_counts[pixel] += rays_traced;
}
