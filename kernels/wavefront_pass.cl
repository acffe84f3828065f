/* The render pass as a wavefront (Laine et al. 2013, "Megakernels considered harmful"): the path states live in a
 * global buffer, one slot per pixel, and each launch of wavefront_advance takes every live path one segment
 * further (path_segment, the function the megakernel loops over). The launch runs only the live slots: each
 * appends its slot to the next launch's queue with an atomic counter, so finished paths leave no idle lanes. A
 * slot whose path ends adds it to the film and starts its pixel's next sample of the pass in the same launch.
 *
 * A slot belongs to one pixel and runs its samples in sample-index order, so each pixel's film sum sees the same
 * additions in the same order as in the megakernel, whatever order the queue holds the slots in: the image is
 * deterministic and does not depend on how a render is split into passes. The includer includes
 * path_tracer.cl first.
 *
 * AOVs (FILM_AOVS, kernels/aov.cl): the slot's path state carries the AOV record as the megakernel's does, and a
 * finished sample adds it to the pixel's AOV sums in aov_film, read and written back around each addition: the
 * same additions in the same order as the megakernel's sums held in registers over a pass. */
#include "kernel_entry.h"
#include "aov.cl"
#include "pixel_sample.cl"

/* Everything a pixel's path carries between launches. */
typedef struct {
    PathState path;
    SampledWavelengths w;
    float4 radiance;      /* gathered so far by the current sample */
    float weight;         /* the pixel filter's weight of the current sample (pixel_sample.cl) */
    Sampler sampler;
    int sample;           /* the sample index being traced */
    uint rays_traced;     /* by this pixel in this pass, added to ray_counts when its samples are done */
} PathSlot;

/* Bytes of one slot, for the host to size the slot buffer (the struct is private to the device code). */
KERNEL void wavefront_slot_size(__global uint *size)
{
    *size = (uint)sizeof(PathSlot);
}

/* Adds the slot's finished sample to the pixel's film (and AOV sums). */
inline void add_slot_sample(const PathSlot *slot, int pixel, __global float4 *film, __global float *spectral_film,
                            __global float *response_film, __global float4 *aov_film, __global const float4 *cmf,
                            __global const RenderParams *params)
{
    float4 radiance = slot->weight * slot->radiance;
#if FILM_AOVS
    float4 sums[AOV_FLOAT4S_PER_PIXEL];
    for (int i = 0; i < AOV_FLOAT4S_PER_PIXEL; ++i) sums[i] = aov_film[pixel * AOV_FLOAT4S_PER_PIXEL + i];
#if FILM_STOKES
    add_stokes_sample(sums, &slot->path.pol, radiance, slot->weight, cmf, &slot->w);
#endif
#endif
    IF_POLARIZED(radiance = polarized_film_radiance(&slot->path.pol, params, radiance, slot->weight));
#if FILM_AOVS
    add_aov_sample(sums, &slot->path.aov, radiance, slot->weight, cmf, &slot->w);
    for (int i = 0; i < AOV_FLOAT4S_PER_PIXEL; ++i) aov_film[pixel * AOV_FLOAT4S_PER_PIXEL + i] = sums[i];
#endif
    float4 accumulated = film[pixel];
    add_pixel_sample(&accumulated, spectral_film, response_film, pixel, radiance, cmf, &slot->w, params);
    film[pixel] = accumulated;
}

/* Starts the pixel's samples from `sample_index` on, adding to the film those that end before tracing anything
 * (none unless max_depth < 1); returns 0 when the pass's samples of the pixel are all done. */
inline int start_slot_sample(__global const RenderParams *params, PathSlot *slot, int pixel, int sample_index,
                             __global float4 *film, __global float *spectral_film, __global float *response_film,
                             __global float4 *aov_film, __global const float4 *cmf)
{
    for (; sample_index < params->sample_begin + params->sample_count; ++sample_index) {
        Ray ray = start_pixel_sample(params, cmf, pixel, sample_index, &slot->sampler, &slot->w, &slot->weight);
        slot->path = camera_path(ray);
        IF_POLARIZED(polarized_camera(&slot->path.pol, params, ray.direction));
        slot->radiance = (float4)(0.0f);
        slot->sample = sample_index;
        if (slot->path.segments <= max_segments(params)) return 1;
        add_slot_sample(slot, pixel, film, spectral_film, response_film, aov_film, cmf, params);
    }
    return 0;
}

/* queue, queue_length: the pixels with a live path, appended in no particular order. aov_film: the AOV sums
 * (untouched without FILM_AOVS). */
KERNEL void wavefront_start(__global const RenderParams *params, __global const float4 *cmf,
                              __global float4 *film, __global float *spectral_film, __global float *response_film,
                              __global float4 *aov_film, __global PathSlot *slots, __global int *queue,
                              __global int *queue_length)
{
    int pixel = get_global_id(0);
    if (pixel >= params->width * params->height) return;
    PathSlot slot;
    slot.rays_traced = 0;
    if (start_slot_sample(params, &slot, pixel, params->sample_begin, film, spectral_film, response_film, aov_film,
                          cmf)) {
        slots[pixel] = slot;
        queue[atomic_inc(queue_length)] = pixel;
    }
}

/* One segment of every path in `queue` (its first *queue_length entries); the paths still live after it go to
 * next_queue. */
KERNEL void wavefront_advance(SCENE_KERNEL_PARAMS, __global const float4 *cmf, __global float4 *film,
                                __global uint *ray_counts, __global float *spectral_film,
                                __global float *response_film, __global float4 *aov_film, __global PathSlot *slots,
                                __global const int *queue, __global const int *queue_length,
                                __global int *next_queue, __global int *next_queue_length)
{
    int item = get_global_id(0);
    if (item >= *queue_length) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
#if FILM_AOVS
    scene.film_cmf = cmf;
#endif
    int pixel = queue[item];
    PathSlot slot = slots[pixel];
    int live = path_segment(&scene, &slot.w, &slot.sampler, &slot.path, &slot.radiance, &slot.rays_traced);
    if (!live) {
        add_slot_sample(&slot, pixel, film, spectral_film, response_film, aov_film, cmf, params);
        live = start_slot_sample(params, &slot, pixel, slot.sample + 1, film, spectral_film, response_film, aov_film,
                                 cmf);
    }
    if (live) {
        slots[pixel] = slot;
        next_queue[atomic_inc(next_queue_length)] = pixel;
    } else {
        ray_counts[pixel] += slot.rays_traced;
    }
}
