/* Homogeneous participating media filling closed shapes (subsurface scattering by a volumetric random walk).
 *
 * Inside a medium light is absorbed (σa) and scattered (σs) per unit length; between events it travels straight,
 * surviving a distance t with probability exp(−σt t), σt = σa + σs (Beer–Lambert). The four wavelengths of a
 * path see four different σt, so one free-flight distance must serve all of them: a lane c is picked uniformly and
 * t drawn from σt_c exp(−σt_c t); each lane is then weighted against the mixture of the four lanes' densities
 * (one-sample MIS with the balance heuristic, Veach 1997 §9.2.4; the "spectral MIS" of Wilkie et al. 2014,
 * "Hero wavelength spectral sampling"), which is unbiased for every lane however different their σt.
 * docs/media.md describes the scene side. */
#ifndef SPECTRACE_MEDIUM_CL
#define SPECTRACE_MEDIUM_CL

#include "types.h"
#include "spectrum.cl"
#include "sampling.cl"

/* Material-less boundaries one path (or one shadow ray) may cross: a guard against a ray stuck on a boundary by
 * rounding, far above what any scene needs. */
#define MAX_NULL_CROSSINGS 256

/* The medium a ray leaving a surface along `direction` travels in, for a ray that met it travelling in `current`:
 * at a medium boundary (a shape with an interior medium) the interior when it heads against the outward geometric
 * normal, none otherwise; any other surface (no interior) is no boundary, and the ray stays in `current`, as in
 * Mitsuba 3, where a shape without interior or exterior media keeps the ray's medium. One level only: media do not
 * nest (docs/media.md). */
inline int medium_beyond(int interior, float3 outward_normal, float3 direction, int current)
{
    if (interior < 0) return current;
    return dot(outward_normal, direction) < 0.0f ? interior : -1;
}

inline float4 medium_sigma_s(__global const Medium *m, __global const float *spectra, const SampledWavelengths *w)
{
    return spectrum_at(spectra, m->sigma_s_offset, w);
}

inline float4 medium_sigma_t(__global const Medium *m, __global const float *spectra, const SampledWavelengths *w)
{
    return spectrum_at(spectra, m->sigma_a_offset, w) + medium_sigma_s(m, spectra, w);
}

/* exp(−σt t) per lane, also for t = ∞ (where a lane with σt = 0 keeps 1 instead of exp(−0·∞) = NaN). */
inline float4 beer_lambert(float4 sigma_t, float t)
{
    return select((float4)(1.0f), exp(-sigma_t * t), sigma_t > (float4)(0.0f));
}

typedef struct {
    float distance;  /* where the flight ends: a scattering point, or the surface at t_surface */
    int scattered;   /* 1: a real scattering event before the surface */
    float4 weight;   /* throughput multiplier per lane: T·σs / p(t) at a scattering point, T / P(t ≥ t_surface) else */
#if SCENE_HAS_MEDIUM_EMISSION
    float4 emitted;  /* a glowing grid's emission gathered on the way, per lane, before `weight` (medium_emission.cl) */
#endif
} FreeFlight;

/* One free flight from the ray's origin toward the next surface at t_surface (∞ when none); `hero_only` when a
 * dispersive event left only the first lane alive (it is then the only lane sampled). */
inline FreeFlight medium_sample_flight(__global const Medium *m, __global const float *spectra,
                                       const SampledWavelengths *w, float t_surface, int hero_only, float u_lane,
                                       float u_distance)
{
    float4 sigma_s = medium_sigma_s(m, spectra, w);
    float4 sigma_t = medium_sigma_t(m, spectra, w);
    FreeFlight flight;
#if SCENE_HAS_MEDIUM_EMISSION
    flight.emitted = (float4)(0.0f);  /* a homogeneous medium's is added in closed form (medium_emission.cl) */
#endif
    if (all(sigma_s == (float4)(0.0f))) {
        /* A pure absorber scatters nowhere: the flight surely reaches the surface, weighted by its transmittance
         * (the expectation of the sampled estimate, without its noise). */
        flight.distance = t_surface;
        flight.scattered = 0;
        flight.weight = beer_lambert(sigma_t, t_surface);
        return flight;
    }
    float4 lanes = hero_only ? (float4)(1.0f, 0.0f, 0.0f, 0.0f) : (float4)(1.0f);
    float lane_count = hero_only ? 1.0f : 4.0f;
    int lane = hero_only ? 0 : min((int)(4.0f * u_lane), 3);
    float sigma_lane = lane == 0 ? sigma_t.x : lane == 1 ? sigma_t.y : lane == 2 ? sigma_t.z : sigma_t.w;
    float t = sigma_lane > 0.0f ? -log(1.0f - u_distance) / sigma_lane : INFINITY;

    if (t < t_surface) {
        float4 transmittance = beer_lambert(sigma_t, t);
        float pdf = dot(lanes, sigma_t * transmittance) / lane_count;
        flight.distance = t;
        flight.scattered = 1;
        flight.weight = pdf > 0.0f ? lanes * sigma_s * transmittance / pdf : (float4)(0.0f);
    } else {
        float4 transmittance = beer_lambert(sigma_t, t_surface);
        float probability = dot(lanes, transmittance) / lane_count;
        flight.distance = t_surface;
        flight.scattered = 0;
        flight.weight = probability > 0.0f ? lanes * transmittance / probability : (float4)(0.0f);
    }
    return flight;
}

/* Henyey & Greenstein 1941 phase function: p(cos θ) = (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2}), θ measured from
 * the direction light travels, mean cosine g. */
inline float henyey_greenstein(float cos_theta, float g)
{
    float denominator = 1.0f + g * g - 2.0f * g * cos_theta;
    return (1.0f - g * g) / (4.0f * M_PI_F * denominator * sqrt(denominator));
}

/* A direction after scattering light that travelled along `direction`, drawn exactly from the phase function
 * (its CDF in cos θ inverted in closed form), so the throughput weight is 1. */
inline float3 sample_henyey_greenstein(float3 direction, float g, float2 u)
{
    float cos_theta;
    if (fabs(g) < 1.0e-3f) {
        cos_theta = 1.0f - 2.0f * u.x;
    } else {
        float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u.x);
        cos_theta = (1.0f + g * g - s * s) / (2.0f * g);
    }
    cos_theta = clamp(cos_theta, -1.0f, 1.0f);
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float2 around = sin_theta * cos_sin_turns(u.y);
    float3 tangent, bitangent;
    orthonormal_basis(direction, &tangent, &bitangent);
    return normalize(around.x * tangent + around.y * bitangent + cos_theta * direction);
}

#include "medium_grid.cl"

#endif
