/* The render-pass kernel shared by the integrators: the including file defines TRACE_RADIANCE(scene, w,
 * sampler, ray, rays_traced) first.
 *
 * One work-item per pixel runs the pass's samples in sample-index order and adds each to the film one at a
 * time, so the float sums do not depend on how a render is split into passes. */
#include "camera.cl"
#include "scene.cl"

/* Optional spectral film: SPECTRAL_BINS equal bands over [SPECTRAL_MIN_NM, SPECTRAL_MAX_NM], each accumulating
 * the band-averaged radiance (1/Δ)∫_band L dλ, estimated per lane as L(λ)·[λ in band] / (p(λ) Δ). */
#ifndef SPECTRAL_BINS
#define SPECTRAL_BINS 0
#define SPECTRAL_MIN_NM 360.0f
#define SPECTRAL_MAX_NM 830.0f
#endif

inline void add_to_spectral_film(__global float *spectral_film, int pixel, float4 radiance,
                                 const SampledWavelengths *w)
{
#if SPECTRAL_BINS > 0
    const float band = (SPECTRAL_MAX_NM - SPECTRAL_MIN_NM) / (float)SPECTRAL_BINS;
    float4 value = 0.25f * radiance / (w->pdf * band);
    float lambda[4] = {w->lambda.x, w->lambda.y, w->lambda.z, w->lambda.w};
    float values[4] = {value.x, value.y, value.z, value.w};
    for (int i = 0; i < 4; ++i) {
        int bin = (int)floor((lambda[i] - SPECTRAL_MIN_NM) / band);
        if (bin >= 0 && bin < SPECTRAL_BINS) spectral_film[pixel * SPECTRAL_BINS + bin] += values[i];
    }
#endif
}

/* film: per pixel (ΣX, ΣY, ΣZ, number of dropped non-finite samples); ray_counts: rays traced per pixel, for
 * the benchmark's rays/s. */
__kernel void render_pass(__global const RenderParams *params, __global const BVHNode *nodes,
                          __global const float4 *triangle_vertices, __global const float2 *triangle_uvs,
                          __global const TriangleInfo *triangle_info,
                          __global const Material *materials, __global const Light *lights,
                          __global const float *light_cdf, __global const float *spectra,
                          __global const float4 *texels, __global const float *map_cdf,
                          __global const Medium *media, __global const float4 *cmf, __global float4 *film, __global uint *ray_counts,
                          __global float *spectral_film)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    Scene scene = {params, nodes,     triangle_vertices, triangle_uvs, triangle_info, materials,
                   lights, light_cdf, spectra,           texels,       map_cdf,   media};
    int pixel_x = pixel % params->width;
    int pixel_y = pixel / params->width;

    float4 accumulated = film[pixel];
    uint rays_traced = 0;
    for (int s = params->sample_begin; s < params->sample_begin + params->sample_count; ++s) {
        Sampler sampler = sampler_start((uint)params->seed, (uint)pixel, (uint)s);
        SampledWavelengths w = sample_wavelengths(sample_1d(&sampler));
        Ray ray = camera_ray(params, pixel_x, pixel_y, sample_2d(&sampler));
        float4 radiance = TRACE_RADIANCE(&scene, &w, &sampler, ray, &rays_traced);
        float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, &w);
        if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) {
            accumulated += xyz;
            add_to_spectral_film(spectral_film, pixel, radiance, &w);
        } else {
            accumulated.w += 1.0f;
        }
    }
    film[pixel] = accumulated;
    ray_counts[pixel] += rays_traced;
}
