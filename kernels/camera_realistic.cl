/* CAMERA_REALISTIC: rays from the film through a thick lens system of spherical surfaces and an aperture stop
 * (pbrt-v4's RealisticCamera; Pharr, Jakob & Humphreys, 4th ed., 5.3; Kolb, Mitchell & Hanrahan 1995).
 *
 * Units: scene units (metres); the host (spectrace.cameras.realistic) focuses the lens and fills
 * RenderParams.lens_elements. Lens space: the film at z = 0 centred on the axis, the scene toward +z; x along
 * camera_right, y along camera_up, z along camera_forward, the origin at camera_origin.
 * Rows: [0] = (half film width, half film height, surface count n, rear surface's aperture radius), then
 * [1..n] the surfaces from the film side: (radius of curvature, 0 for the stop; vertex distance from the film;
 * n_scene side / n_film side; aperture radius). A radius > 0 has its centre of curvature on the film side.
 *
 * lens_pupils[i]: the bounds (x0, y0, x1, y1) on the rear vertex's plane of what a film point at radius r in ring
 * i = ⌊r / (half diagonal) · LENS_PUPIL_BINS⌋ sees through the lens, for a point on the +x axis (turned to the
 * film point's azimuth here; all zero: nothing).
 *
 * Contract: `weight` is multiplied by the ray's weight cos⁴θ · A / z² (θ: the film-to-pupil segment's angle to
 * the axis; A: the bounds' area, which the draw covers uniformly; z: the rear vertex's distance), or set to 0
 * where the lens stops the ray (outside an aperture, a missed surface, total internal reflection); a stopped ray is
 * still a ray (from the film along the axis), so the caller traces it and adds nothing. Draws one 2D sample. */
#ifndef SPECTRACE_CAMERA_REALISTIC_CL
#define SPECTRACE_CAMERA_REALISTIC_CL

#include "types.h"
#include "ray.cl"
#include "rng.cl"
#include "sampling.cl"

/* The ray (o, d), d unit and toward +z, through surface `s`: 0 where it is stopped, else o on the surface and d
 * refracted into the scene-side medium. */
inline int realistic_surface(float4 s, float3 *o, float3 *d)
{
    float radius = s.x;
    float t;
    float3 normal = (float3)(0.0f, 0.0f, 1.0f);
    if (radius == 0.0f) {
        t = (s.y - (*o).z) / (*d).z;
        if (!(t >= 0.0f)) return 0;
    } else {
        float3 centre = (float3)(0.0f, 0.0f, s.y - radius);
        float3 oc = *o - centre;
        float b = dot(oc, *d);
        float c = dot(oc, oc) - radius * radius;
        float disc = b * b - c;
        if (!(disc >= 0.0f)) return 0;
        float root = sqrt(disc);
        /* The cap around the vertex: the far crossing when the centre lies on the film side, else the near. */
        t = radius > 0.0f ? -b + root : -b - root;
        if (!(t > 0.0f)) return 0;
        normal = normalize(*o + t * *d - centre);
    }
    float3 p = *o + t * *d;
    if (p.x * p.x + p.y * p.y > s.w * s.w) return 0;
    *o = p;
    if (radius == 0.0f) return 1;
    /* Snell's law with η = n_t / n_i = s.z, the normal turned toward the incoming side. */
    float cos_i = -dot(*d, normal);
    if (cos_i < 0.0f) {
        normal = -normal;
        cos_i = -cos_i;
    }
    float eta = s.z;
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return 0;
    float cos_t = sqrt(1.0f - sin2_t);
    *d = normalize(*d / eta + (cos_i / eta - cos_t) * normal);
    return 1;
}

/* film: the position in pixels (x right, y down). */
inline Ray realistic_camera_ray(__global const RenderParams *p, float2 film, Sampler *sampler, float *weight)
{
    float4 head = p->lens_elements[0];
    int count = (int)head.z;
    /* The lens images the film upside down and mirrored: a point right of centre sees the scene left of it. */
    float3 o = (float3)(-(2.0f * film.x / (float)p->width - 1.0f) * head.x,
                        (2.0f * film.y / (float)p->height - 1.0f) * head.y, 0.0f);
    float2 u = sample_2d(sampler);
    float r = length(o.xy);
    int ring = min((int)(r / length(head.xy) * (float)LENS_PUPIL_BINS), LENS_PUPIL_BINS - 1);
    float4 box = p->lens_pupils[ring];
    float area = (box.z - box.x) * (box.w - box.y);
    float2 q = (float2)(box.x + u.x * (box.z - box.x), box.y + u.y * (box.w - box.y));
    float2 azimuth = r > 0.0f ? o.xy / r : (float2)(1.0f, 0.0f);
    float2 rear = (float2)(azimuth.x * q.x - azimuth.y * q.y, azimuth.y * q.x + azimuth.x * q.y);
    float z_rear = p->lens_elements[1].y;
    float3 d = (float3)(rear.x, rear.y, z_rear) - o;
    float cos_theta = d.z / length(d);
    float cos2 = cos_theta * cos_theta;
    d = normalize(d);
    int passed = area > 0.0f;
    for (int i = 1; i <= count && passed; ++i) passed = realistic_surface(p->lens_elements[i], &o, &d);
    float3 right = normalize(p->camera_right.xyz), up = normalize(p->camera_up.xyz), forward = p->camera_forward.xyz;
    Ray ray;
    if (!passed) {
        *weight = 0.0f;
        ray.origin = p->camera_origin.xyz;
        ray.direction = forward;
        return ray;
    }
    *weight *= cos2 * cos2 * area / (z_rear * z_rear);
    ray.origin = p->camera_origin.xyz + o.x * right + o.y * up + o.z * forward;
    ray.direction = normalize(d.x * right + d.y * up + d.z * forward);
    return ray;
}

#endif
