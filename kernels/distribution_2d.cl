/* A piecewise-constant density over the unit square [0, 1)², tabulated on width × height cells (Pharr, Jakob &
 * Humphreys, "Physically Based Rendering", 4th ed., sec. A.5.6, the marginal and conditional densities of a 2-D
 * function): a row is drawn from the marginal CDF, then a column from that row's conditional CDF, each continued
 * linearly within its cell. `cdf` holds the marginal CDF over rows (height + 1 floats, 0 to 1), then each row's
 * conditional CDF (width + 1 floats, 0 to 1), as spectrace.lights.distribution.piecewise_constant_2d writes them.
 * Densities are per unit area of the square: (row's mass) · (column's mass in its row) · width · height.
 * Used by the environment map (light_environment_map.cl), the projector and the goniometric light. */
#ifndef SPECTRACE_DISTRIBUTION_2D_CL
#define SPECTRACE_DISTRIBUTION_2D_CL

#include "light_sample.cl"

/* The point of the square that u ∈ [0, 1)² maps to; *row_mass and *column_mass the two masses whose product times
 * width · height is its density. */
inline float2 distribution_2d_sample(__global const float *cdf, int width, int height, float2 u, float *row_mass,
                                     float *column_mass)
{
    int row = cdf_search(cdf, height, u.x);
    *row_mass = cdf[row + 1] - cdf[row];
    float v = ((float)row + clamp((u.x - cdf[row]) / *row_mass, 0.0f, 0.99999994f)) / (float)height;
    __global const float *row_cdf = cdf + (height + 1) + row * (width + 1);
    int column = cdf_search(row_cdf, width, u.y);
    *column_mass = row_cdf[column + 1] - row_cdf[column];
    float uu = ((float)column + clamp((u.y - row_cdf[column]) / *column_mass, 0.0f, 0.99999994f)) / (float)width;
    return (float2)(uu, v);
}

/* The density at the point uv of the square (clamped into it). */
inline float distribution_2d_density(__global const float *cdf, int width, int height, float2 uv)
{
    int row = clamp((int)(uv.y * (float)height), 0, height - 1);
    int column = clamp((int)(uv.x * (float)width), 0, width - 1);
    __global const float *row_cdf = cdf + (height + 1) + row * (width + 1);
    return (cdf[row + 1] - cdf[row]) * (row_cdf[column + 1] - row_cdf[column]) * (float)(width * height);
}

#endif
