/* Render-pass program of the `light` integrator (light tracing, kernels/light_tracer.cl).
 *
 * One launch runs one pixel sample's light paths: as many as the film has pixels, work-item k tracing path k (the
 * sampler keyed by k as a pixel), or the work-items listed in `items` when the host launches some paths again for
 * their later splat records. Each writes its splat records to its own `capacity` slots and the number it made to
 * counts; the host adds them to the film (spectrace.engine.light_tracer). With SPECTRAL_BINS each record also
 * carries its four lanes' band values and bands (splat_band_value, splat_band), and with a pixel filter other than
 * the box its film position (splat_film); one-element placeholders when not recorded.
 * hide_environment comes from the host as an argument of its own, so this kernel reads no RenderParams field for it. */
#include "kernel_entry.h"
#include "light_tracer.cl"

KERNEL void light_pass(SCENE_KERNEL_PARAMS, __global const float4 *cmf, float4 scene_sphere, int hide_environment,
                       int sample_index,
                       __global const int *items, int item_count, int record_begin, int capacity,
                       __global float4 *splat_xyz, __global int *splat_pixel, __global int *splat_counts,
                       __global float4 *splat_band_value, __global int4 *splat_band, __global float2 *splat_film,
                       __global uint *ray_counts)
{
    int slot = get_global_id(0);
    if (slot >= item_count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    int item = items[slot];
    for (int k = 0; k < capacity; ++k) splat_pixel[slot * capacity + k] = -1;
    SplatRecords records = {splat_xyz + slot * capacity, splat_pixel + slot * capacity, record_begin, capacity, 0,
                            splat_band_value + slot * capacity, splat_band + slot * capacity,
                            splat_film + slot * capacity};
    uint rays_traced = 0;
    trace_light_path(&scene, item, sample_index, scene_sphere, hide_environment, cmf, &records, &rays_traced);
    splat_counts[slot] = records.count;
    if (record_begin == 0) ray_counts[item] += rays_traced;
}
