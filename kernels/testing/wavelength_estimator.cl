/* Test harness: each work-item averages `samples_per_item` hero-wavelength estimates of the film XYZ of one
 * tabulated spectrum, exactly as the path tracer forms them; the host compares the mean with colour-science and
 * uses the spread between work-items for the standard error. */
#include "kernel_entry.h"
#include "rng.cl"
#include "film.cl"
#include "spectrum.cl"

KERNEL void estimate_spectrum_xyz(__global const float *spectra, int offset, __global const float4 *cmf,
                                    uint seed, int samples_per_item, __global float4 *item_means)
{
    int item = get_global_id(0);
    float4 sum = (float4)(0.0f);
    for (int s = 0; s < samples_per_item; ++s) {
        Sampler sampler = sampler_start(seed, (uint)item, (uint)s);
        SampledWavelengths w = sample_wavelengths(sample_1d(&sampler));
        sum += spectrum_to_xyz_estimate(spectrum_at(spectra, offset, &w), cmf, &w);
    }
    item_means[item] = sum / (float)samples_per_item;
}

/* The visible-wavelength sampler itself: λ for given uniform numbers, the pdf the estimator divides by (the
 * sampler's), and p(λ) evaluated at that λ. */
KERNEL void sample_wavelength_pdf(__global const float *u, __global float *lambda, __global float *sampled_pdf,
                                    __global float *evaluated_pdf)
{
    int i = get_global_id(0);
    SampledWavelengths w = sample_wavelengths(u[i]);
    lambda[i] = w.lambda.x;
    sampled_pdf[i] = w.pdf.x;
    evaluated_pdf[i] = visible_wavelength_pdf(w.lambda.x);
}

/* The film's wavelength sampler (film.cl: tabulated when built with WAVELENGTH_TABLE, after the rows of the film's
 * `film_responses` curves): the hero λ and its pdf. */
KERNEL void sample_film_wavelength_pdf(__global const float4 *film_table, int film_responses,
                                         __global const float *u, __global float *lambda, __global float *sampled_pdf)
{
    int i = get_global_id(0);
    SampledWavelengths w = sample_film_wavelengths(u[i], film_table, film_responses);
    lambda[i] = w.lambda.x;
    sampled_pdf[i] = w.pdf.x;
}
