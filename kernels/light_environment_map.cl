/* An environment map (pbrt-v4's ImageInfiniteLight; Mitsuba 3's envmap): light from infinitely far away given by a
 * latitude-longitude RGB image, radiance W/(m² sr nm) times the light's scale.
 *
 * Map convention (+y up): a direction d has θ = acos(d.y) (0 at the zenith) and φ = atan2(d.x, −d.z); texel
 * column u = (φ + π) / 2π, row v = θ / π, row 0 at the top. Each texel's radiance is r·R(λ) + g·G(λ) + b·B(λ), with
 * R, G, B the emission spectra uplifted from the three primaries (Light.spectrum_offset, basis_green_offset,
 * basis_blue_offset), so the map's linear sRGB is reproduced exactly; or, for `texel_spectra = "smooth"`
 * (basis_green_offset SMOOTH_TEXELS, -1), as Mitsuba 3's spectral variants and pbrt-v4's RGBIlluminantSpectrum
 * (Jakob & Hanika 2019): s · S(a t² + b t + c) · D65(λ), the texel holding the dimensionless sigmoid coefficients
 * (a, b, c) of its colour over s = 2 max(r, g, b) and s (rgb_spectrum.cl), D65 at Light.spectrum_offset. The map is importance-sampled by a
 * piecewise-constant density ∝ luminance × sin θ (distribution_2d.cl: marginal CDF over rows, then a conditional CDF
 * within the row), as in pbrt-v4's image infinite light. A map may be turned: the light's `position` and `direction`
 * hold the first two rows of the rotation from world to map directions (the third is their cross product), the
 * identity unless the scene turns it. Contract: Light.map_width, map_height >= 1; texels from Light.texel_offset;
 * map_cdf as below. */
#ifndef SPECTRACE_LIGHT_ENVIRONMENT_MAP_CL
#define SPECTRACE_LIGHT_ENVIRONMENT_MAP_CL

#include "light_sample.cl"
#include "distribution_2d.cl"
#include "rgb_spectrum.cl"

#define LIGHT_ENVIRONMENT_MAP_DELTA 0

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

/* r·R(λ) + g·G(λ) + b·B(λ) of a texel: the light's three basis spectra weighted by the texel's RGB (or its smooth
 * spectrum, above). */
inline float4 texel_radiance(__global const Light *light, __global const float *spectra, float4 rgb,
                             const SampledWavelengths *w)
{
#if SCENE_HAS_SMOOTH_ENVIRONMENT_MAP
    if (light->basis_green_offset < 0)
        return (light->scale * rgb.w) * sigmoid_polynomial_dimensionless(rgb.xyz, w->lambda)
             * spectrum_at(spectra, light->spectrum_offset, w);
#endif
    return light->scale * (rgb.x * spectrum_at(spectra, light->spectrum_offset, w)
                         + rgb.y * spectrum_at(spectra, light->basis_green_offset, w)
                         + rgb.z * spectrum_at(spectra, light->basis_blue_offset, w));
}

/* Radiance arriving from direction d (pointing away from the scene). */
inline float4 light_environment_map_radiance(__global const Light *light, __global const float *spectra,
                                             __global const float4 *texels, const SampledWavelengths *w, float3 d)
{
    return texel_radiance(light, spectra, texels[light->texel_offset + map_texel(light, direction_to_map_uv(world_to_map(light, d)))], w);
}

/* Solid-angle pdf of sampling direction d, times the light's pick probability. map_cdf holds the marginal CDF
 * over rows (height + 1 floats), then each row's conditional CDF (width + 1 floats). */
inline float light_environment_map_pdf_wi(__global const Light *light, __global const float *map_cdf, float3 d)
{
    float2 uv = direction_to_map_uv(world_to_map(light, d));
    float density_uv = distribution_2d_density(map_cdf, light->map_width, light->map_height, uv);
    float sin_theta = sin(uv.y * PI_F);
    if (!(sin_theta > 0.0f)) return 0.0f;
    return light->pmf * density_uv / (2.0f * PI_F * PI_F * sin_theta);
}

/* Samples a direction toward the environment; returns it with its pdf (pick probability included). */
inline float3 light_environment_map_sample_wi(__global const Light *light, __global const float *map_cdf, float2 u,
                                              float *pdf)
{
    int width = light->map_width, height = light->map_height;
    float row_mass, column_mass;
    float2 uv = distribution_2d_sample(map_cdf, width, height, u, &row_mass, &column_mass);
    float uu = uv.x, v = uv.y;
    float sin_theta = sin(v * PI_F);
    *pdf = sin_theta > 0.0f
         ? light->pmf * row_mass * column_mass * (float)(width * height) / (2.0f * PI_F * PI_F * sin_theta)
         : 0.0f;
    return map_to_world(light, map_uv_to_direction((float2)(uu, v)));
}

inline int light_environment_map_sample_li(__global const Light *light, const LightBuffers *buffers,
                                           const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    s->wi = light_environment_map_sample_wi(light, buffers->map_cdf, u, &s->pdf);
    s->arriving = light_environment_map_radiance(light, buffers->spectra, buffers->texels, w, s->wi);
    return at_infinity_sampled(p, s);
}

#endif
