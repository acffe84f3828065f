/* Hero-wavelength sampling (Wilkie et al. 2014): one uniform number picks four wavelengths, the hero and three
 * rotations of it in sample space, each distributed by the visible-range pdf
 *     p(λ) ∝ 1 / cosh²(b (λ − 538 nm)),  b = 0.0072 / nm,  λ ∈ [360, 830] nm
 * (the shape pbrt-v4 uses, Sec. 4.6.5). Its CDF is a tanh, so sampling inverts it in closed form; here the
 * normalisation is computed exactly for the truncated range instead of using rounded constants. */
#ifndef SPECTRACE_WAVELENGTHS_CL
#define SPECTRACE_WAVELENGTHS_CL

#include "types.h"

#define VISIBLE_PDF_CENTER_NM 538.0f
#define VISIBLE_PDF_SHARPNESS 0.0072f

typedef struct {
    float4 lambda;  /* nm */
    float4 pdf;     /* 1/nm */
    int4 grid_index;  /* lower grid sample of each wavelength, for table lookups */
    float4 grid_frac; /* position between grid_index and grid_index + 1 */
} SampledWavelengths;

inline float visible_cdf_at(float lambda_nm)
{
    return tanh(VISIBLE_PDF_SHARPNESS * (lambda_nm - VISIBLE_PDF_CENTER_NM));
}

inline float visible_wavelength_pdf(float lambda_nm)
{
    if (lambda_nm < GRID_MIN_NM || lambda_nm > GRID_MAX_NM) return 0.0f;
    float span = visible_cdf_at(GRID_MAX_NM) - visible_cdf_at(GRID_MIN_NM);
    float c = cosh(VISIBLE_PDF_SHARPNESS * (lambda_nm - VISIBLE_PDF_CENTER_NM));
    return VISIBLE_PDF_SHARPNESS / (span * c * c);
}

inline float sample_visible_wavelength(float u)
{
    float lo = visible_cdf_at(GRID_MIN_NM);
    float hi = visible_cdf_at(GRID_MAX_NM);
    float lambda = VISIBLE_PDF_CENTER_NM + atanh(mad(u, hi - lo, lo)) / VISIBLE_PDF_SHARPNESS;
    return clamp(lambda, GRID_MIN_NM, GRID_MAX_NM);
}

inline SampledWavelengths sample_wavelengths(float u)
{
    float4 us = (float4)(u, u + 0.25f, u + 0.5f, u + 0.75f);
    us = us - floor(us);
    SampledWavelengths w;
    w.lambda = (float4)(sample_visible_wavelength(us.x), sample_visible_wavelength(us.y),
                        sample_visible_wavelength(us.z), sample_visible_wavelength(us.w));
    w.pdf = (float4)(visible_wavelength_pdf(w.lambda.x), visible_wavelength_pdf(w.lambda.y),
                     visible_wavelength_pdf(w.lambda.z), visible_wavelength_pdf(w.lambda.w));
    float4 position = w.lambda - GRID_MIN_NM;
    float4 lower = clamp(floor(position), 0.0f, (float)(GRID_SAMPLES - 2));
    w.grid_index = convert_int4(lower);
    w.grid_frac = position - lower;
    return w;
}

/* Fixed wavelengths (sensors measure chosen wavelengths instead of sampling them); pdf is 1 (unused). */
inline SampledWavelengths fixed_wavelengths(float4 lambda)
{
    SampledWavelengths w;
    w.lambda = clamp(lambda, GRID_MIN_NM, GRID_MAX_NM);
    w.pdf = (float4)(1.0f);
    float4 position = w.lambda - GRID_MIN_NM;
    float4 lower = clamp(floor(position), 0.0f, (float)(GRID_SAMPLES - 2));
    w.grid_index = convert_int4(lower);
    w.grid_frac = position - lower;
    return w;
}

#endif
