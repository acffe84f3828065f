/* Test harness: pick_light_reusing (lights.cl) on given 2D numbers: the light picked and the rescaled numbers. */
#include "kernel_entry.h"
#include "lights.cl"

KERNEL void pick_reusing(__global const float *light_cdf, int light_count, __global const float2 *u,
                           __global int *picked, __global float2 *rescaled, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    float2 v = u[i];
    picked[i] = pick_light_reusing(light_cdf, light_count, &v);
    rescaled[i] = v;
}
