/* Test harness: the index-of-refraction models and the dielectric BSDF's eval, pdf and sample on arrays, so that
 * tests/materials/test_bsdf_dielectric.py can check them against numpy references and statistics. Directions are float4
 * with w unused, in the BSDF's local frame (+z = geometric normal, to the exterior). */
#include "kernel_entry.h"
#include "types.h"
#include "ior.cl"
#include "../bsdf_dielectric.cl"  /* not this file, which has the same name */

KERNEL void material_ior_at(__global const Material *materials, __global const int *material_index,
                              __global const float *lambda_nm, __global float *ior, __global int *dispersive)
{
    int i = get_global_id(0);
    __global const Material *m = &materials[material_index[i]];
    ior[i] = material_ior(m, lambda_nm[i]);
    dispersive[i] = material_ior_is_dispersive(m);
}

KERNEL void fresnel(__global const float *cos_i, __global const float *eta, __global float *reflectance,
                      __global float *cos_t)
{
    int i = get_global_id(0);
    float ct;
    reflectance[i] = fresnel_dielectric_refracting(cos_i[i], eta[i], &ct);
    cos_t[i] = ct;
}

/* For each ωo and uniform number: the sampled direction, weight, pdf, is_delta and whether a sample came out. */
KERNEL void smooth_sample(__global const float4 *wo, __global const float *uc, float eta, __global float4 *wi,
                            __global float *weight, __global float *pdf, __global int *ok)
{
    int i = get_global_id(0);
    DielectricSample s;
    int valid = smooth_dielectric_sample(wo[i].xyz, eta, uc[i], &s);
    ok[i] = valid ? 1 + s.is_delta : 0;
    wi[i] = valid ? (float4)(s.wi, 0.0f) : (float4)(0.0f);
    weight[i] = valid ? s.weight : 0.0f;
    pdf[i] = valid ? s.pdf : 0.0f;
}

/* distribution: MICROFACET_*. */
KERNEL void rough_eval_pdf(__global const float4 *wo, __global const float4 *wi, float eta, float alpha,
                             int distribution, __global float *f_cos, __global float *pdf)
{
    int i = get_global_id(0);
    f_cos[i] = rough_dielectric_eval(wo[i].xyz, wi[i].xyz, eta, alpha, distribution);
    pdf[i] = rough_dielectric_pdf(wo[i].xyz, wi[i].xyz, eta, alpha, distribution);
}

/* u = (uc, u1, u2, unused). */
KERNEL void rough_sample(__global const float4 *wo, __global const float4 *u, float eta, float alpha,
                           int distribution, __global float4 *wi, __global float *weight, __global float *pdf,
                           __global int *ok)
{
    int i = get_global_id(0);
    DielectricSample s;
    int valid = rough_dielectric_sample(wo[i].xyz, eta, alpha, distribution, u[i].x, u[i].yz, &s);
    ok[i] = valid ? 1 + s.is_delta : 0;
    wi[i] = valid ? (float4)(s.wi, 0.0f) : (float4)(0.0f);
    weight[i] = valid ? s.weight : 0.0f;
    pdf[i] = valid ? s.pdf : 0.0f;
}
