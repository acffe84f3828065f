/* Hero-wavelength sampling (Wilkie et al. 2014): one uniform number picks four wavelengths, the hero and three
 * rotations of it in sample space, each distributed by the visible-range pdf
 *     p(λ) ∝ 1 / cosh²(b (λ − 538 nm)),  b = 0.0072 / nm,  λ ∈ [360, 830] nm
 * (the shape pbrt-v4 uses, Sec. 4.6.5). Its CDF is a tanh, so sampling inverts it in closed form; here the
 * normalisation is exact for the truncated range instead of using rounded constants. */
#ifndef SPECTRACE_WAVELENGTHS_CL
#define SPECTRACE_WAVELENGTHS_CL

#include "types.h"

#define VISIBLE_PDF_CENTER_NM 538.0f
#define VISIBLE_PDF_SHARPNESS 0.0072f
/* The unnormalised CDF tanh(b (λ − 538 nm)) at the range's ends, 360 and 830 nm, with b the float 0.0072f,
 * evaluated in double precision and rounded to float. Sampling and pdf both use these two numbers, so they stay an
 * exact pair whatever the last bit; a last-bit change would only move the range's ends by ~1e-4 nm. */
#define VISIBLE_CDF_LO (-0x1.b6bcfep-1f)
#define VISIBLE_CDF_HI 0x1.f0f15ap-1f
#define VISIBLE_CDF_SPAN (VISIBLE_CDF_HI - VISIBLE_CDF_LO)

typedef struct {
    float4 lambda;  /* nm */
    float4 pdf;     /* 1/nm */
    int4 grid_index;  /* lower grid sample of each wavelength, for table lookups */
    float4 grid_frac; /* position between grid_index and grid_index + 1 */
} SampledWavelengths;

/* p(λ) = b / (span cosh²x), x = b (λ − 538). With e = exp(−2|x|) ≤ 1, 1/cosh²x = 4e / (1 + e)²: one exp, no
 * overflow. */
inline float visible_wavelength_pdf(float lambda_nm)
{
    if (lambda_nm < GRID_MIN_NM || lambda_nm > GRID_MAX_NM) return 0.0f;
    float e = exp(-2.0f * fabs(VISIBLE_PDF_SHARPNESS * (lambda_nm - VISIBLE_PDF_CENTER_NM)));
    float one_plus_e = 1.0f + e;
    return (4.0f * VISIBLE_PDF_SHARPNESS / VISIBLE_CDF_SPAN) * e / (one_plus_e * one_plus_e);
}

/* Inverts the CDF at four uniform numbers. t = tanh x is where the CDF lands, so x = atanh t = ½ log((1 + t)/(1 − t))
 * and, since 1/cosh²x = 1 − tanh²x, the pdf there is b (1 − t)(1 + t) / span: one log per wavelength, no hyperbolic
 * function, and the pdf comes from the same t as λ (t ≥ −0.86 and ≤ 0.98, so 1 − t² loses no precision). */
inline float4 sample_visible_wavelengths(float4 u, float4 *pdf)
{
    float4 t = mad(u, (float4)(VISIBLE_CDF_SPAN), (float4)(VISIBLE_CDF_LO));
    float4 one_minus_t = 1.0f - t;
    float4 one_plus_t = 1.0f + t;
    *pdf = (VISIBLE_PDF_SHARPNESS / VISIBLE_CDF_SPAN) * one_minus_t * one_plus_t;
    float4 lambda = VISIBLE_PDF_CENTER_NM + (0.5f / VISIBLE_PDF_SHARPNESS) * log(one_plus_t / one_minus_t);
    return clamp(lambda, GRID_MIN_NM, GRID_MAX_NM);
}

/* The four sample-space positions of a hero wavelength's u ∈ [0, 1): u and its rotations by ¼, ½, ¾. */
inline float4 hero_rotations(float u)
{
    float4 us = (float4)(u, u + 0.25f, u + 0.5f, u + 0.75f);
    return us - floor(us);
}

/* Wavelengths `lambda` (nm, within the grid) drawn with density `pdf` (1/nm), with their grid positions. */
inline SampledWavelengths wavelengths_on_grid(float4 lambda, float4 pdf)
{
    SampledWavelengths w;
    w.lambda = lambda;
    w.pdf = pdf;
    float4 position = w.lambda - GRID_MIN_NM;
    float4 lower = clamp(floor(position), 0.0f, (float)(GRID_SAMPLES - 2));
    w.grid_index = convert_int4(lower);
    w.grid_frac = position - lower;
    return w;
}

inline SampledWavelengths sample_wavelengths(float u)
{
    float4 pdf;
    float4 lambda = sample_visible_wavelengths(hero_rotations(u), &pdf);
    return wavelengths_on_grid(lambda, pdf);
}

/* Whether the four wavelengths differ: sensors put one wavelength in all four lanes, which then go on together
 * through dispersive events. */
inline int wavelengths_differ(const SampledWavelengths *w)
{
    return any(w->lambda != (float4)(w->lambda.x));
}

/* Hero-only continuation after an event that sends each wavelength its own way (dispersion): the secondary
 * wavelengths' lanes of the path's per-wavelength weight `throughput` end, and the hero's counts 4 times, so the
 * four-lane average the film takes stays unbiased (pbrt-v4's TerminateSecondary reaches the same through the pdfs).
 * Light already gathered on the secondary lanes stays. *hero_only records that it happened (the free-flight
 * sampling of media follows the hero alone from then on); a second call changes nothing. */
inline void terminate_secondary(float4 *throughput, int *hero_only)
{
    if (*hero_only) return;
    *throughput = (float4)(4.0f * throughput->x, 0.0f, 0.0f, 0.0f);
    *hero_only = 1;
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
