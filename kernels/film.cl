/* The film on the device: what a finished pixel sample adds, and how. Each pixel holds (ΣX, ΣY, ΣZ, number of
 * dropped samples) in a float4; the host divides by the samples done. The optional spectral film holds
 * SPECTRAL_BINS band sums per pixel. Both kernel shapes (render_pass.cl, wavefront_pass.cl) and the estimator's
 * test harness add samples only through this file, so they form the same numbers in the same order.
 *
 * Film XYZ = ∫ L(λ) cmf(λ) dλ / ∫ȳ: the CMF table the host uploads is already divided by ∫ȳ, so a constant
 * radiance 1 gives Y = 1. A sample's four wavelengths give four estimates L(λᵢ) cmf(λᵢ) / p(λᵢ), averaged.
 *
 * Film responses (optional): FILM_RESPONSES more curves r_c(λ) (other observers' x̄ȳz̄, a camera's measured channel
 * sensitivities), each estimated the same way, ∫ L r_c dλ, into FILM_RESPONSES floats per pixel of `response_film`.
 * With WAVELENGTH_TABLE the wavelengths follow a tabulated pdf the host shaped after the film's curves (as Mitsuba
 * 3's specfilm samples by its response curves): a piecewise-constant pdf on the grid's intervals, inverted by binary
 * search on its CDF (pbrt-v4's PiecewiseConstant1D does the same). The film table `cmf` then holds, in float4
 * rows: GRID_SAMPLES rows of the XYZ film's CMFs, FILM_RESPONSE_GROUPS × GRID_SAMPLES rows of the response curves
 * four at a time, then the sampling table: GRID_SAMPLES floats of CDF at the grid's nodes and GRID_SAMPLES - 1
 * floats of pdf (1/nm) on the intervals between them (host: spectrace.spectral.film_response). Renders of the
 * default CIE 1931 film define neither and carry none of this code. */
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

#ifndef FILM_RESPONSES
#define FILM_RESPONSES 0
#endif
#define FILM_RESPONSE_GROUPS ((FILM_RESPONSES + 3) / 4)
#define FILM_TABLE_SAMPLING_ROW (GRID_SAMPLES * (1 + FILM_RESPONSE_GROUPS))

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

/* The sample's four wavelengths from u ∈ [0, 1): the hero-wavelength rotations, through the film's tabulated pdf
 * when it has one, else the visible-range pdf of wavelengths.cl. */
inline SampledWavelengths sample_film_wavelengths(float u, __global const float4 *film_table)
{
#ifdef WAVELENGTH_TABLE
    __global const float *cdf = (__global const float *)(film_table + FILM_TABLE_SAMPLING_ROW);
    __global const float *density = cdf + GRID_SAMPLES;
    const float step_nm = (GRID_MAX_NM - GRID_MIN_NM) / (float)(GRID_SAMPLES - 1);
    float4 us = hero_rotations(u);
    float positions[4] = {us.x, us.y, us.z, us.w};
    float lambda[4], pdf[4];
    for (int k = 0; k < 4; ++k) {
        /* Largest interval lo with cdf[lo] <= u: cdf[0] = 0 <= u < 1 = cdf[GRID_SAMPLES - 1]. */
        int lo = 0, hi = GRID_SAMPLES - 1;
        while (hi - lo > 1) {
            int mid = (lo + hi) >> 1;
            if (cdf[mid] <= positions[k]) lo = mid; else hi = mid;
        }
        float t = clamp((positions[k] - cdf[lo]) / (cdf[lo + 1] - cdf[lo]), 0.0f, 1.0f);
        lambda[k] = min(GRID_MIN_NM + step_nm * ((float)lo + t), GRID_MAX_NM);
        pdf[k] = density[lo];
    }
    return wavelengths_on_grid((float4)(lambda[0], lambda[1], lambda[2], lambda[3]),
                               (float4)(pdf[0], pdf[1], pdf[2], pdf[3]));
#else
    return sample_wavelengths(u);
#endif
}

/* Adds the sample's estimates of ∫ L r_c dλ for the film's response curves to the pixel's response sums. */
inline void add_to_response_film(__global float *response_film, int pixel, float4 radiance,
                                 __global const float4 *film_table, const SampledWavelengths *w)
{
#if FILM_RESPONSES > 0
    float4 weight = 0.25f * radiance / w->pdf;
    for (int group = 0; group < FILM_RESPONSE_GROUPS; ++group) {
        __global const float4 *curves = film_table + (1 + group) * GRID_SAMPLES;
        float4 value = weight.x * cmf_at(curves, w->grid_index.x, w->grid_frac.x)
                     + weight.y * cmf_at(curves, w->grid_index.y, w->grid_frac.y)
                     + weight.z * cmf_at(curves, w->grid_index.z, w->grid_frac.z)
                     + weight.w * cmf_at(curves, w->grid_index.w, w->grid_frac.w);
        float values[4] = {value.x, value.y, value.z, value.w};
        for (int k = 0; k < 4 && 4 * group + k < FILM_RESPONSES; ++k)
            response_film[pixel * FILM_RESPONSES + 4 * group + k] += values[k];
    }
#endif
}

/* Adds a finished sample's XYZ estimate to the pixel's running film sum `accumulated` (film[pixel], held by the
 * caller), its bands to the spectral film and its response curves' estimates to the response film. A non-finite
 * estimate (a NaN or inf from a degenerate path) would
 * spoil the pixel for good: it is dropped and counted in w instead, and the host reports the count. */
inline void add_pixel_sample(float4 *accumulated, __global float *spectral_film, __global float *response_film,
                             int pixel, float4 radiance, __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, w);
    if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) {
        *accumulated += xyz;
        add_to_spectral_film(spectral_film, pixel, radiance, w);
        add_to_response_film(response_film, pixel, radiance, cmf, w);
    } else {
        accumulated->w += 1.0f;
    }
}

#endif
