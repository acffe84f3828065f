/* Render-pass program of the `bdpt` integrator (bidirectional path tracing, kernels/bdpt.cl).
 *
 * One launch runs one pixel sample: work-item k is a pixel sample of pixel k (or of the pixel listed in `items` when
 * the host launches some again for their later records). Its light-to-camera connections land in any pixel, so,
 * as for the `light` integrator (integrator_light.cl), everything it finds is written as splat records in its own
 * `capacity` slots: those connections in the order it makes them, then its own pixel's estimate. The host adds them
 * to the film in the order (sample index, work-item, record) (spectrace.engine.light_tracer). The arguments are the
 * light tracer's, so the same host code drives both; scene_sphere and hide_environment are unused (the host refuses
 * distant and environment lights for this integrator). */
#include "kernel_entry.h"
#include "pixel_sample.cl"
#include "bdpt.cl"

KERNEL void bdpt_pass(SCENE_KERNEL_PARAMS, __global const float4 *cmf, float4 scene_sphere, int hide_environment,
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
    /* The light pass's arguments: BDPT writes no bands and no film positions (it refuses both). */
    SplatRecords records = {splat_xyz + slot * capacity, splat_pixel + slot * capacity, record_begin, capacity, 0,
                            splat_band_value + slot * capacity, splat_band + slot * capacity,
                            splat_film + slot * capacity};
    uint rays_traced = 0;
    trace_bdpt(&scene, item, sample_index, cmf, &records, &rays_traced);
    splat_counts[slot] = records.count;
    if (record_begin == 0) ray_counts[item] += rays_traced;
}
