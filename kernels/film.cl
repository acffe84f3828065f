/* The film on the device: what a finished pixel sample adds, and how. Each pixel holds (ΣX, ΣY, ΣZ, number of
 * dropped samples) in a float4; the host divides by the samples done. The optional spectral film holds
 * SPECTRAL_BINS band sums per pixel. Both kernel shapes (render_pass.cl, wavefront_pass.cl) and the estimator's
 * test harness add samples only through this file, so they form the same numbers in the same order.
 *
 * Film XYZ = ∫ L(λ) cmf(λ) dλ / ∫ȳ: the CMF table the host uploads is already divided by ∫ȳ, so a constant
 * radiance 1 gives Y = 1. A sample's four wavelengths give four estimates L(λᵢ) cmf(λᵢ) / p(λᵢ), averaged. */
#ifndef SPECTRACE_FILM_CL
#define SPECTRACE_FILM_CL

#include "wavelengths.cl"

/* Optional spectral film: SPECTRAL_BINS equal bands over [SPECTRAL_MIN_NM, SPECTRAL_MAX_NM], each accumulating
 * the band-averaged radiance (1/Δ)∫_band L dλ, estimated per lane as L(λ)·[λ in band] / (p(λ) Δ). Renders that
 * ask for no spectral output build without SPECTRAL_BINS and carry none of its code. */
#ifndef SPECTRAL_BINS
#define SPECTRAL_BINS 0
#define SPECTRAL_MIN_NM GRID_MIN_NM
#define SPECTRAL_MAX_NM GRID_MAX_NM
#endif

inline float4 cmf_at(__global const float4 *cmf, int index, float frac)
{
    float4 a = cmf[index];
    return mad((float4)(frac), cmf[index + 1] - a, a);
}

/* Monte Carlo estimate of film XYZ, averaging the four wavelengths' estimates L(λᵢ) cmf(λᵢ) / p(λᵢ); w = 0. */
inline float4 spectrum_to_xyz_estimate(float4 radiance, __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 weight = radiance / w->pdf;
    float4 xyz = weight.x * cmf_at(cmf, w->grid_index.x, w->grid_frac.x)
               + weight.y * cmf_at(cmf, w->grid_index.y, w->grid_frac.y)
               + weight.z * cmf_at(cmf, w->grid_index.z, w->grid_frac.z)
               + weight.w * cmf_at(cmf, w->grid_index.w, w->grid_frac.w);
    return 0.25f * (float4)(xyz.x, xyz.y, xyz.z, 0.0f);
}

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

/* Adds a finished sample's XYZ estimate to the pixel's running film sum `accumulated` (film[pixel], held by the
 * caller) and its bands to the spectral film. A non-finite estimate (a NaN or inf from a degenerate path) would
 * spoil the pixel for good: it is dropped and counted in w instead, and the host reports the count. */
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
