/* Tabulated spectra: every spectrum lives in one float table on the 1 nm grid (GRID_*_NM); a lookup at the
 * path's four wavelengths is a linear interpolation between neighbouring grid samples. The film's XYZ estimator
 * is in film.cl. */
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

#endif
