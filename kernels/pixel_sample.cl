/* A pixel sample's start (sampler, wavelengths, camera ray) and end (its XYZ estimate and spectral bands added to
 * the film), shared by the render-pass kernel shapes so they draw and add the same numbers in the same order. */
#ifndef SPECTRACE_PIXEL_SAMPLE_CL
#define SPECTRACE_PIXEL_SAMPLE_CL

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

/* Sample `sample_index` of a pixel: its random stream, its four wavelengths and its camera ray. */
inline Ray start_pixel_sample(__global const RenderParams *params, int pixel, int sample_index, Sampler *sampler,
                              SampledWavelengths *w)
{
    *sampler = sampler_start((uint)params->seed, (uint)pixel, (uint)sample_index);
    *w = sample_wavelengths(sample_1d(sampler));
    return camera_ray(params, pixel % params->width, pixel / params->width, sample_2d(sampler));
}

/* Adds a finished sample's XYZ estimate to the pixel's running film sum (x, y, z, dropped samples); a non-finite
 * estimate is dropped and counted instead. */
inline void add_pixel_sample(float4 *accumulated, __global float *spectral_film, int pixel, float4 radiance,
                             __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, w);
    if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) {
        *accumulated += xyz;
        add_to_spectral_film(spectral_film, pixel, radiance, w);
    } else {
        accumulated->w += 1.0f;
    }
}

#endif
