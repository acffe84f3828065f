/* What sampling a light gives and needs, shared by every device light type's file (light_<name>.cl) and the
 * dispatch (lights.cl, light_emission.cl, bdpt.cl): the sample from a shaded point (LightSample), the scene-wide
 * buffers a light may read (LightBuffers), a light's spectrum, and the warps the lights share.
 * Units: positions in scene units, spectra per the light's type (types.h, Light), densities per steradian or per
 * square scene unit as each function says. */
#ifndef SPECTRACE_LIGHT_SAMPLE_CL
#define SPECTRACE_LIGHT_SAMPLE_CL

#include "types.h"
#include "spectrum.cl"
#include "sampling.cl"
#include "texture.cl"
#include "shapes.cl"

#define INV_FOUR_PI 0.07957747154594767f
#define PI_F 3.14159265358979f

typedef struct {
    float3 wi;         /* unit direction from the shaded point toward the light */
    float distance;    /* to the light point; INFINITY for distant and environment lights */
    float3 point;      /* the light point (finite lights), to aim the shadow ray at */
    float3 normal;     /* lights on a surface (LIGHT_ON_SURFACE): its geometric normal, for the shadow ray's end offset */
    float4 arriving;   /* radiance arriving along -wi (area, environment) or, for delta lights, the irradiance
                          it produces on a surface facing it: I/d² or E (W/(m² nm)) */
    float pdf;         /* solid-angle pdf including the pick probability; for delta lights the pick probability */
    int is_delta;
} LightSample;

/* The scene-wide buffers that sampling a light may need besides the light itself. */
typedef struct {
    __global const float4 *triangle_vertices;
    __global const float2 *triangle_uvs;
    __global const float *spectra;
    __global const float4 *texels;
    __global const float *map_cdf;
    TextureBuffers textures;  /* the emission textures' rows, the same texels as floats, the spectra */
    __global const AnalyticShape *shapes;
} LightBuffers;

inline float4 light_spectrum(__global const Light *light, __global const float *spectra, const SampledWavelengths *w)
{
    return light->scale * spectrum_at(spectra, light->spectrum_offset, w);
}

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

/* Ends next-event estimation toward a light at infinity whose direction s->wi, density s->pdf and arriving
 * radiance are set: the shadow ray from p is unbounded. Returns 0 when the direction has no density. */
inline int at_infinity_sampled(float3 p, LightSample *s)
{
    s->distance = INFINITY;
    s->point = p;
    return s->pdf > 0.0f;
}

/* A direction uniform over the sphere; pdf 1/(4π) sr⁻¹. */
inline float3 sample_uniform_sphere(float2 u)
{
    float z = 1.0f - 2.0f * u.x;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    float2 circle = r * cos_sin_turns(u.y);
    return (float3)(circle.x, circle.y, z);
}

/* A direction uniform within the cone of half-angle acos(cos_max) about axis; pdf 1/(2π(1 − cos_max)) sr⁻¹. */
inline float3 sample_uniform_cone_about(float3 axis, float cos_max, float2 u)
{
    float cos_theta = 1.0f - u.x * (1.0f - cos_max);
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float2 circle = sin_theta * cos_sin_turns(u.y);
    float3 t, b;
    orthonormal_basis(axis, &t, &b);
    return circle.x * t + circle.y * b + cos_theta * axis;
}

/* A point of the disk of radius r about centre, perpendicular to the unit direction d; pdf 1/(πr²). */
inline float3 sample_disk_across(float3 centre, float3 d, float r, float2 u)
{
    float3 t, b;
    orthonormal_basis(d, &t, &b);
    float2 circle = sqrt(u.x) * r * cos_sin_turns(u.y);
    return centre + circle.x * t + circle.y * b;
}

#endif
