/* A measured BRDF of the RGL material database in the adaptive parameterisation of Dupuy & Jakob 2018 ("An
 * Adaptive Parameterization for Efficient Material Acquisition and Rendering", ACM Trans. Graph. 37(6)), read as
 * Mitsuba 3's `measured` and pbrt-v4's MeasuredBxDF read the same files (spectrace.materials.measured).
 *
 * Angles map to the unit square by u(θ, φ) = (√(2θ/π), (φ + π) / 2π). For the viewer's direction ωo (θo, φo) and a
 * microfacet normal ωm (an isotropic file's φm counted from φo), the visible-normal table's inverse map s = V⁻¹(u(ωm))
 * is the point of the measurement where the spectra R(s, λ) were tabulated, and
 *     f(ωo, ωi) cos θi = R(s, λ) D(u(ωm)) / (4 σ(u(ωo))),   ωm = (ωo + ωi) / |ωo + ωi|,
 * D the microfacet distribution, σ its projected area (both tabulated on u; files without `jacobian` hold the
 * product whole). Each path wavelength reads R between the file's two nearest wavelengths (clamped at its ends):
 * spectra, not a colour. R below 0 (measurement noise) reads as 0, as pbrt-v4 reads it.
 *
 * Sampling: the luminance table (warp_bilinear_2d.cl) warps u to s, the visible-normal table warps s to u(ωm), and
 * ωi is ωo reflected about ωm; its density per solid angle is V(u(ωm)) L(s) / (2π² uθ sin θm · 4 ωo·ωm), the
 * Jacobians of the square to angles to normals to reflected directions. A sample's value and density are those
 * measured_eval and measured_pdf give at its direction, so the two agree exactly.
 *
 * One face: ωo and ωi above the surface (spectrace's reflectors turn the frame toward the viewer, unless
 * two_sided = false, as Mitsuba 3's importer sets outside `twosided`). Anisotropic files folded by a symmetry
 * (`reduction` 2 or 4: phi_i spans π or π/2) mirror both directions into the tabulated quadrants, as Mitsuba does.
 * The measured BRDF is reciprocal only as far as the measurement is: importance transport (SurfaceContext.adjoint)
 * weighs its samples by the value with the directions swapped, the adjoint BSDF. Units: angles in radians,
 * wavelengths in nm; the block's layout is spectrace.materials.measured.HEADER. */
#ifndef SPECTRACE_BSDF_MEASURED_CL
#define SPECTRACE_BSDF_MEASURED_CL

#include "bsdf_sample.cl"
#include "spectrum.cl"
#include "texture.cl"
#include "warp_bilinear_2d.cl"

/* The header fields of the block (spectrace.materials.measured.HEADER), in its order. */
enum {
    MEASURED_PHI_COUNT, MEASURED_THETA_COUNT, MEASURED_WAVELENGTH_COUNT, MEASURED_ISOTROPIC, MEASURED_JACOBIAN,
    MEASURED_REDUCTION, MEASURED_PHI_VALUES, MEASURED_THETA_VALUES, MEASURED_WAVELENGTH_VALUES,
    MEASURED_NDF, MEASURED_NDF_WIDTH, MEASURED_NDF_HEIGHT,
    MEASURED_SIGMA, MEASURED_SIGMA_WIDTH, MEASURED_SIGMA_HEIGHT,
    MEASURED_SPECTRA, MEASURED_SPECTRA_WIDTH, MEASURED_SPECTRA_HEIGHT,
    MEASURED_VNDF, MEASURED_VNDF_MARGINAL, MEASURED_VNDF_CONDITIONAL, MEASURED_VNDF_WIDTH, MEASURED_VNDF_HEIGHT,
    MEASURED_LUMINANCE, MEASURED_LUMINANCE_MARGINAL, MEASURED_LUMINANCE_CONDITIONAL, MEASURED_LUMINANCE_WIDTH,
    MEASURED_LUMINANCE_HEIGHT
};

typedef struct {
    __global const float *block;
    float4 lambda;  /* nm */
    int adjoint;    /* importance transport: a sample weighs the value with its directions swapped */
} MeasuredParams;

inline int measured_flags(__global const Material *m)
{
    return BSDF_NON_DELTA;
}

inline MeasuredParams measured_params(__global const Material *m, const SurfaceContext *sc,
                                      const SampledWavelengths *w)
{
    MeasuredParams p;
    p.block = sc->buffers.spectra + m->eta_offset;
    p.lambda = w->lambda;
    p.adjoint = sc->adjoint;
    return p;
}

inline int measured_int(const MeasuredParams *p, int field)
{
    return ((__global const int *)p->block)[field];
}

inline WarpTable measured_table(const MeasuredParams *p, int first, int sampled)
{
    WarpTable t;
    t.data = measured_int(p, first);
    t.marginal = sampled ? measured_int(p, first + 1) : 0;
    t.conditional = sampled ? measured_int(p, first + 2) : 0;
    t.width = measured_int(p, first + (sampled ? 3 : 1));
    t.height = measured_int(p, first + (sampled ? 4 : 2));
    return t;
}

/* The slices of the tables over (φo, θo), and, with a wavelength, over (φo, θo, λ). */
inline WarpSlices measured_slices(const MeasuredParams *p, float phi_o, float theta_o, int with_lambda, float lambda)
{
    int offset[3] = {measured_int(p, MEASURED_PHI_VALUES), measured_int(p, MEASURED_THETA_VALUES),
                     measured_int(p, MEASURED_WAVELENGTH_VALUES)};
    int count[3] = {measured_int(p, MEASURED_PHI_COUNT), measured_int(p, MEASURED_THETA_COUNT),
                    measured_int(p, MEASURED_WAVELENGTH_COUNT)};
    float at[3] = {phi_o, theta_o, lambda};
    return warp_slices(p->block, with_lambda ? 3 : 2, offset, count, at);
}

/* The angle from +z of unit d, accurate near the pole (where acos loses half its digits). */
inline float measured_elevation(float3 d)
{
    float3 e = d - (float3)(0.0f, 0.0f, 1.0f);
    return 2.0f * asin(fmin(0.5f * length(e), 1.0f));
}

inline float measured_theta_to_u(float theta)
{
    return sqrt(fmax(theta, 0.0f) * (2.0f / M_PI_F));
}

inline float measured_phi_to_u(float phi)
{
    return (phi + M_PI_F) * (0.5f / M_PI_F);
}

/* −a where b ≥ 0 (its sign bit clear), a otherwise: mirrors a direction into the quadrants a folded file holds. */
inline float measured_fold(float a, float b)
{
    return signbit(b) ? a : -a;
}

/* What eval and pdf share at a pair of directions above the surface: the viewer's angles, u(ωo), u(ωm), ωm's
 * elevation's sine, ωo·ωm and the measurement's point s with the visible-normal density there. */
typedef struct {
    float phi_o, theta_o;
    float2 u_o, u_m;
    float sin_theta_m, cos_om;
    float2 s;
    float vndf;
} MeasuredPair;

inline MeasuredPair measured_pair(const MeasuredParams *p, float3 wo, float3 wi)
{
    int reduction = measured_int(p, MEASURED_REDUCTION);
    if (reduction >= 2) {
        float sy = wo.y, sx = reduction == 4 ? wo.x : sy;
        wo.x = measured_fold(wo.x, sx);
        wo.y = measured_fold(wo.y, sy);
        wi.x = measured_fold(wi.x, sx);
        wi.y = measured_fold(wi.y, sy);
    }
    MeasuredPair q;
    float3 m = normalize(wo + wi);
    q.theta_o = measured_elevation(wo);
    q.phi_o = atan2(wo.y, wo.x);
    float phi_m = atan2(m.y, m.x);
    if (measured_int(p, MEASURED_ISOTROPIC)) phi_m -= q.phi_o;
    q.u_o = (float2)(measured_theta_to_u(q.theta_o), measured_phi_to_u(q.phi_o));
    q.u_m = (float2)(measured_theta_to_u(measured_elevation(m)), measured_phi_to_u(phi_m));
    q.u_m.y -= floor(q.u_m.y);
    q.sin_theta_m = sqrt(m.x * m.x + m.y * m.y);
    q.cos_om = dot(wo, m);
    WarpSlices slices = measured_slices(p, q.phi_o, q.theta_o, 0, 0.0f);
    WarpTable vndf = measured_table(p, MEASURED_VNDF, 1);
    q.s = warp_invert(p->block, &vndf, &slices, q.u_m, &q.vndf);
    return q;
}

/* f·cos θi from the viewer's side wo to the light's side wi. */
inline float4 measured_value(const MeasuredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return (float4)(0.0f);
    MeasuredPair q = measured_pair(p, wo, wi);
    WarpTable spectra = measured_table(p, MEASURED_SPECTRA, 0);
    float r[4], lambda[4] = {p->lambda.x, p->lambda.y, p->lambda.z, p->lambda.w};
    for (int k = 0; k < 4; ++k) {
        WarpSlices slices = measured_slices(p, q.phi_o, q.theta_o, 1, lambda[k]);
        r[k] = fmax(warp_eval(p->block, &spectra, &slices, q.s), 0.0f);
    }
    float4 value = (float4)(r[0], r[1], r[2], r[3]);
    if (measured_int(p, MEASURED_JACOBIAN)) {
        WarpSlices none = warp_no_slices();
        WarpTable ndf = measured_table(p, MEASURED_NDF, 0), sigma = measured_table(p, MEASURED_SIGMA, 0);
        float projected = warp_eval(p->block, &sigma, &none, q.u_o);
        value *= projected > 0.0f ? warp_eval(p->block, &ndf, &none, q.u_m) / (4.0f * projected) : 0.0f;
    }
    return value;
}

inline float4 measured_eval(const MeasuredParams *p, float3 wo, float3 wi)
{
    return measured_value(p, wo, wi);
}

inline float measured_pdf(const MeasuredParams *p, float3 wo, float3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    MeasuredPair q = measured_pair(p, wo, wi);
    WarpSlices slices = measured_slices(p, q.phi_o, q.theta_o, 0, 0.0f);
    WarpTable luminance = measured_table(p, MEASURED_LUMINANCE, 1);
    float jacobian = fmax(2.0f * M_PI_F * M_PI_F * q.u_m.x * q.sin_theta_m, 1e-6f) * 4.0f * q.cos_om;
    float pdf = q.vndf * warp_eval(p->block, &luminance, &slices, q.s) / jacobian;
    return isfinite(pdf) && pdf > 0.0f ? pdf : 0.0f;
}

inline int measured_sample(const MeasuredParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (wo.z <= 0.0f) return 0;
    float3 v = wo;
    float sx = -1.0f, sy = -1.0f;
    int reduction = measured_int(p, MEASURED_REDUCTION);
    if (reduction >= 2) {
        sy = v.y;
        sx = reduction == 4 ? v.x : sy;
        v.x = measured_fold(v.x, sx);
        v.y = measured_fold(v.y, sy);
    }
    float theta_o = measured_elevation(v), phi_o = atan2(v.y, v.x);
    WarpSlices slices = measured_slices(p, phi_o, theta_o, 0, 0.0f);
    WarpTable luminance = measured_table(p, MEASURED_LUMINANCE, 1), vndf = measured_table(p, MEASURED_VNDF, 1);
    float pdf_luminance, pdf_vndf;
    float2 point = warp_sample(p->block, &luminance, &slices, (float2)(u.y, u.x), &pdf_luminance);
    float2 u_m = warp_sample(p->block, &vndf, &slices, point, &pdf_vndf);
    float theta_m = u_m.x * u_m.x * (0.5f * M_PI_F), phi_m = (2.0f * u_m.y - 1.0f) * M_PI_F;
    if (measured_int(p, MEASURED_ISOTROPIC)) phi_m += phi_o;
    float cos_phi, sin_phi = sincos(phi_m, &cos_phi), cos_theta, sin_theta = sincos(theta_m, &cos_theta);
    float3 m = (float3)(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta);
    float3 wi = 2.0f * dot(m, v) * m - v;
    /* Back out of the folded quadrant: the mirror that took wo there takes wi back. */
    wi.x = measured_fold(wi.x, sx);
    wi.y = measured_fold(wi.y, sy);
    if (wi.z <= 0.0f) return 0;
    float4 f_cos = measured_value(p, wo, wi);
    /* Importance flows from wo (the light's side) to wi: the value with the directions swapped, divided by wo's
     * cosine and times wi's (the adjoint BSDF f(wi, wo) times wi's cosine). */
    if (p->adjoint) f_cos = measured_value(p, wi, wo) * (wi.z / wo.z);
    return continuous_sample(wi, f_cos, measured_pdf(p, wo, wi), s);
}

#endif
