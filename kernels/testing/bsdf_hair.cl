/* Test harness: a hair Material (kernels/bsdf_hair.cl) through material.cl's dispatch, at an offset h across the
 * fibre given per item (the v texture coordinate, h = 2v − 1) and four fixed wavelengths. The surface normal is +z
 * and dp/du, the fibre's direction, +x, so world and local directions are the same. */
#include "kernel_entry.h"
#include "material.cl"

inline SurfaceContext hair_harness_context(__global const float *spectra, float h, int adjoint)
{
    SurfaceContext sc;
    sc.buffers.textures = 0;
    sc.buffers.texels = 0;
    sc.buffers.spectra = spectra;
    sc.uv = (float2)(0.5f, 0.5f * (h + 1.0f));
    sc.footprint = 0.0f;
    sc.base_normal = (float3)(0.0f);
    sc.dpdu = (float3)(1.0f, 0.0f, 0.0f);
    sc.tangent_w = 1.0f;
    sc.adjoint = adjoint;
    /* what scene.cl's surface_context sets for a plain surface: the harness builds its own context */
    SURFACE_NORMAL(sc, (float3)(0.0f));
#if SCENE_HAS_MITSUBA_CURVE_UV
    sc.fibre_h_from_geometry = 0;
#endif
    return sc;
}

#define HAIR_HARNESS_NORMAL ((float3)(0.0f, 0.0f, 1.0f))

/* f(wo, wi)·|cos θi| (the fibre's S) and the pdf of wi given wo, at offsets h. */
KERNEL void hair_harness_eval_pdf(__global const Material *material, __global const float *spectra,
                          __global const float *lambda, __global const float4 *wo, __global const float4 *wi,
                          __global const float *h, __global float4 *f_cos, __global float *pdf)
{
    int i = get_global_id(0);
    SampledWavelengths w = fixed_wavelengths((float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
    SurfaceContext sc = hair_harness_context(spectra, h[i], 0);
    f_cos[i] = material_eval(material, &sc, &w, HAIR_HARNESS_NORMAL, wo[i].xyz, wi[i].xyz);
    pdf[i] = material_pdf(material, &sc, &w, HAIR_HARNESS_NORMAL, wo[i].xyz, wi[i].xyz);
}

/* One sample per item from u = (uc, u.x, u.y) at offset h; wi.w = 1 when a direction was produced. */
KERNEL void hair_harness_sample(__global const Material *material, __global const float *spectra,
                        __global const float *lambda, __global const float4 *wo, __global const float4 *u,
                        __global const float *h, int adjoint, __global float4 *wi, __global float4 *weight,
                        __global float *pdf)
{
    int i = get_global_id(0);
    SampledWavelengths w = fixed_wavelengths((float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
    SurfaceContext sc = hair_harness_context(spectra, h[i], adjoint);
    BSDFSample s;
    int ok = material_sample(material, &sc, &w, HAIR_HARNESS_NORMAL, wo[i].xyz, u[i].x, u[i].yz, &s);
    wi[i] = ok ? (float4)(s.wi, 1.0f) : (float4)(0.0f);
    weight[i] = ok ? s.weight : (float4)(0.0f);
    pdf[i] = ok ? s.pdf : 0.0f;
}
