/* The camera seen from the scene: where a point lands on the film and the camera's importance We there, for
 * integrators that reach the camera from the lights (light tracing, kernels/light_tracer.cl).
 *
 * camera.cl's rays pass through the image plane at unit distance along camera_forward, which spans
 * [-1, 1]·camera_right × [-1, 1]·camera_up, so its area is A = 4 |camera_right| |camera_up|. A pixel's value is the
 * mean radiance over the directions through its square with a uniform density on that plane (the box filter of
 * camera_ray's jitter). Normalised over the whole film, that is the importance We(ω) = 1 / (A cos⁴θ) for θ between
 * ω and camera_forward (Veach 1997, sec. 4.A, 8.1.2; pbrt-v4's PerspectiveCamera::We); a pixel's own importance is
 * pixel_count times it, and with pixel_count light paths per pixel sample that factor cancels (light_tracer.cl).
 *
 * - The pinhole (perspective): the point is seen from the eye; the connection's estimate is We · cos θ / d².
 * - The thin lens (pbrt-v4's PerspectiveCamera::SampleWi with a lens): a lens point drawn uniformly on the aperture
 *   disk of area A_lens (camera_ray's draw), We = 1 / (A · A_lens · cos⁴θ) for the ray from it, whose film
 *   position is where the eye sees that ray's point on the plane of focus; divided by the lens point's density
 *   1 / A_lens the estimate is again 1 / (A cos³θ d²), θ and d now from the lens point.
 * - The orthographic camera: its rays all run along camera_forward, from the view rectangle of area
 *   A = 4 |camera_right| |camera_up| (scene units²) through the camera's plane, so a point is seen along exactly one
 *   ray, from its projection on that plane; the direction is a delta, and the estimate is 1 / A (per unit area of
 *   the point's surface projected on the plane, the surface's cosine toward the camera being the caller's).
 * - The equirectangular camera (camera.cl): film position (u, v) in [0, 1]² looks along θ = π v from camera_up and
 *   φ = 2π u − π around it from camera_forward, a uniform density on the film, so over directions
 *   p(ω) = 1 / (2π² sin θ) (dω = sin θ dθ dφ = 2π² sin θ du dv): that is We, with no film plane to add a cosine,
 *   and the estimate is 1 / (2π² sin θ d²). Points on the axis (sin θ = 0) are not seen. The host takes it with the
 *   box filter only: a wider filter would have to wrap around the seam and the poles, as a camera path's does.

 * - The equal-area camera (camera_equal_area.cl): uniform film positions give directions uniform over the sphere,
 *   p(ω) = 1 / (4π): the estimate is 1 / (4π d²); the host takes it with the box filter only, as the
 *   equirectangular.
 *
 * With a pixel filter wider than the box, a point up to (radius − ½) pixels beyond the film's edge still adds to the
 * edge pixels (as a camera path's filter-sampled position may fall there): such points are seen too. */
#ifndef SPECTRACE_CAMERA_IMPORTANCE_CL
#define SPECTRACE_CAMERA_IMPORTANCE_CL

#include "types.h"
#include "camera.cl"
#include "sampling.cl"

typedef struct {
    int pixel;        /* row-major pixel index (row 0 at the top), or -1 when the point is not seen; for a
                         point in the filter's margin outside the film, the nearest pixel */
    float2 film;      /* where it lands on the film, pixels (x right, y down from the top-left corner) */
    float3 lens;      /* the point the camera sees it from: the eye, or the near plane's point on the way to it */
    float3 to_camera; /* unit direction from the point toward the eye */
    float distance;   /* from the point to the eye, scene units */
    float importance; /* We · cos θ / distance²: the film-normalised importance times the geometry term's camera
                         side, 1/(A cos³θ distance²) in 1/(sr · scene unit²) per unit image-plane area */
} CameraConnection;

/* Fills c's film position and pixel for the film position (fx, fy); 0 when it lies outside the film and the
 * filter's margin. */
inline int land_on_film(__global const RenderParams *params, float fx, float fy, CameraConnection *c)
{
    float margin = PIXEL_FILTER_IS(params, PIXEL_FILTER_BOX) ? 0.0f : params->filter_shape.x - 0.5f;
    float w = (float)params->width, h = (float)params->height;
    if (!(fx >= -margin && fx < w + margin && fy >= -margin && fy < h + margin)) return 0;
    c->film = (float2)(fx, fy);
    int px = max(min((int)fx, params->width - 1), 0), py = max(min((int)fy, params->height - 1), 0);
    c->pixel = py * params->width + px;
    return 1;
}

/* Where x lands on the film of the camera in params, and with what importance (pixel -1: outside the view, behind
 * the camera, nearer than the near clip plane or beyond the far one). u_lens: a uniform 2D sample for the thin lens's lens point (unused
 * by the other cameras); (0, 0) is the lens's centre. */
inline CameraConnection connect_to_camera_sampled(__global const RenderParams *params, float3 x, float2 u_lens)
{
    CameraConnection c;
    c.pixel = -1;
    float3 eye = params->camera_origin.xyz;
    float3 forward = params->camera_forward.xyz;
    float3 right = params->camera_right.xyz;
    float3 up = params->camera_up.xyz;
    float near = params->camera_origin.w;
#if SCENE_HAS_FAR_CLIP
    float far = params->camera_forward.w > 0.0f ? params->camera_forward.w : INFINITY;
#else
    float far = INFINITY;
#endif
    float tan_x2 = dot(right, right), tan_y2 = dot(up, up);
    float area = 4.0f * sqrt(tan_x2 * tan_y2);
    if (CAMERA_IS(params, CAMERA_ORTHOGRAPHIC)) {
        float3 d = x - eye;
        float depth = dot(d, forward);
        if (!(depth > near) || depth > far) return c;
        float ndc_x = dot(d, right) / tan_x2, ndc_y = dot(d, up) / tan_y2;
        float fx = 0.5f * (ndc_x + 1.0f) * (float)params->width;
        float fy = 0.5f * (1.0f - ndc_y) * (float)params->height;
        if (!land_on_film(params, fx, fy, &c)) return c;
        c.to_camera = -forward;
        c.distance = depth - near;
        c.lens = x - c.distance * forward;
        c.importance = 1.0f / area;
        return c;
    }
    if (CAMERA_IS(params, CAMERA_EQUIRECTANGULAR)) {
        float3 d = x - eye;
        float dist = length(d);
        if (!(dist > near)) return c;
        float3 dir = d / dist;
        float cos_theta = clamp(dot(dir, normalize(up)), -1.0f, 1.0f);
        float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
        if (!(sin_theta > 0.0f)) return c;
        float phi = atan2(dot(dir, normalize(right)), dot(dir, normalize(forward)));
        float fx = (0.5f + phi / (2.0f * CAMERA_PI)) * (float)params->width;
        float fy = acos(cos_theta) / CAMERA_PI * (float)params->height;
        if (!land_on_film(params, fx, fy, &c)) return c;
        c.to_camera = -dir;
        c.distance = dist;
        c.lens = eye + near * dir;
        c.importance = 1.0f / (2.0f * CAMERA_PI * CAMERA_PI * sin_theta * dist * dist);
        return c;
    }
    if (CAMERA_IS(params, CAMERA_EQUALAREA)) {
        float3 d = x - eye;
        float dist = length(d);
        if (!(dist > near) || dist > far) return c;
        float3 dir = d / dist;
        float2 film = equal_area_camera_film(params, dir);
        if (!land_on_film(params, film.x, film.y, &c)) return c;
        c.to_camera = -dir;
        c.distance = dist;
        c.lens = eye + near * dir;
        c.importance = 1.0f / (4.0f * CAMERA_PI * dist * dist);
        return c;
    }
    float3 lens_point = eye;
    if (CAMERA_IS(params, CAMERA_THINLENS)) {
        float2 disk = params->lens.x * sqrt(u_lens.x) * cos_sin_turns(u_lens.y);
        lens_point = eye + disk.x * normalize(right) + disk.y * normalize(up);
    }
    float3 d = x - lens_point;
    float depth = dot(d, forward);
    if (!(depth > 0.0f) || depth <= near || depth > far) return c;
    /* The eye sees the film position of the ray lens_point → x where that ray meets the plane of focus (for the
     * pinhole, lens_point is the eye and that is x's own direction). */
    float3 seen = CAMERA_IS(params, CAMERA_THINLENS) ? lens_point + (params->lens.y / depth) * d - eye : d;
    float seen_depth = dot(seen, forward);
    float ndc_x = dot(seen, right) / (tan_x2 * seen_depth);
    float ndc_y = dot(seen, up) / (tan_y2 * seen_depth);
    float fx = 0.5f * (ndc_x + 1.0f) * (float)params->width;
    float fy = 0.5f * (1.0f - ndc_y) * (float)params->height;
    if (!land_on_film(params, fx, fy, &c)) return c;
    float dist = length(d);
    float cos_theta = depth / dist;
    c.to_camera = -d / dist;
    c.distance = dist;
    c.lens = lens_point + (near / depth) * d;
    c.importance = 1.0f / (area * cos_theta * cos_theta * cos_theta * dist * dist);
    return c;
}

/* The connection through the lens's centre: exact for the pinhole and orthographic cameras. */
inline CameraConnection connect_to_camera(__global const RenderParams *params, float3 x)
{
    return connect_to_camera_sampled(params, x, (float2)(0.0f));
}

#endif
