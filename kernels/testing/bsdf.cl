/* Test harness: one Material (with its spectrum table) evaluated, sampled and queried for its pdf on arrays of
 * directions and random numbers, at four fixed wavelengths. The surface normal is +z in world space, so world and
 * local directions differ only by a rotation about the normal. */
#include "kernel_entry.h"
#include "material.cl"

inline SampledWavelengths harness_wavelengths(__global const float *lambda)
{
    return fixed_wavelengths((float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
}

#define HARNESS_NORMAL ((float3)(0.0f, 0.0f, 1.0f))

/* A material without textures needs only the spectrum table. */
inline SurfaceContext harness_context(__global const float *spectra)
{
    SurfaceContext sc;
    sc.buffers.textures = 0;
    sc.buffers.texels = 0;
    sc.buffers.spectra = spectra;
    sc.uv = (float2)(0.0f);
    sc.p = (float3)(0.0f);
    sc.footprint = 0.0f;
    sc.base_normal = (float3)(0.0f);
    sc.dpdu = (float3)(0.0f);
    sc.tangent_w = 1.0f;
    sc.adjoint = 0;
    /* what scene.cl's surface_context sets for a plain surface: the harness builds its own context */
    SURFACE_NORMAL(sc, (float3)(0.0f));
#if SCENE_HAS_MITSUBA_CURVE_UV
    sc.fibre_h_from_geometry = 0;
#endif
    return sc;
}

/* f(wo, wi)·|cos θi| and the pdf of wi given wo. */
KERNEL void bsdf_eval_pdf(__global const Material *material, __global const float *spectra,
                            __global const float *lambda, __global const float4 *wo, __global const float4 *wi,
                            __global float4 *f_cos, __global float *pdf)
{
    int i = get_global_id(0);
    SampledWavelengths w = harness_wavelengths(lambda);
    SurfaceContext sc = harness_context(spectra);
    f_cos[i] = material_eval(material, &sc, &w, HARNESS_NORMAL, wo[i].xyz, wi[i].xyz);
    pdf[i] = material_pdf(material, &sc, &w, HARNESS_NORMAL, wo[i].xyz, wi[i].xyz);
}

/* One sample per item from u = (uc, u.x, u.y); wi.w = 1 when a direction was produced. adjoint: importance
 * transport (SurfaceContext.adjoint), wo the light's side. */
inline void harness_sample(__global const Material *material, __global const float *spectra,
                           __global const float *lambda, __global const float4 *wo, __global const float4 *u,
                           __global float4 *wi, __global float4 *weight, __global float *pdf,
                           __global int *is_delta, int adjoint)
{
    int i = get_global_id(0);
    SampledWavelengths w = harness_wavelengths(lambda);
    BSDFSample s;
    SurfaceContext sc = harness_context(spectra);
    sc.adjoint = adjoint;
    int ok = material_sample(material, &sc, &w, HARNESS_NORMAL, wo[i].xyz, u[i].x, u[i].yz, &s);
    wi[i] = ok ? (float4)(s.wi, 1.0f) : (float4)(0.0f);
    weight[i] = ok ? s.weight : (float4)(0.0f);
    pdf[i] = ok ? s.pdf : 0.0f;
    is_delta[i] = ok ? s.is_delta : 0;
}

KERNEL void bsdf_sample(__global const Material *material, __global const float *spectra,
                          __global const float *lambda, __global const float4 *wo, __global const float4 *u,
                          __global float4 *wi, __global float4 *weight, __global float *pdf, __global int *is_delta)
{
    harness_sample(material, spectra, lambda, wo, u, wi, weight, pdf, is_delta, 0);
}

KERNEL void bsdf_sample_importance(__global const Material *material, __global const float *spectra,
                                     __global const float *lambda, __global const float4 *wo,
                                     __global const float4 *u, __global float4 *wi, __global float4 *weight,
                                     __global float *pdf, __global int *is_delta)
{
    harness_sample(material, spectra, lambda, wo, u, wi, weight, pdf, is_delta, 1);
}

KERNEL void bsdf_has_non_delta_lobe(__global const Material *material, __global int *result)
{
    result[0] = material_has_non_delta_lobe(material);
}

/* D(v) and G1(v) of the microfacet distribution (MICROFACET_*) of roughness alpha at local directions v. */
KERNEL void microfacet_terms(__global const float4 *v, float alpha, int distribution, __global float *d,
                               __global float *g1)
{
    int i = get_global_id(0);
    d[i] = microfacet_d(v[i].xyz, alpha, distribution);
    g1[i] = microfacet_g1(v[i].xyz, alpha, distribution);
}
