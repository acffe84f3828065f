/* Fresnel reflectance of smooth interfaces for unpolarised light (Born & Wolf, "Principles of Optics", Sec. 1.5;
 * pbrt-v4 Sec. 9.3). */
#ifndef SPECTRACE_FRESNEL_CL
#define SPECTRACE_FRESNEL_CL

/* Dielectric interface: light arrives at cos θi ∈ [0, 1] from the side of index n_i, and eta = n_t / n_i.
 * Returns 1 under total internal reflection. *cos_t receives the cosine of the refracted direction (0 under total
 * internal reflection), which Snell's law needs next. */
inline float fresnel_dielectric_refracting(float cos_i, float eta, float *cos_t)
{
    cos_i = clamp(cos_i, 0.0f, 1.0f);
    /* cos²θt = 1 − sin²θi/η², arranged so that it does not cancel when η is near 1 ((η − 1) is exact there). */
    float cos2_t = (cos_i * cos_i + (eta - 1.0f) * (eta + 1.0f)) / (eta * eta);
    if (cos2_t <= 0.0f) {
        *cos_t = 0.0f;
        return 1.0f;
    }
    float ct = sqrt(cos2_t);
    *cos_t = ct;
    float r_parallel = (eta * cos_i - ct) / (eta * cos_i + ct);
    float r_perpendicular = (cos_i - eta * ct) / (cos_i + eta * ct);
    return 0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

inline float fresnel_dielectric(float cos_i, float eta)
{
    float cos_t;
    return fresnel_dielectric_refracting(cos_i, eta, &cos_t);
}

/* Cosine-weighted hemispherical average 2∫₀¹ F(μ) μ dμ of fresnel_dielectric for light arriving from outside
 * (eta ≥ 1), by 8-point Gauss-Legendre quadrature in μ: F is smooth in μ for eta ≥ 1, and the rule is exact to
 * about 1e-6 for eta ∈ [1.1, 4] (checked against adaptive quadrature). */
inline float fresnel_dielectric_average(float eta)
{
    const float nodes[8] = {0.019855072f, 0.101666761f, 0.237233795f, 0.408282679f,
                            0.591717321f, 0.762766205f, 0.898333239f, 0.980144928f};
    const float weights[8] = {0.050614268f, 0.111190517f, 0.156853323f, 0.181341892f,
                              0.181341892f, 0.156853323f, 0.111190517f, 0.050614268f};
    float sum = 0.0f;
    for (int i = 0; i < 8; ++i) sum += weights[i] * 2.0f * nodes[i] * fresnel_dielectric(nodes[i], eta);
    return sum;
}

/* Conductor with complex index η + ik relative to the outside, per wavelength, exact for unpolarised light
 * (the a², b² form of Born & Wolf Sec. 14.2, as written in Lazányi & Szirmay-Kalos 2005, "Fresnel term
 * approximations for metals"). At normal incidence it reduces to ((η−1)² + k²) / ((η+1)² + k²). */
inline float4 fresnel_conductor(float cos_i, float4 eta, float4 k)
{
    float c = clamp(cos_i, 0.0f, 1.0f);
    float c2 = c * c;
    float s2 = 1.0f - c2;
    float4 t = eta * eta - k * k - s2;
    float4 a2_plus_b2 = sqrt(fmax(t * t + 4.0f * eta * eta * k * k, 0.0f));
    float4 a = sqrt(fmax(0.5f * (a2_plus_b2 + t), 0.0f));
    float4 r_s = (a2_plus_b2 - 2.0f * a * c + c2) / (a2_plus_b2 + 2.0f * a * c + c2);
    float4 r_p = r_s * (c2 * a2_plus_b2 - 2.0f * a * c * s2 + s2 * s2) / (c2 * a2_plus_b2 + 2.0f * a * c * s2 + s2 * s2);
    return clamp(0.5f * (r_s + r_p), 0.0f, 1.0f);
}

#endif
