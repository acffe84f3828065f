/* Analytic shapes (types.h AnalyticShape): exact ray intersection, the surface at a hit (point, normal, texture
 * coordinates and their tangents, in Mitsuba 3's conventions for its sphere, disk and cylinder plugins), uniform area
 * sampling, and the sphere's sampling by the cone of directions it subtends.
 *
 * The sphere is intersected in world space with the quadratic's numerically stable form (Haines, Günther, Wald,
 * "Precise Ray/Sphere Intersection", Ray Tracing Gems ch. 7, 2019; pbrt-v4's Sphere::BasicIntersect): the
 * discriminant from the squared distance of the ray to the centre, r² − |f − (f·d) d|², rather than the difference
 * b² − c of two large numbers, and the smaller root as c / q; the hit point is then projected back onto the sphere
 * (pbrt-v4's refinement). The disk and cylinder are intersected in object space, so any affine placement works.
 * A hit stores the shape's texture coordinates in Hit.b12, from which its surface is rebuilt; a shape imported from
 * pbrt-v4 may keep pbrt's texture coordinates instead of Mitsuba's (pbrt_uv). Partial shapes (phi_max > 0) are
 * shape_partial.cl's. */
#ifndef SPECTRACE_SHAPES_CL
#define SPECTRACE_SHAPES_CL

#include "types.h"
#include "ray.cl"
#include "sampling.cl"

#define SHAPE_TWO_PI 6.28318530717958647692f
#define SHAPE_PI 3.14159265358979323846f

inline float3 shape_point_to_world(__global const AnalyticShape *s, float3 p)
{
    float4 q = (float4)(p, 1.0f);
    return (float3)(dot(s->to_world[0], q), dot(s->to_world[1], q), dot(s->to_world[2], q));
}

inline float3 shape_vector_to_world(__global const AnalyticShape *s, float3 v)
{
    return (float3)(dot(s->to_world[0].xyz, v), dot(s->to_world[1].xyz, v), dot(s->to_world[2].xyz, v));
}

inline float3 shape_point_to_object(__global const AnalyticShape *s, float3 p)
{
    float4 q = (float4)(p, 1.0f);
    return (float3)(dot(s->to_object[0], q), dot(s->to_object[1], q), dot(s->to_object[2], q));
}

inline float3 shape_vector_to_object(__global const AnalyticShape *s, float3 v)
{
    return (float3)(dot(s->to_object[0].xyz, v), dot(s->to_object[1].xyz, v), dot(s->to_object[2].xyz, v));
}

/* An object-space normal in world space, by the inverse transpose (not normalised): its length times abs_det is
 * how much the map stretches area there. */
inline float3 shape_normal_to_world(__global const AnalyticShape *s, float3 n)
{
    return n.x * s->to_object[0].xyz + n.y * s->to_object[1].xyz + n.z * s->to_object[2].xyz;
}

/* u in [0, 1) of the azimuth of (x, y), as Mitsuba's atan2 + 2π wrap. */
inline float shape_azimuth_turns(float x, float y)
{
    float u = atan2(y, x) * (1.0f / SHAPE_TWO_PI);
    return u < 0.0f ? u + 1.0f : u;
}

/* A shape's texture coordinates from Mitsuba 3's, and back. With pbrt_uv they are pbrt-v4's (its Disk and Sphere
 * InteractionFromIntersection): the whole disk u = φ/2π, v = 1 − r (Mitsuba's u = r, v = φ/2π); the whole sphere
 * v = 1 − θ/π (Mitsuba's θ/π). The cylinders agree. Hits, surfaces and samples all use the shape's own. */
inline float2 shape_uv_from_mitsuba(__global const AnalyticShape *s, float2 uv)
{
    if (!s->pbrt_uv) return uv;
    if (s->type == SHAPE_DISK) return (float2)(uv.y, 1.0f - uv.x);
    if (s->type == SHAPE_SPHERE) return (float2)(uv.x, 1.0f - uv.y);
    return uv;
}

inline float2 shape_uv_to_mitsuba(__global const AnalyticShape *s, float2 uv)
{
    if (!s->pbrt_uv) return uv;
    if (s->type == SHAPE_DISK) return (float2)(1.0f - uv.y, uv.x);
    if (s->type == SHAPE_SPHERE) return (float2)(uv.x, 1.0f - uv.y);
    return uv;
}

/* The roots of a t² + 2 b t + c = 0 given sqrt(b² − a c) (>= 0), near first; 0 when there are none. */
inline int stable_roots(float a, float b, float c, float sqrt_discriminant, float *t0, float *t1)
{
    float q = -(b + copysign(sqrt_discriminant, b));
    if (q == 0.0f || a == 0.0f) return 0;
    float r0 = q / a, r1 = c / q;
    *t0 = fmin(r0, r1);
    *t1 = fmax(r0, r1);
    return 1;
}

#if SCENE_HAS_PARTIAL_SHAPES
#include "shape_partial.cl"
#endif
#if SCENE_HAS_SDF_GRIDS
#include "shape_sdf_grid.cl"
#endif
#if SCENE_HAS_CURVES
#include "shape_curve.cl"
#endif

/* The nearest hit of the shape in (0, t_max) along the ray (unit direction), or t_max; its texture coordinates in
 * *uv. */
inline float intersect_shape(__global const AnalyticShape *s, float3 origin, float3 direction, float t_max,
                             float2 *uv)
{
#if SCENE_HAS_SDF_GRIDS
    if (s->type == SHAPE_SDFGRID) return intersect_sdf_grid(s, origin, direction, t_max, uv);
#endif
#if SCENE_HAS_PARTIAL_SHAPES
    if (s->phi_max > 0.0f) return intersect_partial_shape(s, origin, direction, t_max, uv);
#endif
#if SCENE_HAS_CURVES
    if (s->type == SHAPE_CURVE) return intersect_curve_shape(s, origin, direction, t_max, uv);
#endif
    if (s->type == SHAPE_SPHERE) {
        float3 centre = s->sphere.xyz;
        float radius = s->sphere.w;
        float3 f = origin - centre;
        float b = dot(f, direction);
        float3 perpendicular = f - b * direction;
        float discriminant = radius * radius - dot(perpendicular, perpendicular);
        if (discriminant < 0.0f) return t_max;
        float t0, t1;
        if (!stable_roots(1.0f, b, dot(f, f) - radius * radius, sqrt(discriminant), &t0, &t1)) return t_max;
        float t = t0 > 0.0f ? t0 : t1;
        if (!(t > 0.0f && t < t_max)) return t_max;
        /* Projected back onto the sphere: the object-space point at unit distance from the centre. */
        float3 object_point = normalize(shape_point_to_object(s, origin + t * direction));
        *uv = shape_uv_from_mitsuba(s, (float2)(shape_azimuth_turns(object_point.x, object_point.y),
                       atan2(sqrt(object_point.x * object_point.x + object_point.y * object_point.y), object_point.z) * (1.0f / SHAPE_PI)));
        return t;
    }
    float3 o = shape_point_to_object(s, origin);
    float3 d = shape_vector_to_object(s, direction);
    if (s->type == SHAPE_DISK) {
        if (d.z == 0.0f) return t_max;
        float t = -o.z / d.z;
        if (!(t > 0.0f && t < t_max)) return t_max;
        float x = o.x + t * d.x, y = o.y + t * d.y;
        float r2 = x * x + y * y;
        if (r2 > 1.0f) return t_max;
        *uv = shape_uv_from_mitsuba(s, (float2)(sqrt(r2), shape_azimuth_turns(x, y)));
        return t;
    }
    /* SHAPE_CYLINDER: x² + y² = 1, 0 <= z <= 1. b² − a c = a − (o × d)_z² for the unit circle (Lagrange's identity),
     * the same precise form as the sphere's. */
    float a = d.x * d.x + d.y * d.y;
    float b = o.x * d.x + o.y * d.y;
    float cross_z = o.x * d.y - o.y * d.x;
    float discriminant = a - cross_z * cross_z;
    if (!(discriminant >= 0.0f)) return t_max;
    float t0, t1;
    if (!stable_roots(a, b, o.x * o.x + o.y * o.y - 1.0f, sqrt(discriminant), &t0, &t1)) return t_max;
    float z0 = o.z + t0 * d.z, z1 = o.z + t1 * d.z;
    float t;
    if (t0 > 0.0f && t0 < t_max && z0 >= 0.0f && z0 <= 1.0f) {
        t = t0;
    } else if (t1 > 0.0f && t1 < t_max && z1 >= 0.0f && z1 <= 1.0f) {
        t = t1;
    } else {
        return t_max;
    }
    float3 p = o + t * d;
    *uv = (float2)(shape_azimuth_turns(p.x, p.y), clamp(p.z, 0.0f, 1.0f));
    return t;
}

/* A point of an analytic shape, in world space. */
typedef struct {
    float3 p;
    float3 n;          /* unit geometric normal: outward (the disk's: +z's image), the front side; the other way
                          round with flip_normals */
    float3 dpdu;       /* tangents along the texture coordinates (Mitsuba 3's dp_du, dp_dv), for surface detail */
    float3 dpdv;
    float area_stretch;  /* world area per object-space area here: abs_det · |M⁻ᵀ n_object| */
} ShapeSurface;

/* The whole shape's object-space point, normal and tangents along its texture coordinates (shape_uv_from_mitsuba),
 * from Mitsuba's: sphere u = φ/2π, v = θ/π (θ from +z); disk u = r, v = φ/2π; cylinder u = φ/2π, v = z. */
inline void whole_shape_local(__global const AnalyticShape *s, float2 shape_uv, float3 *point, float3 *normal,
                              float3 *tangent_u, float3 *tangent_v)
{
    float2 uv = shape_uv_to_mitsuba(s, shape_uv);
    float3 object_point, n_local, dpdu, dpdv;
    if (s->type == SHAPE_SPHERE) {
        float2 azimuth = cos_sin_turns(uv.x);
        float cos_theta = cos(SHAPE_PI * uv.y), sin_theta = sin(SHAPE_PI * uv.y);
        object_point = (float3)(sin_theta * azimuth.x, sin_theta * azimuth.y, cos_theta);
        n_local = object_point;
        dpdu = SHAPE_TWO_PI * (float3)(-object_point.y, object_point.x, 0.0f);
        dpdv = SHAPE_PI * (float3)(cos_theta * azimuth.x, cos_theta * azimuth.y, -sin_theta);
    } else if (s->type == SHAPE_DISK) {
        float2 azimuth = cos_sin_turns(uv.y);
        object_point = (float3)(uv.x * azimuth.x, uv.x * azimuth.y, 0.0f);
        n_local = (float3)(0.0f, 0.0f, 1.0f);
        dpdu = (float3)(azimuth.x, azimuth.y, 0.0f);
        dpdv = SHAPE_TWO_PI * (float3)(-object_point.y, object_point.x, 0.0f);
    } else {
        float2 azimuth = cos_sin_turns(uv.x);
        object_point = (float3)(azimuth.x, azimuth.y, uv.y);
        n_local = (float3)(azimuth.x, azimuth.y, 0.0f);
        dpdu = SHAPE_TWO_PI * (float3)(-azimuth.y, azimuth.x, 0.0f);
        dpdv = (float3)(0.0f, 0.0f, 1.0f);
    }
    if (s->pbrt_uv && s->type == SHAPE_DISK) {  /* pbrt's (u, v) = (Mitsuba's v, 1 − Mitsuba's u) */
        float3 dpdr = dpdu;
        dpdu = dpdv;
        dpdv = -dpdr;
    } else if (s->pbrt_uv && s->type == SHAPE_SPHERE) {
        dpdv = -dpdv;
    }
    *point = object_point;
    *normal = n_local;
    *tangent_u = dpdu;
    *tangent_v = dpdv;
}

/* The surface at the shape's texture coordinates (whole_shape_local; a partial shape's: shape_partial.cl). */
inline ShapeSurface shape_surface(__global const AnalyticShape *s, float2 shape_uv)
{
#if SCENE_HAS_CURVES
    if (s->type == SHAPE_CURVE) {  /* its rows hold the segment itself, in the space the row is in */
        ShapeSurface c;
        curve_shape_local(s, shape_uv, &c.p, &c.n, &c.dpdu, &c.dpdv);
        c.area_stretch = 1.0f;
        return c;
    }
#endif
    float3 object_point, n_local, dpdu, dpdv;
#if SCENE_HAS_SDF_GRIDS
    if (s->type == SHAPE_SDFGRID)
        sdf_grid_local(s, shape_uv, &object_point, &n_local, &dpdu, &dpdv);
    else
#endif
#if SCENE_HAS_PARTIAL_SHAPES
    if (s->phi_max > 0.0f)
        partial_shape_local(s, shape_uv, &object_point, &n_local, &dpdu, &dpdv);
    else
#endif
        whole_shape_local(s, shape_uv, &object_point, &n_local, &dpdu, &dpdv);
    ShapeSurface g;
    g.p = shape_point_to_world(s, object_point);
    float3 n = shape_normal_to_world(s, n_local);
    float length_n = length(n);
    g.n = (s->flip_normals ? -1.0f : 1.0f) * n / length_n;
    g.area_stretch = s->abs_det * length_n;
    g.dpdu = shape_vector_to_world(s, dpdu);
    g.dpdv = shape_vector_to_world(s, dpdv);
    return g;
}

/* Texture coordinates of a point drawn uniformly over the shape's object-space area from u in [0, 1)². */
inline float2 shape_sample_uv(__global const AnalyticShape *s, float2 u)
{
#if SCENE_HAS_PARTIAL_SHAPES
    if (s->phi_max > 0.0f) return partial_shape_sample_uv(s, u);
#endif
    float2 uv;
    if (s->type == SHAPE_SPHERE) {
        uv = (float2)(u.y, acos(clamp(1.0f - 2.0f * u.x, -1.0f, 1.0f)) * (1.0f / SHAPE_PI));
    } else if (s->type == SHAPE_DISK) {
        uv = (float2)(sqrt(u.x), u.y);
    } else {
        uv = (float2)(u.y, u.x);
    }
    return shape_uv_from_mitsuba(s, uv);
}

/* Density over world area of shape_sample_uv's points, at a point where the map stretches area by area_stretch. */
inline float shape_area_pdf(__global const AnalyticShape *s, float area_stretch)
{
    return 1.0f / (s->object_area * area_stretch);
}

/* Cone sampling of a sphere seen from p (pbrt-v4 Sphere::Sample(ctx, u), Mitsuba 3 Sphere::sample_direction): when
 * p is outside, directions are drawn uniformly within the cone of half-angle θmax, sin θmax = r / |c − p|, that the
 * sphere fills, with solid-angle density 1 / (2π (1 − cos θmax)); the sphere point they meet follows in closed form.
 * For tiny cones 1 − cos θmax loses all its digits in float, so it comes from sin²θmax / 2 there (pbrt-v4's
 * threshold: sin²θmax below sin²(1.5°)). */
#define SPHERE_SMALL_CONE_SIN2 0.00068523f

/* 1 − cos θmax of the cone a sphere (centre c, radius r) fills seen from p; 0 when p is not outside. */
inline float sphere_cone_one_minus_cos(float3 c, float r, float3 p)
{
    float3 to_centre = c - p;
    float distance2 = dot(to_centre, to_centre);
    float r2 = r * r;
    if (!(distance2 > r2 * 1.0001f)) return 0.0f;
    float sin2_max = r2 / distance2;
    if (sin2_max < SPHERE_SMALL_CONE_SIN2) return 0.5f * sin2_max;
    return 1.0f - sqrt(fmax(0.0f, 1.0f - sin2_max));
}

/* The sphere point seen from p in a direction drawn uniformly within the cone (u in [0, 1)²): the point, its outward
 * unit normal in *n_world and the direction's solid-angle pdf. p must be outside (sphere_cone_one_minus_cos > 0). */
inline float3 sample_sphere_cone(float3 c, float r, float3 p, float2 u, float3 *n_world, float *pdf)
{
    float3 to_centre = c - p;
    float distance2 = dot(to_centre, to_centre);
    float distance = sqrt(distance2);
    float sin2_max = r * r / distance2;
    float sin_max = sqrt(sin2_max);
    float one_minus_cos_max;
    float cos_theta, sin2_theta;
    if (sin2_max < SPHERE_SMALL_CONE_SIN2) {
        sin2_theta = sin2_max * u.x;
        cos_theta = sqrt(1.0f - sin2_theta);
        one_minus_cos_max = 0.5f * sin2_max;
    } else {
        float cos_max = sqrt(fmax(0.0f, 1.0f - sin2_max));
        cos_theta = (cos_max - 1.0f) * u.x + 1.0f;
        sin2_theta = 1.0f - cos_theta * cos_theta;
        one_minus_cos_max = 1.0f - cos_max;
    }
    /* The angle α at the centre between the direction back to p and the sphere point the sampled ray meets first. */
    float cos_alpha = sin2_theta / sin_max + cos_theta * sqrt(fmax(0.0f, 1.0f - sin2_theta / sin2_max));
    float sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
    float3 axis = to_centre / distance;  /* from p toward the centre */
    float3 tangent, bitangent;
    orthonormal_basis(axis, &tangent, &bitangent);
    float2 azimuth = cos_sin_turns(u.y);
    *n_world = -(sin_alpha * (azimuth.x * tangent + azimuth.y * bitangent) + cos_alpha * axis);
    *pdf = 1.0f / (SHAPE_TWO_PI * one_minus_cos_max);
    return c + r * *n_world;
}

#endif
