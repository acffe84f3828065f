/* Cameras: a position on the film (in pixels, x to the right, y down, (0, 0) the top-left corner) becomes a ray.
 *
 * - CAMERA_PERSPECTIVE, a pinhole: the image plane spans [-1, 1] in both directions at unit distance along
 *   camera_forward; camera_right and camera_up carry tan(fov/2) of their axis, so no trigonometry runs here.
 * - CAMERA_THINLENS (Pharr, Jakob & Humphreys, 4th ed., 5.2.3): the pinhole's ray through the film position meets
 *   the plane of focus (lens.y along camera_forward) at a point every lens ray then aims at; the ray starts on a
 *   disk of radius lens.x (uniform in area) around camera_origin, in the plane spanned by camera_right and
 *   camera_up. Points on the plane of focus image sharply; the others blur into the circle of confusion.
 * - CAMERA_ORTHOGRAPHIC: parallel rays along camera_forward from the plane through camera_origin; camera_right and
 *   camera_up carry half the view's width and height in scene units.
 * - CAMERA_EQUIRECTANGULAR: latitude-longitude over the whole sphere, in the convention of the environment maps
 *   (kernels/light_environment_map.cl) with camera_up as the map's +y, camera_forward as its -z and camera_right as its +x:
 *   the image's centre looks along camera_forward, a column is a longitude (2π over the width), a row a latitude
 *   (π over the height, row 0 at the zenith). An environment rendered so, and put back as an envmap light with the
 *   same frame, is the environment again.
 * - CAMERA_EQUALAREA: the whole sphere on a square film by Clarberg's equal-area octahedral mapping, pbrt-v4's
 *   "equalarea" spherical camera (camera_equal_area.cl); near and far clip along the ray, as the equirectangular.
 * - CAMERA_REALISTIC: a thick lens system traced from the film (camera_realistic.cl), whose rays carry a weight:
 *   weighted_camera_ray makes them; camera_ray, which the light tracer calls, does not know it (the light tracer and
 *   BDPT refuse it). Its rays start at the front lens: near_clip is not applied.
 * camera_origin.w is the near clip distance (Mitsuba 3's near_clip): rays start where they cross the plane that far
 * along camera_forward (equirectangular: that far along the ray), so nothing nearer is seen (0: at the lens).
 * camera_forward.w is the far clip distance (Mitsuba 3's far_clip; 0: none), measured the same way: the camera's own
 * rays see nothing beyond that plane (a miss, which shows the environment), and light arriving from beyond it does
 * not reach the film (camera_importance.cl). Mitsuba 3's perspective, thin lens and orthographic sensors set the
 * ray's maxt to the distance to that plane along the view axis, as here. */
#ifndef SPECTRACE_CAMERA_CL
#define SPECTRACE_CAMERA_CL

#include "types.h"
#include "ray.cl"
#include "rng.cl"
#include "sampling.cl"
#include "camera_equal_area.cl"
#include "camera_realistic.cl"
#ifndef CAMERA_TYPE_COUNT
#error "built without the cameras' generated sources (spectrace.plugins.generated_sources)"
#endif

#define CAMERA_PI 3.14159265358979f

/* The pinhole's ray through the film position; its direction before normalising has unit part along
 * camera_forward. */
inline float3 pinhole_direction(__global const RenderParams *p, float2 film)
{
    float ndc_x = 2.0f * film.x / (float)p->width - 1.0f;
    float ndc_y = 1.0f - 2.0f * film.y / (float)p->height;
    return p->camera_forward.xyz + ndc_x * p->camera_right.xyz + ndc_y * p->camera_up.xyz;
}

/* film: the position in pixels. A thin lens draws its lens position from `sampler` (one 2D draw, after the film
 * position's); the other cameras draw nothing. */
inline Ray camera_ray(__global const RenderParams *p, float2 film, Sampler *sampler)
{
    Ray ray;
    if (CAMERA_IS(p, CAMERA_ORTHOGRAPHIC)) {
        float ndc_x = 2.0f * film.x / (float)p->width - 1.0f;
        float ndc_y = 1.0f - 2.0f * film.y / (float)p->height;
        ray.direction = p->camera_forward.xyz;
        ray.origin = p->camera_origin.xyz + ndc_x * p->camera_right.xyz + ndc_y * p->camera_up.xyz
                     + p->camera_origin.w * ray.direction;
        return ray;
    }
    if (CAMERA_IS(p, CAMERA_EQUIRECTANGULAR)) {
        float theta = CAMERA_PI * film.y / (float)p->height;
        float2 cs = cos_sin_turns(film.x / (float)p->width - 0.5f);  /* φ = 2π u − π: (cos φ, sin φ) */
        float sin_theta = sin(theta);
        ray.direction = normalize(sin_theta * cs.y * p->camera_right.xyz + cos(theta) * p->camera_up.xyz
                                  + sin_theta * cs.x * p->camera_forward.xyz);
        ray.origin = p->camera_origin.xyz + p->camera_origin.w * ray.direction;
        return ray;
    }
    if (CAMERA_IS(p, CAMERA_EQUALAREA)) {
        ray.direction = equal_area_camera_direction(p, film);
        ray.origin = p->camera_origin.xyz + p->camera_origin.w * ray.direction;
        return ray;
    }
    float3 direction = pinhole_direction(p, film);
    if (CAMERA_IS(p, CAMERA_THINLENS)) {
        float2 u = sample_2d(sampler);
        float2 disk = p->lens.x * sqrt(u.x) * cos_sin_turns(u.y);
        float3 lens = disk.x * normalize(p->camera_right.xyz) + disk.y * normalize(p->camera_up.xyz);
        /* The pinhole ray reaches the plane of focus at lens.y · direction (its forward part is 1). */
        float3 towards = p->lens.y * direction - lens;
        float forward = dot(towards, p->camera_forward.xyz);
        ray.origin = p->camera_origin.xyz + lens + (p->camera_origin.w / forward) * towards;
        ray.direction = normalize(towards);
        return ray;
    }
    /* direction's part along camera_forward is 1, so this lands on the near plane. */
    ray.origin = p->camera_origin.xyz + p->camera_origin.w * direction;
    ray.direction = normalize(direction);
    return ray;
}

/* A pixel sample's camera ray: camera_ray's, or a lens system's, which multiplies `weight` by its own. */
inline Ray weighted_camera_ray(__global const RenderParams *p, float2 film, Sampler *sampler, float *weight)
{
    if (CAMERA_IS(p, CAMERA_REALISTIC)) return realistic_camera_ray(p, film, sampler, weight);
    return camera_ray(p, film, sampler);
}

/* How far along `ray`, a ray camera_ray made, from its start, the camera sees: to the far clip plane (INFINITY
 * without one). */
inline float camera_ray_reach(__global const RenderParams *p, Ray ray)
{
#if SCENE_HAS_FAR_CLIP
    float far = p->camera_forward.w;
    if (!(far > 0.0f)) return INFINITY;
    float near = p->camera_origin.w;
    if (CAMERA_IS(p, CAMERA_EQUIRECTANGULAR) || CAMERA_IS(p, CAMERA_EQUALAREA)) return far - near;
    /* Every other camera's rays start on the near plane. */
    return (far - near) / dot(ray.direction, p->camera_forward.xyz);
#else
    return INFINITY;
#endif
}

/* The rays through the film positions one pixel to the right of and one below the one that sees the point p, as
 * origins o_x, o_y and directions d_x, d_y (not normalised), for ray differentials (kernels/scene.cl's footprint);
 * 0 where p is not in view (behind a perspective or orthographic camera, on an equirectangular camera's axis). A
 * thin lens is taken as its pinhole (as pbrt-v4's Camera::Approximate_dp_dxy takes every camera's central ray). */
inline int camera_neighbour_rays(__global const RenderParams *p, float3 point, float3 *o_x, float3 *d_x,
                                 float3 *o_y, float3 *d_y)
{
    float3 origin = p->camera_origin.xyz;
    float3 to_p = point - origin;
    float3 forward = p->camera_forward.xyz;
    if (CAMERA_IS(p, CAMERA_EQUIRECTANGULAR)) {
        float distance = length(to_p);
        if (!(distance > 0.0f)) return 0;
        float3 d = to_p / distance;
        float lx = dot(d, p->camera_right.xyz), ly = dot(d, p->camera_up.xyz), lz = dot(d, forward);
        float sin_theta = sqrt(lx * lx + lz * lz);
        if (!(sin_theta > 0.0f)) return 0;
        /* ∂d/∂φ = (lz right − lx forward); ∂d/∂θ, a unit vector: (ly lx / sin θ, −sin θ, ly lz / sin θ) in the
         * camera's (right, up, forward). */
        float3 d_phi = lz * p->camera_right.xyz - lx * forward;
        float3 d_theta = (ly / sin_theta) * (lx * p->camera_right.xyz + lz * forward) - sin_theta * p->camera_up.xyz;
        *o_x = origin;
        *o_y = origin;
        *d_x = d + d_phi * (2.0f * CAMERA_PI / (float)p->width);
        *d_y = d + d_theta * (CAMERA_PI / (float)p->height);
        return 1;
    }
    if (CAMERA_IS(p, CAMERA_EQUALAREA)) {
        float distance = length(to_p);
        if (!(distance > 0.0f)) return 0;
        /* The rays one pixel over (back where that would leave the film: the map folds at its edges). */
        float2 film = equal_area_camera_film(p, to_p / distance);
        float step_x = film.x + 1.0f <= (float)p->width ? 1.0f : -1.0f;
        float step_y = film.y + 1.0f <= (float)p->height ? 1.0f : -1.0f;
        *o_x = origin;
        *o_y = origin;
        *d_x = equal_area_camera_direction(p, film + (float2)(step_x, 0.0f));
        *d_y = equal_area_camera_direction(p, film + (float2)(0.0f, step_y));
        return 1;
    }
    float depth = dot(to_p, forward);
    if (!(depth > 0.0f)) return 0;
    if (CAMERA_IS(p, CAMERA_ORTHOGRAPHIC)) {
        *o_x = point + p->camera_right.xyz * (2.0f / (float)p->width);
        *o_y = point + p->camera_up.xyz * (2.0f / (float)p->height);
        *d_x = forward;
        *d_y = forward;
        return 1;
    }
    float3 d = to_p / depth;  /* the camera ray's direction with unit forward part, as camera_ray forms it */
    *o_x = origin;
    *o_y = origin;
    *d_x = d + p->camera_right.xyz * (2.0f / (float)p->width);
    *d_y = d + p->camera_up.xyz * (2.0f / (float)p->height);
    return 1;
}

#endif
