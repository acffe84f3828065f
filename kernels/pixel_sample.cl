/* A pixel sample's start (sampler, wavelengths, film position by the pixel filter, camera ray), shared by the
 * render-pass kernel shapes so they draw the same numbers in the same order; its end, the addition to the film, is
 * film.cl's. Draws: the wavelengths (1D), the film position (2D), then the lens position (2D, thin lens only). */
#ifndef SPECTRACE_PIXEL_SAMPLE_CL
#define SPECTRACE_PIXEL_SAMPLE_CL

#include "camera.cl"
#include "film.cl"
#include "pixel_filter.cl"
#include "rng.cl"
#include "scene.cl"

/* Sample `sample_index` of a pixel: its random stream, its four wavelengths (drawn as the film table `cmf` says,
 * film.cl) and its camera ray; `weight` is what its radiance is multiplied by before it reaches the film (the pixel
 * filter's, 1 for box and tent; a lens system's ray weight, kernels/camera_realistic.cl). */
inline Ray start_pixel_sample(__global const RenderParams *params, __global const float4 *cmf, int pixel,
                              int sample_index, Sampler *sampler, SampledWavelengths *w, float *weight)
{
    *sampler = sampler_start((uint)params->seed, (uint)pixel, (uint)sample_index);
    *w = sample_film_wavelengths(sample_1d(sampler), cmf, params->film_responses);
    float2 film = pixel_filter_sample(params, pixel % params->width, pixel / params->width, sample_2d(sampler),
                                      weight);
    return weighted_camera_ray(params, film, sampler, weight);
}

#endif
