/* Pinhole perspective camera. The image plane spans [-1, 1] in both directions at unit distance along
 * camera_forward; camera_right and camera_up carry tan(fov/2) of their axis, so no trigonometry runs here. */
#ifndef SPECTRACE_CAMERA_CL
#define SPECTRACE_CAMERA_CL

#include "types.h"
#include "ray.cl"

/* pixel_x, pixel_y: integer pixel, row 0 at the top; jitter in [0,1)². */
inline Ray camera_ray(__global const RenderParams *p, int pixel_x, int pixel_y, float2 jitter)
{
    float ndc_x = 2.0f * ((float)pixel_x + jitter.x) / (float)p->width - 1.0f;
    float ndc_y = 1.0f - 2.0f * ((float)pixel_y + jitter.y) / (float)p->height;
    float3 direction = p->camera_forward.xyz + ndc_x * p->camera_right.xyz + ndc_y * p->camera_up.xyz;
    Ray ray;
    ray.origin = p->camera_origin.xyz;
    ray.direction = normalize(direction);
    return ray;
}

#endif
