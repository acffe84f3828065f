/* The pinhole camera seen from the scene: where a point lands on the film and the camera's importance We there,
 * for integrators that reach the camera from the lights (light tracing, kernels/light_tracer.cl).
 *
 * camera.cl's rays pass through the image plane at unit distance along camera_forward, which spans
 * [-1, 1]·camera_right × [-1, 1]·camera_up, so its area is A = 4 |camera_right| |camera_up|. A pixel's value is the
 * mean radiance over the directions through its square with a uniform density on that plane (the box filter of
 * camera_ray's jitter). Normalised over the whole film, that is the importance We(ω) = 1 / (A cos⁴θ) for θ between
 * ω and camera_forward (Veach 1997, sec. 4.A, 8.1.2; pbrt-v4's PerspectiveCamera::We); a pixel's own importance is
 * pixel_count times it, and with pixel_count light paths per pixel sample that factor cancels (light_tracer.cl).
 *
 * Only the pinhole perspective camera is handled; the host refuses other cameras for light tracing. */
#ifndef SPECTRACE_CAMERA_IMPORTANCE_CL
#define SPECTRACE_CAMERA_IMPORTANCE_CL

#include "types.h"

typedef struct {
    int pixel;        /* row-major pixel index (row 0 at the top), or -1 when the point is not seen */
    float3 lens;      /* the point the camera sees it from: the eye, or the near plane's point on the way to it */
    float3 to_camera; /* unit direction from the point toward the eye */
    float distance;   /* from the point to the eye, scene units */
    float importance; /* We · cos θ / distance²: the film-normalised importance times the geometry term's camera
                         side, 1/(A cos³θ distance²) in 1/(sr · scene unit²) per unit image-plane area */
} CameraConnection;

/* Where x lands on the film of the pinhole camera in params, and with what importance (pixel -1: outside the
 * frustum, behind the eye or nearer than the near clip plane). */
inline CameraConnection connect_to_camera(__global const RenderParams *params, float3 x)
{
    CameraConnection c;
    c.pixel = -1;
    float3 eye = params->camera_origin.xyz;
    float3 forward = params->camera_forward.xyz;
    float3 right = params->camera_right.xyz;
    float3 up = params->camera_up.xyz;
    float3 d = x - eye;
    float depth = dot(d, forward);
    float near = params->camera_origin.w;
    if (!(depth > 0.0f) || depth <= near) return c;
    float tan_x2 = dot(right, right), tan_y2 = dot(up, up);
    float ndc_x = dot(d, right) / (tan_x2 * depth);
    float ndc_y = dot(d, up) / (tan_y2 * depth);
    float fx = 0.5f * (ndc_x + 1.0f) * (float)params->width;
    float fy = 0.5f * (1.0f - ndc_y) * (float)params->height;
    if (!(fx >= 0.0f && fx < (float)params->width && fy >= 0.0f && fy < (float)params->height)) return c;
    int px = min((int)fx, params->width - 1), py = min((int)fy, params->height - 1);
    float dist = length(d);
    float cos_theta = depth / dist;
    float area = 4.0f * sqrt(tan_x2 * tan_y2);
    c.pixel = py * params->width + px;
    c.to_camera = -d / dist;
    c.distance = dist;
    c.lens = eye + (near / depth) * d;
    c.importance = 1.0f / (area * cos_theta * cos_theta * cos_theta * dist * dist);
    return c;
}

#endif
