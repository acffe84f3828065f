/* Pinhole perspective camera. The image plane spans [-1, 1] in both directions at unit distance along
 * camera_forward; camera_right and camera_up carry tan(fov/2) of their axis, so no trigonometry runs here.
 * camera_origin.w is the near clip distance (Mitsuba 3's near_clip): rays start on the plane that far along
 * camera_forward, so nothing nearer is seen (0: they start at the eye). */
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
    /* direction's part along camera_forward is 1, so this lands on the near plane. */
    ray.origin = p->camera_origin.xyz + p->camera_origin.w * direction;
    ray.direction = normalize(direction);
    return ray;
}

#endif
