/* Emission inside participating media: a medium whose absorbing part glows, adding σa(λ, x) Le(λ, x) of radiance
 * per unit length (pbrt-v4's emissive media: its homogeneous `Le`, its grid media's `Lescale` and `temperature`
 * grids; Mitsuba 3's volpath has none).
 *
 * Sources (read to learn, not copied): pbrt-v4's VolPathIntegrator (emission added at every majorant sample of
 * delta tracking, σa Le / σmaj times the path's weight there); Planck's law, normalised to its peak at Wien's
 * λmax = b/T as pbrt-v4's BlackbodySpectrum (and spectrace.spectral.blackbody) are.
 *
 * Contract. Medium.emission: the offset of the spectrum E(λ) in the scene's float table, -1 when the medium does
 * not glow. Le(λ, x) = E(λ) s(x) B(λ, T(x)), where a grid medium's block may hold an emission scale grid s (header
 * int 12, -1: s = 1) and a temperature grid T in kelvin (header int 13, -1: B = 1), both looked up as its density
 * is. Units: E in the scene's radiance units, σa in 1/scene unit, so σa Le is radiance per scene unit.
 *
 * Estimators. Through a homogeneous medium the emission reaching the ray's origin from the stretch [0, t] is
 * E σa (1 − exp(−σt t)) / σt per lane, added in closed form (no noise) whatever the flight samples. Through a grid,
 * each tentative collision adds its weight so far times σa(x) Le(x) / μ: the collisions are a Poisson process at
 * rate μ and the weight so far estimates the transmittance to them, so the sum estimates ∫ T σa Le dt without bias. */
#ifndef SPECTRACE_MEDIUM_EMISSION_CL
#define SPECTRACE_MEDIUM_EMISSION_CL

/* c2 / (λmax T) = hc / (k b): the exponent of Planck's law at its peak, the same for every temperature. */
#define PLANCK_PEAK_EXPONENT 4.965114231744276f
/* Wien's displacement constant b (nm K) and the second radiation constant c2 = hc/k (nm K), CODATA 2018. */
#define WIEN_DISPLACEMENT_NM_K 2897771.955f
#define SECOND_RADIATION_NM_K 14387768.78f

/* Planck's law at the four wavelengths (nm), divided by its peak: B(λ, T) / B(λmax, T), 0 for T ≤ 0. */
inline float4 planck_normalised(float4 lambda_nm, float temperature_k)
{
    if (!(temperature_k > 0.0f)) return (float4)(0.0f);
    float4 ratio = WIEN_DISPLACEMENT_NM_K / (lambda_nm * temperature_k);  /* λmax / λ */
    float4 power5 = ratio * ratio * ratio * ratio * ratio;
    return power5 * expm1(PLANCK_PEAK_EXPONENT) / expm1(SECOND_RADIATION_NM_K / (lambda_nm * temperature_k));
}

inline float4 medium_emission_spectrum(__global const Medium *m, __global const float *spectra,
                                       const SampledWavelengths *w)
{
    return spectrum_at(spectra, m->emission, w);
}

/* The emission reaching the origin from the stretch [0, t] of a homogeneous medium, per lane (`lanes` masks the
 * lanes a dispersive event ended). */
inline float4 medium_emitted_homogeneous(__global const Medium *m, __global const float *spectra,
                                         const SampledWavelengths *w, float4 lanes, float t)
{
    if (m->emission < 0) return (float4)(0.0f);
    float4 sigma_a = spectrum_at(spectra, m->sigma_a_offset, w);
    float4 sigma_t = medium_sigma_t(m, spectra, w);
    float4 absorbed = select(sigma_a * t, sigma_a * (1.0f - beer_lambert(sigma_t, t)) / sigma_t,
                             sigma_t > (float4)(0.0f));
    /* σa = 0 glows nowhere, also over an infinite stretch (0 · ∞) */
    absorbed = select(absorbed, (float4)(0.0f), sigma_a == (float4)(0.0f));
    return lanes * medium_emission_spectrum(m, spectra, w) * absorbed;
}

/* s(x) B(λ, T(x)) of grid `grid` at world point x (1 for each factor its block lacks). */
inline float4 grid_emission_factor(__global const float *spectra, int grid, float3 x, float4 lambda)
{
    int scale_offset = GRID_HEADER_INT(spectra, grid, 12);
    int temperature_offset = GRID_HEADER_INT(spectra, grid, 13);
    if (scale_offset < 0 && temperature_offset < 0) return (float4)(1.0f);
    float3 u = grid_unit_point(spectra, grid, x);
    int3 n = (int3)(GRID_HEADER_INT(spectra, grid, 0), GRID_HEADER_INT(spectra, grid, 1),
                    GRID_HEADER_INT(spectra, grid, 2));
    int outside = GRID_HEADER_INT(spectra, grid, 11);
    int3 i0, i1;
    float3 f = grid_corners_outside(outside, n, u, &i0, &i1);
    float4 factor = (float4)(1.0f);
    if (scale_offset >= 0) factor *= grid_trilinear(spectra, scale_offset, n, i0, i1, f);
    if (temperature_offset >= 0)
        factor *= planck_normalised(lambda, grid_trilinear(spectra, temperature_offset, n, i0, i1, f));
    return factor;
}

#endif
