/* The frame of a light at a point that shows an image about an axis: a spot's slide (light_spot.cl), a projector
 * (light_projector.cl), a goniometric light's map (light_goniometric.cl). z = Light.direction.xyz, the unit axis;
 * x at the angle Light.direction.w, radians, from the tangent of z's orthonormal basis (Duff et al. 2017, "Building
 * an Orthonormal Basis, Revisited", sampling.cl) toward its bitangent, the angle the host's lights/spot.py
 * slide_angle measures; y = z × x. Contract: Light.direction.xyz unit; x, y, z unit and right-handed. */
#ifndef SPECTRACE_LIGHT_SLIDE_FRAME_CL
#define SPECTRACE_LIGHT_SLIDE_FRAME_CL

#include "types.h"
#include "sampling.cl"

inline void light_slide_frame(__global const Light *light, float3 *x, float3 *y, float3 *z)
{
    float3 tangent, bitangent;
    *z = light->direction.xyz;
    orthonormal_basis(*z, &tangent, &bitangent);
    *x = cos(light->direction.w) * tangent + sin(light->direction.w) * bitangent;
    *y = cross(*z, *x);
}

#endif
