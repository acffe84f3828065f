/* Tabulated spectra: every spectrum lives in one float table on the 1 nm grid of types.h; a lookup at the
 * path's four wavelengths is a linear interpolation between neighbouring grid samples. */
#ifndef SPECTRACE_SPECTRUM_CL
#define SPECTRACE_SPECTRUM_CL

#include "wavelengths.cl"

inline float table_lerp(__global const float *table, int index, float frac)
{
    float a = table[index];
    return mad(frac, table[index + 1] - a, a);
}

inline float4 spectrum_at(__global const float *table, int offset, const SampledWavelengths *w)
{
    int4 i = w->grid_index + offset;
    return (float4)(table_lerp(table, i.x, w->grid_frac.x), table_lerp(table, i.y, w->grid_frac.y),
                    table_lerp(table, i.z, w->grid_frac.z), table_lerp(table, i.w, w->grid_frac.w));
}

inline float4 cmf_at(__global const float4 *cmf, int index, float frac)
{
    float4 a = cmf[index];
    return mad((float4)(frac), cmf[index + 1] - a, a);
}

/* Monte Carlo estimate of film XYZ = ∫ L(λ) cmf(λ) dλ / ∫ȳ (the CMF table is pre-divided by ∫ȳ), averaging the
 * four wavelengths' estimates L(λ_i) cmf(λ_i) / p(λ_i). */
inline float4 spectrum_to_xyz_estimate(float4 radiance, __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 weight = radiance / w->pdf;
    float4 xyz = weight.x * cmf_at(cmf, w->grid_index.x, w->grid_frac.x)
               + weight.y * cmf_at(cmf, w->grid_index.y, w->grid_frac.y)
               + weight.z * cmf_at(cmf, w->grid_index.z, w->grid_frac.z)
               + weight.w * cmf_at(cmf, w->grid_index.w, w->grid_frac.w);
    return 0.25f * (float4)(xyz.x, xyz.y, xyz.z, 0.0f);
}

#endif
