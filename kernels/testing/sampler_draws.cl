/* Test harness: the numbers the sampler of this build draws (rng.cl; SAMPLER_SOBOL=1 selects the Sobol sampler).
 * Each work-item is one pixel; for each of its `sample_count` samples from index `sample_begin` it makes the draws
 * listed in `draw_dimensions` (1: sample_1d, 2: sample_2d) in order, as the integrators do, and writes each as a
 * float2 (a 1D draw's second component is 0). */
#include "kernel_entry.h"
#include "rng.cl"

KERNEL void draw_samples(uint seed, uint first_pixel, uint sample_begin, int sample_count,
                           __global const int *draw_dimensions, int draw_count, __global float2 *draws)
{
    int item = get_global_id(0);
    for (int s = 0; s < sample_count; ++s) {
        Sampler sampler = sampler_start(seed, first_pixel + (uint)item, sample_begin + (uint)s);
        for (int d = 0; d < draw_count; ++d) {
            float2 u = draw_dimensions[d] == 2 ? sample_2d(&sampler) : (float2)(sample_1d(&sampler), 0.0f);
            draws[((size_t)item * (size_t)sample_count + (size_t)s) * (size_t)draw_count + (size_t)d] = u;
        }
    }
}
