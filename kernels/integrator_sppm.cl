/* Render-pass programs of the `sppm` integrator (stochastic progressive photon mapping, kernels/sppm.cl).
 *
 * An iteration (one pixel sample) is two launches with the host between them (spectrace.engine.sppm):
 * sppm_photon_pass traces photon paths (work-item k: photons k, k + pixels, ... of the iteration) and writes each one's records to its
 * own `capacity` slots (with each one's hash bucket) and their number to photon_counts; the host sorts the slots by
 * bucket; then
 * sppm_gather_pass (work-item k: pixel k) traces the pixel's camera path to its visible point, gathers the photons
 * around it, updates the pixel's statistics and writes its film sums. */
#include "kernel_entry.h"
#include "sppm.cl"

KERNEL void sppm_photon_pass(SCENE_KERNEL_PARAMS, float4 scene_sphere, int sample_index, int photon_count,
                             int wavelength_stream, int capacity, __global float4 *photon_position,
                             __global float4 *photon_direction, __global float4 *photon_normal,
                             __global float4 *photon_flux, __global uint *photon_bucket, __global int *photon_counts,
                             float4 grid_origin, float cell_size, uint table_size, __global uint *ray_counts)
{
    int pixels = params->width * params->height;
    int first = get_global_id(0);
    if (first >= pixels) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = sppm_wavelengths(params, wavelength_stream, sample_index);
    uint rays_traced = 0;
    /* Work-item k traces photons k, k + pixels, ...: its rays are counted in pixel k's slot alone. */
    for (int item = first; item < photon_count; item += pixels) {
        int slots = item * capacity;
        for (int k = 0; k < capacity; ++k) photon_bucket[slots + k] = table_size;
        PhotonRecords records = {photon_position + slots, photon_direction + slots, photon_normal + slots,
                                 photon_flux + slots, photon_bucket + slots, capacity, 0, grid_origin.xyz, cell_size,
                                 table_size};
        /* Photon k's sampler is keyed past the film's pixels and the wavelengths' stream. */
        trace_photon(&scene, wavelength_stream + 1 + item, sample_index, &w, scene_sphere, &records, &rays_traced);
        photon_counts[item] = records.count;
    }
    ray_counts[first] += rays_traced;
}

KERNEL void sppm_gather_pass(SCENE_KERNEL_PARAMS, __global const float4 *cmf, int sample_index,
                             int wavelength_stream, float radius_per_metre, float photons_per_iteration,
                             __global const float4 *photon_position, __global const float4 *photon_direction,
                             __global const float4 *photon_normal, __global const float4 *photon_flux,
                             __global const int *photon_order, __global const int *cell_start, uint table_size,
                             float4 grid_origin, float cell_size,
                             __global float4 *direct, __global float4 *tau, __global float *radius,
                             __global float *photons, __global float4 *film, __global uint *ray_counts)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = sppm_wavelengths(params, wavelength_stream, sample_index);
    PhotonGrid grid = {photon_position, photon_direction, photon_normal, photon_flux, photon_order, cell_start,
                       table_size, grid_origin.xyz, cell_size};
    PixelStatistics stats = {direct, tau, radius, photons};
    uint rays_traced = 0;
    sppm_gather(&scene, &grid, cmf, pixel, sample_index, &w, radius_per_metre, photons_per_iteration, &stats, film,
                &rays_traced);
    ray_counts[pixel] += rays_traced;
}
