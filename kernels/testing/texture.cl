/* Test harness: texture lookups (texture.cl) at arrays of points, and the sigmoid spectrum (rgb_spectrum.cl) of
 * arrays of coefficients, at four fixed wavelengths. */
#include "kernel_entry.h"
#include "../texture.cl"  /* not this file, which has the same name */

inline SampledWavelengths harness_wavelengths(__global const float *lambda)
{
    return fixed_wavelengths((float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
}

/* Texture `index` at uv = point.xy with footprint point.z (uv units). */
KERNEL void texture_lookup(__global const Texture *textures, __global const float4 *texels,
                             __global const float *spectra, int index, __global const float *lambda,
                             __global const float4 *point, __global float4 *value)
{
    int i = get_global_id(0);
    TextureBuffers b;
    b.textures = textures;
    b.texels = (__global const float *)texels;
    b.spectra = spectra;
    SampledWavelengths w = harness_wavelengths(lambda);
    value[i] = texture_spectrum(&b, index, point[i].xy, point[i].z, &w);
}

/* Texture `index` at the world-space point point.xyz (uv 0, footprint 0): the solid textures' lookup. */
KERNEL void texture_lookup_point(__global const Texture *textures, __global const float4 *texels,
                                 __global const float *spectra, int index, __global const float *lambda,
                                 __global const float4 *point, __global float4 *value)
{
    int i = get_global_id(0);
    TextureBuffers b;
    b.textures = textures;
    b.texels = (__global const float *)texels;
    b.spectra = spectra;
    SampledWavelengths w = harness_wavelengths(lambda);
    value[i] = texture_spectrum_at(&b, index, (float2)(0.0f), point[i].xyz, 0.0f, &w);
}

/* S(c0 λ² + c1 λ + c2) of coefficients.xyz at the four wavelengths. */
KERNEL void sigmoid_spectrum(__global const float4 *coefficients, __global const float *lambda,
                               __global float4 *value)
{
    int i = get_global_id(0);
    value[i] = sigmoid_polynomial(coefficients[i].xyz, (float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
}

#include "../scene.cl"

/* scene.cl's camera_footprint at points p = point.xyz of triangle (int)point.w, with the camera of `params`. */
KERNEL void footprint_at(__global const RenderParams *params, __global const float4 *triangle_vertices,
                           __global const float2 *triangle_uvs, __global const float4 *point, __global float *out)
{
    int i = get_global_id(0);
    Scene scene = {0};
    scene.params = params;
    scene.triangle_vertices = triangle_vertices;
    scene.triangle_uvs = triangle_uvs;
    int triangle = (int)point[i].w;
    out[i] = camera_footprint(&scene, triangle, point[i].xyz, triangle_normal(triangle_vertices, triangle));
}
