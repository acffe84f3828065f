/* Test harness for kernels/medium.cl: free flights at four given wavelengths, and phase-function samples. */
#include "kernel_entry.h"
#include "rng.cl"
#include "medium.cl"

/* Each work-item draws one free flight toward a surface at t_surface and reports the weight it gives each lane,
 * split by the event: scattered before the surface, or reached it. */
KERNEL void free_flights(__global const float *spectra, __global const Medium *medium, float4 lambda,
                           float t_surface, int hero_only, uint seed, __global float4 *scattered_weight,
                           __global float4 *surface_weight)
{
    int item = get_global_id(0);
    SampledWavelengths w = fixed_wavelengths(lambda);
    Sampler sampler = sampler_start(seed, (uint)item, 0u);
    float u_lane = sample_1d(&sampler);
    float u_distance = sample_1d(&sampler);
    FreeFlight flight = medium_sample_flight(medium, spectra, &w, t_surface, hero_only, u_lane, u_distance);
    scattered_weight[item] = flight.scattered ? flight.weight : (float4)(0.0f);
    surface_weight[item] = flight.scattered ? (float4)(0.0f) : flight.weight;
}

/* Directions scattered from light travelling along +z, and the phase function's value for each. */
KERNEL void phase_samples(float g, uint seed, __global float4 *direction, __global float *phase)
{
    int item = get_global_id(0);
    Sampler sampler = sampler_start(seed, (uint)item, 0u);
    float3 travel = (float3)(0.0f, 0.0f, 1.0f);
    float3 d = sample_henyey_greenstein(travel, g, sample_2d(&sampler));
    direction[item] = (float4)(d, 0.0f);
    phase[item] = henyey_greenstein(dot(travel, d), g);
}
