/* RGB reflectances as smooth spectra: Jakob & Hanika 2019, "A Low-Dimensional Function Space for Efficient
 * Spectral Upsampling" (Computer Graphics Forum 38(2)). The host fits three coefficients per colour
 * (spectrace.spectral.uplift); the spectrum is the sigmoid S(x) = 1/2 + x / (2 sqrt(1 + x²)) of the quadratic
 * x = c0 λ² + c1 λ + c2 in λ (nm), evaluated in Horner form as the host's sigmoid_polynomial_spectrum does. S has
 * no exp, stays in (0, 1), and the host's saturated coefficients (c2 = ±1e6) give exactly 0 and 1 in float32. */
#ifndef SPECTRACE_RGB_SPECTRUM_CL
#define SPECTRACE_RGB_SPECTRUM_CL

inline float4 sigmoid_polynomial(float3 c, float4 lambda_nm)
{
    float4 x = (c.x * lambda_nm + c.y) * lambda_nm + c.z;
    return 0.5f + x / (2.0f * sqrt(1.0f + x * x));
}

#endif
