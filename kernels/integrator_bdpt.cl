/* Render-pass program of the `bdpt` integrator (bidirectional path tracing, kernels/bdpt.cl).
 *
 * One launch runs one pixel sample: work-item k is a pixel sample of the bdpt_pixels_per_light_path pixels from
 * k × that, which share a light subpath (or of the group listed in `items` when the host launches some again for their later records). Its
 * light-to-camera connections land in any pixel, so, as for the `light` integrator (integrator_light.cl), they are
 * written as splat records in its own `capacity` slots, in the order it makes them; its pixels' own estimates go
 * to their rows of own_xyz. The host adds, for each sample, every pixel's own estimate and then the records in the
 * order (work-item, record) to the film (spectrace.engine.light_tracer). The arguments are the light tracer's, so
 * the same host code drives both. */
#include "kernel_entry.h"
#include "pixel_sample.cl"
#include "bdpt.cl"

KERNEL void bdpt_pass(SCENE_KERNEL_PARAMS, SPLAT_PASS_PARAMS)
{
    int slot = get_global_id(0);
    if (slot >= item_count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    int item = items[slot];
    SplatRecords records = slot_splat_records(slot, record_begin, capacity, splat_xyz, splat_pixel, splat_band_value,
                                              splat_band, splat_film);
    uint rays_traced = 0;
    trace_bdpt(&scene, item, sample_index, scene_sphere, hide_environment, cmf, &records, own_xyz, &rays_traced);
    splat_counts[slot] = records.count;
    /* The group's rays, counted in its first pixel. */
    if (record_begin == 0) ray_counts[bdpt_pixels_per_light_path(scene.params) * item] += rays_traced;
}
