/* Test harness: the principled material's index from a specular level (bsdf_principled.cl), at arrays of levels,
 * to compare with the host's spectrace.materials.principled.eta_from_specular. */
#include "kernel_entry.h"
#include "../bsdf_principled.cl"

KERNEL void eta_from_specular(__global const float *specular, __global float *eta)
{
    int i = get_global_id(0);
    eta[i] = principled_eta_from_specular(specular[i]);
}
