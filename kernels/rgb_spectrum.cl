/* RGB reflectances as smooth spectra: Jakob & Hanika 2019, "A Low-Dimensional Function Space for Efficient
 * Spectral Upsampling" (Computer Graphics Forum 38(2)). The host fits three coefficients per colour
 * (spectrace.spectral.uplift); the spectrum is the sigmoid S(x) = 1/2 + x / (2 sqrt(1 + x²)) of the quadratic
 * x = c0 λ² + c1 λ + c2 in λ (nm), evaluated in Horner form as the host's sigmoid_polynomial_spectrum does. S has
 * no exp, stays in [0, 1], and the host's saturated coefficients (c2 = ±1e6) give exactly 0 and 1. */
#ifndef SPECTRACE_RGB_SPECTRUM_CL
#define SPECTRACE_RGB_SPECTRUM_CL

/* S(x) at the four wavelengths' polynomial values x. */
inline float4 sigmoid_of(float4 x)
{
    /* x / sqrt(1 + x²) as one rsqrt (no division): as accurate (OpenCL allows rsqrt 2 ulp, sqrt 3 and a division
     * 2.5), but an ulp's error could lift a value past 1 or a saturated one off 0 and 1. Beyond |x| = 10⁴, S is
     * within 2.5e-9 of 0 or 1 (S(x) ≈ 1/(4x²) or 1 − 1/(4x²)): that end exactly. */
    float4 s = clamp(mad(0.5f * x, rsqrt(mad(x, x, 1.0f)), 0.5f), 0.0f, 1.0f);
    return select(s, step(0.0f, x), isgreater(fabs(x), (float4)(1.0e4f)));
}

inline float4 sigmoid_polynomial(float3 c, float4 lambda_nm)
{
    return sigmoid_of((c.x * lambda_nm + c.y) * lambda_nm + c.z);
}

/* The same spectrum from the dimensionless coefficients (a, b, c) of t = (λ − SIGMOID_CENTRE_NM) /
 * SIGMOID_HALF_SPAN_NM, t in [−1, 1] over the grid (spectrace.spectral.uplift's own form): better conditioned than
 * powers of λ in nm, so that half-float coefficients (textures' compact storage) stay within a colour difference
 * far below what the eye tells apart (docs/textures.md, Memory). */
inline float4 sigmoid_polynomial_dimensionless(float3 c, float4 lambda_nm)
{
    float4 t = (lambda_nm - SIGMOID_CENTRE_NM) * (1.0f / SIGMOID_HALF_SPAN_NM);
    return sigmoid_of((c.x * t + c.y) * t + c.z);
}

#endif
