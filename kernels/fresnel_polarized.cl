/* Fresnel reflection and transmission of a smooth interface for polarised light: the complex amplitude
 * coefficients r_s, r_p, t_s, t_p (M. Born & E. Wolf, "Principles of Optics", 7th ed., Sec. 1.5.2, eqs. 20-21;
 * Sec. 14.2 for an absorbing medium, whose index is complex) and the Mueller matrices they give in the s/p basis
 * (E. Collett, "Field Guide to Polarization", "Fresnel equations"; mueller.cl's conventions).
 *
 * Bases (mueller.cl): both beams have x = s, the unit normal of the plane of incidence (shared by the incident,
 * reflected and refracted beams), and y = k × s, each beam's own p direction. With these p directions Born & Wolf's
 * signs hold: at normal incidence r_p = −r_s, so a mirror turns right-circular light into left-circular.
 * Light arrives at cos θi ∈ [0, 1] from the side of index 1 onto the side of relative complex index η = n + ik
 * (n_t / n_i; k = 0 for a dielectric). Units: dimensionless.
 * Handedness: Born & Wolf's amplitudes are for fields exp(−iωt), Collett's Stokes vectors (mueller.cl) for
 * exp(iωt), whose amplitudes are the complex conjugates: the retardance entry d is Im(r_s* r_p), not Im(r_s r_p*)
 * (checked against Maxwell's boundary conditions solved directly, tests/polarization/test_handedness.py). */
#ifndef SPECTRACE_FRESNEL_POLARIZED_CL
#define SPECTRACE_FRESNEL_POLARIZED_CL

#include "mueller.cl"

/* Complex numbers as float2 (re, im). */
inline float2 complex_mul(float2 a, float2 b)
{
    return (float2)(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

inline float2 complex_div(float2 a, float2 b)
{
    float d = b.x * b.x + b.y * b.y;
    return (float2)(a.x * b.x + a.y * b.y, a.y * b.x - a.x * b.y) / d;
}

/* The principal square root: for a negative real argument +i√|z|, the evanescent wave that decays away from the
 * interface under total internal reflection. */
inline float2 complex_sqrt(float2 z)
{
    float r = hypot(z.x, z.y);
    float re = sqrt(fmax(0.5f * (r + z.x), 0.0f));
    float im = sqrt(fmax(0.5f * (r - z.x), 0.0f));
    return (float2)(re, copysign(im, z.y));
}

/* r_s, r_p (and the refracted cosine, complex) of light at cos_i onto relative index eta. */
inline void fresnel_amplitudes(float cos_i, float2 eta, float2 *r_s, float2 *r_p, float2 *cos_t)
{
    float c = clamp(cos_i, 0.0f, 1.0f);
    float2 sin2_t = complex_div((float2)(1.0f - c * c, 0.0f), complex_mul(eta, eta));
    *cos_t = complex_sqrt((float2)(1.0f - sin2_t.x, -sin2_t.y));
    float2 eta_cos_t = complex_mul(eta, *cos_t);
    float2 eta_cos_i = c * eta;
    *r_s = complex_div((float2)(c, 0.0f) - eta_cos_t, (float2)(c, 0.0f) + eta_cos_t);
    *r_p = complex_div(eta_cos_i - *cos_t, eta_cos_i + *cos_t);
}

/* The reflection's Mueller matrix at one wavelength, divided by its (0, 0) entry, the unpolarised reflectance
 * (|r_s|² + |r_p|²)/2: (1, b, c, d) of the aligned form. */
inline float4 fresnel_reflection_shape(float cos_i, float2 eta)
{
    float2 rs, rp, cos_t;
    fresnel_amplitudes(cos_i, eta, &rs, &rp, &cos_t);
    float ss = rs.x * rs.x + rs.y * rs.y;
    float pp = rp.x * rp.x + rp.y * rp.y;
    float a = 0.5f * (ss + pp);
    if (!(a > 0.0f)) return (float4)(1.0f, 0.0f, 0.0f, 0.0f);
    /* r_s* r_p: its real part keeps the diagonal, its imaginary part the retardance between s and p. An exact zero
     * (no retardance) keeps the sign it had with r_s r_p*, so that those scenes keep their bits. */
    float re = rs.x * rp.x + rs.y * rp.y;
    float im = rs.y * rp.x - rs.x * rp.y;
    return (float4)(a, 0.5f * (ss - pp), re, im == 0.0f ? im : -im) / a;
}

/* The refraction's Mueller matrix into a dielectric (real eta, no total internal reflection), divided by its
 * (0, 0) entry: t_s, t_p are real, so the form is (1, (t_s² − t_p²)/(t_s² + t_p²), 2 t_s t_p/(t_s² + t_p²), 0);
 * the factor η cos θt / cos θi of the transmitted power is common to all entries and cancels. */
inline float4 fresnel_transmission_shape(float cos_i, float eta)
{
    float c = clamp(cos_i, 0.0f, 1.0f);
    float cos2_t = 1.0f - (1.0f - c * c) / (eta * eta);
    if (!(cos2_t > 0.0f)) return (float4)(1.0f, 0.0f, 0.0f, 0.0f);
    float ct = sqrt(cos2_t);
    float ts = 2.0f * c / (c + eta * ct);
    float tp = 2.0f * c / (eta * c + ct);
    float sum = ts * ts + tp * tp;
    if (!(sum > 0.0f)) return (float4)(1.0f, 0.0f, 0.0f, 0.0f);
    return (float4)(1.0f, (ts * ts - tp * tp) / sum, 2.0f * ts * tp / sum, 0.0f);
}

/* Four wavelengths' shapes (each a float4 (1, b, c, d)) gathered into one aligned element. */
inline AlignedElement aligned_from_shapes(float4 s0, float4 s1, float4 s2, float4 s3)
{
    AlignedElement e;
    e.a = (float4)(s0.x, s1.x, s2.x, s3.x);
    e.b = (float4)(s0.y, s1.y, s2.y, s3.y);
    e.c = (float4)(s0.z, s1.z, s2.z, s3.z);
    e.d = (float4)(s0.w, s1.w, s2.w, s3.w);
    return e;
}

#endif
