/* Index of refraction of a dielectric's interior at one wavelength, from the models of Material.ior_model.
 * Sellmeier and Cauchy formulas take λ in µm, as glass catalogues state their coefficients (SCHOTT; the
 * refractiveindex.info database); the index is relative to the exterior medium, air. */
#ifndef SPECTRACE_IOR_CL
#define SPECTRACE_IOR_CL

#include "types.h"

/* n²(λ) = 1 + Σ B_i λ² / (λ² − C_i), the three-term Sellmeier formula (Sellmeier 1871). */
inline float sellmeier_ior(float4 b, float4 c_um2, float lambda_nm)
{
    float lambda_um = lambda_nm * 1e-3f;
    float l2 = lambda_um * lambda_um;
    float n2 = 1.0f + b.x * l2 / (l2 - c_um2.x) + b.y * l2 / (l2 - c_um2.y) + b.z * l2 / (l2 - c_um2.z);
    return sqrt(fmax(n2, 0.0f));
}

/* n(λ) = a + b / λ², Cauchy's two-term formula. */
inline float cauchy_ior(float a, float b_um2, float lambda_nm)
{
    float lambda_um = lambda_nm * 1e-3f;
    return a + b_um2 / (lambda_um * lambda_um);
}

inline float material_ior(__global const Material *m, float lambda_nm)
{
    if (m->ior_model == IOR_SELLMEIER) return sellmeier_ior(m->ior_coefficients_b, m->ior_coefficients_c, lambda_nm);
    if (m->ior_model == IOR_CAUCHY) return cauchy_ior(m->ior_coefficients_b.x, m->ior_coefficients_b.y, lambda_nm);
    return m->ior;
}

/* Whether the index depends on the wavelength, so that refraction sends each wavelength its own way. */
inline int material_ior_is_dispersive(__global const Material *m)
{
    return m->ior_model == IOR_SELLMEIER || m->ior_model == IOR_CAUCHY;
}

#endif
