/* Render-pass program of the `light` integrator (light tracing, kernels/light_tracer.cl).
 *
 * One launch runs one pixel sample's light paths: as many as the film has pixels, work-item k tracing path k (the
 * sampler keyed by k as a pixel), or the work-items listed in `items` when the host launches some paths again for
 * their later splat records. Each writes its splat records to its own `capacity` slots and the number it made to
 * counts; the host adds them to the film (spectrace.engine.light_tracer). With SPECTRAL_FILM each record also
 * carries its four lanes' band values and bands (splat_band_value, splat_band), and with a pixel filter other than
 * the box its film position (splat_film); one-element placeholders when not recorded.
 * hide_environment comes from the host as an argument of its own, so this kernel reads no RenderParams field for it. */
#include "kernel_entry.h"
#include "light_tracer.cl"

KERNEL void light_pass(SCENE_KERNEL_PARAMS, SPLAT_PASS_PARAMS)
{
    int slot = get_global_id(0);
    if (slot >= item_count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    int item = items[slot];
    SplatRecords records = slot_splat_records(slot, record_begin, capacity, splat_xyz, splat_pixel, splat_band_value,
                                              splat_band, splat_film);
    uint rays_traced = 0;
    trace_light_path(&scene, item, sample_index, scene_sphere, hide_environment, cmf, &records, &rays_traced);
    splat_counts[slot] = records.count;
    if (record_begin == 0) ray_counts[item] += rays_traced;
}
