/* Environment lights: light from infinitely far away, a constant radiance or a latitude-longitude RGB map.
 *
 * Map convention (+y up): a direction d has θ = acos(d.y) (0 at the zenith) and φ = atan2(d.x, −d.z); texel
 * column u = (φ + π) / 2π, row v = θ / π, row 0 at the top. Each texel's radiance is r·R(λ) + g·G(λ) + b·B(λ), with
 * R, G, B the emission spectra uplifted from the three primaries, so the map's linear sRGB is reproduced exactly.
 * The map is importance-sampled by a piecewise-constant density ∝ luminance × sin θ (marginal CDF over rows, then
 * a conditional CDF within the row), as in pbrt-v4's image infinite light. A map may be turned: the light's
 * `position` and `direction` hold the first two rows of the rotation from world to map directions (the third is
 * their cross product), the identity unless the scene turns it. */
#ifndef SPECTRACE_ENVIRONMENT_CL
#define SPECTRACE_ENVIRONMENT_CL

#include "types.h"
#include "spectrum.cl"
#include "sampling.cl"

#define INV_FOUR_PI 0.07957747154594767f
#define PI_F 3.14159265358979f

/* Smallest i in [0, count) with u < cdf[i + 1]. */
inline int cdf_search(__global const float *cdf, int count, float u)
{
    int lo = 0, hi = count - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (u < cdf[mid + 1]) hi = mid; else lo = mid + 1;
    }
    return lo;
}

inline float2 direction_to_map_uv(float3 d)
{
    float theta = acos(clamp(d.y, -1.0f, 1.0f));
    float phi = atan2(d.x, -d.z);
    return (float2)((phi + PI_F) / (2.0f * PI_F), theta / PI_F);
}

inline float3 map_uv_to_direction(float2 uv)
{
    float theta = uv.y * PI_F;
    float phi = uv.x * 2.0f * PI_F - PI_F;
    float s = sin(theta);
    return (float3)(s * sin(phi), cos(theta), -s * cos(phi));
}

/* World direction -> the map's own frame, and back (the rotation's rows: x, y, and z = x × y). */
inline float3 world_to_map(__global const Light *light, float3 d)
{
    float3 x = light->position.xyz, y = light->direction.xyz;
    return (float3)(dot(x, d), dot(y, d), dot(cross(x, y), d));
}

inline float3 map_to_world(__global const Light *light, float3 d)
{
    float3 x = light->position.xyz, y = light->direction.xyz;
    return d.x * x + d.y * y + d.z * cross(x, y);
}

inline int map_texel(__global const Light *light, float2 uv)
{
    int column = clamp((int)(uv.x * (float)light->map_width), 0, light->map_width - 1);
    int row = clamp((int)(uv.y * (float)light->map_height), 0, light->map_height - 1);
    return row * light->map_width + column;
}

/* r·R(λ) + g·G(λ) + b·B(λ) of a texel: the light's three basis spectra weighted by the texel's RGB. */
inline float4 texel_radiance(__global const Light *light, __global const float *spectra, float4 rgb,
                             const SampledWavelengths *w)
{
    return light->scale * (rgb.x * spectrum_at(spectra, light->spectrum_offset, w)
                         + rgb.y * spectrum_at(spectra, light->basis_green_offset, w)
                         + rgb.z * spectrum_at(spectra, light->basis_blue_offset, w));
}

/* Radiance arriving from direction d (pointing away from the scene). */
inline float4 environment_radiance(__global const Light *light, __global const float *spectra,
                                   __global const float4 *texels, const SampledWavelengths *w, float3 d)
{
    if (LIGHT_IS(light, LIGHT_ENVIRONMENT)) return light->scale * spectrum_at(spectra, light->spectrum_offset, w);
    return texel_radiance(light, spectra, texels[light->texel_offset + map_texel(light, direction_to_map_uv(world_to_map(light, d)))], w);
}

/* Solid-angle pdf of sampling direction d, times the light's pick probability. map_cdf holds the marginal CDF
 * over rows (height + 1 floats), then each row's conditional CDF (width + 1 floats). */
inline float environment_pdf(__global const Light *light, __global const float *map_cdf, float3 d)
{
    if (LIGHT_IS(light, LIGHT_ENVIRONMENT)) return light->pmf * INV_FOUR_PI;
    float2 uv = direction_to_map_uv(world_to_map(light, d));
    int width = light->map_width, height = light->map_height;
    int row = clamp((int)(uv.y * (float)height), 0, height - 1);
    int column = clamp((int)(uv.x * (float)width), 0, width - 1);
    __global const float *row_cdf = map_cdf + (height + 1) + row * (width + 1);
    float density_uv = (map_cdf[row + 1] - map_cdf[row]) * (row_cdf[column + 1] - row_cdf[column])
                     * (float)(width * height);
    float sin_theta = sin(uv.y * PI_F);
    if (!(sin_theta > 0.0f)) return 0.0f;
    return light->pmf * density_uv / (2.0f * PI_F * PI_F * sin_theta);
}

/* Samples a direction toward the environment; returns it with its pdf (pick probability included). */
inline float3 environment_sample(__global const Light *light, __global const float *map_cdf, float2 u, float *pdf)
{
    if (LIGHT_IS(light, LIGHT_ENVIRONMENT)) {
        float z = 1.0f - 2.0f * u.x;
        float r = sqrt(fmax(0.0f, 1.0f - z * z));
        float2 circle = r * cos_sin_turns(u.y);
        *pdf = light->pmf * INV_FOUR_PI;
        return (float3)(circle.x, circle.y, z);
    }
    int width = light->map_width, height = light->map_height;
    int row = cdf_search(map_cdf, height, u.x);
    float row_mass = map_cdf[row + 1] - map_cdf[row];
    float v = ((float)row + clamp((u.x - map_cdf[row]) / row_mass, 0.0f, 0.99999994f)) / (float)height;
    __global const float *row_cdf = map_cdf + (height + 1) + row * (width + 1);
    int column = cdf_search(row_cdf, width, u.y);
    float column_mass = row_cdf[column + 1] - row_cdf[column];
    float uu = ((float)column + clamp((u.y - row_cdf[column]) / column_mass, 0.0f, 0.99999994f)) / (float)width;
    float sin_theta = sin(v * PI_F);
    *pdf = sin_theta > 0.0f
         ? light->pmf * row_mass * column_mass * (float)(width * height) / (2.0f * PI_F * PI_F * sin_theta)
         : 0.0f;
    return map_to_world(light, map_uv_to_direction((float2)(uu, v)));
}

#endif
