/* The film on the device: what a finished pixel sample adds, and how. Each pixel holds (ΣX, ΣY, ΣZ, number of
 * dropped samples) in a float4; the host divides by the samples done. The optional spectral film holds
 * RenderParams.spectral_bins band sums per pixel. Both kernel shapes (render_pass.cl, wavefront_pass.cl) and the estimator's
 * test harness add samples only through this file, so they form the same numbers in the same order.
 *
 * Film XYZ = ∫ L(λ) cmf(λ) dλ / ∫ȳ: the CMF table the host uploads is already divided by ∫ȳ, so a constant
 * radiance 1 gives Y = 1. A sample's four wavelengths give four estimates L(λᵢ) cmf(λᵢ) / p(λᵢ), averaged.
 *
 * Film responses (optional): RenderParams.film_responses more curves r_c(λ) (other observers' x̄ȳz̄, a camera's
 * measured channel sensitivities), each estimated the same way, ∫ L r_c dλ, into that many floats per pixel of
 * `response_film`.
 * With WAVELENGTH_TABLE the wavelengths follow a tabulated pdf the host shaped after the film's curves (as Mitsuba
 * 3's specfilm samples by its response curves): a piecewise-constant pdf on the grid's intervals, inverted by binary
 * search on its CDF (pbrt-v4's PiecewiseConstant1D does the same). The film table `cmf` then holds, in float4
 * rows: GRID_SAMPLES rows of the XYZ film's CMFs, ⌈film_responses / 4⌉ × GRID_SAMPLES rows of the response curves
 * four at a time, then the sampling table: GRID_SAMPLES floats of CDF at the grid's nodes and GRID_SAMPLES - 1
 * floats of pdf (1/nm) on the intervals between them (host: spectrace.spectral.film_response). Renders of the
 * default CIE 1931 film define neither and carry none of this code. The counts and the bands' range are run-time
 * values (RenderParams), so one program serves every film of a kind: only what needs code, not its sizes, is a
 * build define. */
#ifndef SPECTRACE_FILM_CL
#define SPECTRACE_FILM_CL

#include "wavelengths.cl"

/* Optional spectral film (SPECTRAL_FILM): RenderParams.spectral_bins equal bands over [spectral_min_nm,
 * spectral_max_nm], each accumulating the band-averaged radiance (1/Δ)∫_band L dλ, estimated per lane as
 * L(λ)·[λ in band] / (p(λ) Δ). Renders that ask for no spectral output build without SPECTRAL_FILM and carry none
 * of its code. */

/* Groups of four response curves in the film table, after its XYZ rows. */
inline int film_response_groups(int film_responses)
{
    return (film_responses + 3) / 4;
}

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

/* The width of one band of the spectral film, nm. */
inline float spectral_band_nm(__global const RenderParams *params)
{
    return (params->spectral_max_nm - params->spectral_min_nm) / (float)params->spectral_bins;
}

inline void add_to_spectral_film(__global float *spectral_film, int pixel, float4 radiance,
                                 const SampledWavelengths *w, __global const RenderParams *params)
{
#ifdef SPECTRAL_FILM
    const int bins = params->spectral_bins;
    const float band = spectral_band_nm(params);
    float4 value = 0.25f * radiance / (w->pdf * band);
    float lambda[4] = {w->lambda.x, w->lambda.y, w->lambda.z, w->lambda.w};
    float values[4] = {value.x, value.y, value.z, value.w};
    for (int i = 0; i < 4; ++i) {
        int bin = (int)floor((lambda[i] - params->spectral_min_nm) / band);
        if (bin >= 0 && bin < bins) spectral_film[pixel * bins + bin] += values[i];
    }
#endif
}

/* The sample's four wavelengths from u ∈ [0, 1): the hero-wavelength rotations, through the film's tabulated pdf
 * when it has one (after the XYZ rows and those of the film's `film_responses` curves), else the visible-range pdf
 * of wavelengths.cl. */
inline SampledWavelengths sample_film_wavelengths(float u, __global const float4 *film_table, int film_responses)
{
#ifdef WAVELENGTH_TABLE
    __global const float *cdf =
        (__global const float *)(film_table + GRID_SAMPLES * (1 + film_response_groups(film_responses)));
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
                                 __global const float4 *film_table, const SampledWavelengths *w,
                                 __global const RenderParams *params)
{
#ifdef WAVELENGTH_TABLE
    const int responses = params->film_responses;
    float4 weight = 0.25f * radiance / w->pdf;
    for (int group = 0; group < film_response_groups(responses); ++group) {
        __global const float4 *curves = film_table + (1 + group) * GRID_SAMPLES;
        float4 value = weight.x * cmf_at(curves, w->grid_index.x, w->grid_frac.x)
                     + weight.y * cmf_at(curves, w->grid_index.y, w->grid_frac.y)
                     + weight.z * cmf_at(curves, w->grid_index.z, w->grid_frac.z)
                     + weight.w * cmf_at(curves, w->grid_index.w, w->grid_frac.w);
        float values[4] = {value.x, value.y, value.z, value.w};
        for (int k = 0; k < 4 && 4 * group + k < responses; ++k)
            response_film[pixel * responses + 4 * group + k] += values[k];
    }
#endif
}

/* Adds a finished sample's XYZ estimate to the pixel's running film sum `accumulated` (film[pixel], held by the
 * caller), its bands to the spectral film and its response curves' estimates to the response film. A non-finite
 * estimate (a NaN or inf from a degenerate path) would
 * spoil the pixel for good: it is dropped and counted in w instead, and the host reports the count. */
inline void add_pixel_sample(float4 *accumulated, __global float *spectral_film, __global float *response_film,
                             int pixel, float4 radiance, __global const float4 *cmf, const SampledWavelengths *w,
                             __global const RenderParams *params)
{
    float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, w);
    if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) {
        *accumulated += xyz;
        add_to_spectral_film(spectral_film, pixel, radiance, w, params);
        add_to_response_film(response_film, pixel, radiance, cmf, w, params);
    } else {
        accumulated->w += 1.0f;
    }
}

#endif
