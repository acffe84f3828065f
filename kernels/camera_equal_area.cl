/* The equal-area spherical camera (CAMERA_EQUALAREA; pbrt-v4's `spherical` camera with mapping "equalarea"):
 * the whole sphere of directions on a square film by Clarberg's equal-area octahedral mapping (equal_area.cl), so
 * every pixel of the film sees the same solid angle, 4π / pixel count. Film position (x right, y down, pixels) →
 * (u, v) = (x / width, y / height); the mapping's direction (dx, dy, dz) is dx·camera_right − dy·camera_up +
 * dz·camera_forward: the image's centre looks along camera_forward, its corners along −camera_forward, its right
 * along camera_right, its bottom down. Units: none (unit vectors); the film is meant square (a non-square one
 * stretches the map). */
#ifndef SPECTRACE_CAMERA_EQUAL_AREA_CL
#define SPECTRACE_CAMERA_EQUAL_AREA_CL

#include "equal_area.cl"

/* The world direction the camera sees at film position `film` (pixels). */
inline float3 equal_area_camera_direction(__global const RenderParams *p, float2 film)
{
    float3 d = equal_area_square_to_sphere((float2)(film.x / (float)p->width, film.y / (float)p->height));
    return normalize(d.x * p->camera_right.xyz - d.y * p->camera_up.xyz + d.z * p->camera_forward.xyz);
}

/* The film position (pixels) that sees along the unit world direction `direction`. */
inline float2 equal_area_camera_film(__global const RenderParams *p, float3 direction)
{
    float3 in_frame = (float3)(dot(direction, p->camera_right.xyz), -dot(direction, p->camera_up.xyz),
                            dot(direction, p->camera_forward.xyz));
    float2 square = equal_area_sphere_to_square(in_frame);
    return (float2)(square.x * (float)p->width, square.y * (float)p->height);
}

#endif
