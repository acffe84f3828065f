/* Test harness for kernels/medium_grid.cl: free flights and ratio-tracked transmittance through one grid medium at
 * four given wavelengths, along a given ray. */
#include "kernel_entry.h"
#include "rng.cl"
#include "medium.cl"

/* Each work-item draws one free flight toward a surface at t_surface and reports the weight it gives each lane,
 * split by the event (scattered before the surface, or reached it), and where it scattered (-1: it did not). */
KERNEL void grid_flights(__global const float *spectra, __global const Medium *medium, float4 lambda, float4 origin,
                         float4 direction, float t_surface, int hero_only, uint seed,
                         __global float4 *scattered_weight, __global float4 *surface_weight,
                         __global float *distance)
{
    int item = get_global_id(0);
    SampledWavelengths w = fixed_wavelengths(lambda);
    Sampler sampler = sampler_start(seed, (uint)item, 0u);
    float u_lane = sample_1d(&sampler);
    float u_distance = sample_1d(&sampler);
    FreeFlight flight = grid_sample_flight(medium, spectra, &w, origin.xyz, direction.xyz, t_surface, hero_only,
                                           (float4)(1.0f), u_lane, u_distance);
    scattered_weight[item] = flight.scattered ? flight.weight : (float4)(0.0f);
    surface_weight[item] = flight.scattered ? (float4)(0.0f) : flight.weight;
    distance[item] = flight.scattered ? flight.distance : -1.0f;
}

/* Each work-item's ratio-tracking estimate of the transmittance of origin + t·direction, t in [0, length]. */
KERNEL void grid_transmittances(__global const float *spectra, __global const Medium *medium, float4 lambda,
                                float4 origin, float4 direction, float length, uint seed,
                                __global float4 *transmittance)
{
    int item = get_global_id(0);
    SampledWavelengths w = fixed_wavelengths(lambda);
    transmittance[item] = grid_transmittance(medium, spectra, &w, origin.xyz, direction.xyz, length,
                                             hash_u32(seed ^ hash_u32((uint)item)));
}
