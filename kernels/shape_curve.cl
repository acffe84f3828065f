/* Curve segments as analytic shapes: an AnalyticShape row of type SHAPE_CURVE is one linear swept-sphere segment
 * (kernels/curve.cl) of a curve shape (host: spectrace.geometry.curves), a primitive of the shapes' BVH like a
 * sphere. Row layout: sphere = (a, ra), to_world[0] = (b, rb), to_world[1] = (u0, u1, cap a, cap b): the curve's
 * texture u at a and b, and whether the end sphere at a (b) is surface (1) or not (0: the tube is open there, a
 * B-spline curve's ends); to_object[0], [1] = the two control points (x, y, z, radius) before a, to_object[2],
 * to_world[2] the two after b (radius 0: none), whose segments' insides are not this segment's surface, so that
 * (but for curves bent within two segments' length) no surface lies inside the tube; world (or an instanced object's) space, scene units.
 * cut_min holds the curve's type, CURVE_TYPE_TUBE (0) for these; a flat or ribbon row (pbrt-v4's strips,
 * curve_ribbon.cl) has the same ends and u0, u1, no caps or neighbours, and a ribbon's unit normals at a and b in
 * to_object[0].xyz and to_object[1].xyz.
 *
 * Back faces are culled, as Mitsuba 3's curves (Embree, OptiX) and pbrt-v4's ribbons do: a ray leaving a fibre's
 * surface inward (the hair BSDF's transmission) crosses the fibre, whose interior that BSDF already accounts for.
 *
 * The hit stores where on the segment's surface it lies in Hit.b12, from which curve_shape_local rebuilds it:
 * x the profile coordinate s (−1..0 over the end sphere at a, from its pole opposite b to where the cone touches it;
 * 0..1 the cone, s the parameter of the centre of the sphere the point lies on, as CurveHit.u; 1..2 the end sphere
 * at b, out to its pole), y the azimuth about the axis in turns (frame: curve_frame). The texture coordinates a
 * material sees are, with the row's pbrt_uv, pbrt-v4's curves': u along the curve, v = (1 + h) / 2 across it
 * (curve_texture_uv); h depends on the ray, so the path vertex sets them (path_state.cl shape_vertex). Without
 * pbrt_uv they are Mitsuba 3's (its linearcurve.cpp; curve_mitsuba_uv): u the azimuth in turns about the axis,
 * v along all the file's segments, (segment index + position within it) / segment
 * count, which the host writes as the row's u0, u1; the hair BSDF then takes h from the geometry at the hit
 * (bsdf_hair.cl, SurfaceContext.fibre_h_from_geometry). */
#ifndef SPECTRACE_SHAPE_CURVE_CL
#define SPECTRACE_SHAPE_CURVE_CL

#include "curve.cl"
#include "ray.cl"

#define CURVE_HALF_PI 1.57079632679489661923f

/* Two unit vectors completing the unit axis w to a right-handed frame (Duff et al. 2017, "Building an Orthonormal
 * Basis, Revisited", JCGT 6(1)). */
inline void curve_frame(float3 w, float3 *e1, float3 *e2)
{
    float sign = copysign(1.0f, w.z);
    float a = -1.0f / (sign + w.z);
    float b = w.x * w.y * a;
    *e1 = (float3)(1.0f + sign * w.x * w.x * a, sign * b, -sign * w.x);
    *e2 = (float3)(b, sign + w.y * w.y * a, -w.y);
}

#if SCENE_HAS_CURVE_RIBBONS
#include "curve_ribbon.cl"
#endif

/* Whether p lies inside the swept sphere from (a.xyz, radius a.w) to (b.xyz, b.w) by more than the rounding of
 * its coordinates: |p − c(s)| − r(s) at the s of p's projection on the axis, an upper bound of the distance to the
 * surface, so a point it calls inside is. The margin is a tenth of the step a spawned ray takes off its surface
 * (ray.cl): a ray sent into the fibre (the hair BSDF's transmission) starts that far inside this segment, and a
 * neighbour's surface it then crosses lies at least about that deep inside, so it is not taken for surface. A
 * margin in proportion to the radius let the neighbours' surfaces, which cross at grazing angles where a curve
 * bends a little per segment, stop such rays within a thousandth of the radius. False where either radius is 0
 * (no segment). */
inline int curve_inside_segment(float3 p, float4 a, float4 b)
{
    if (!(a.w > 0.0f && b.w > 0.0f)) return 0;
    float3 axis = b.xyz - a.xyz;
    float s = clamp(dot(p - a.xyz, axis) / dot(axis, axis), 0.0f, 1.0f);
    float r = a.w + s * (b.w - a.w);
    return length(p - (a.xyz + s * axis)) < r - 1.0e-6f * (1.0f + max_abs_component(p));
}

/* The nearest front-facing hit of the segment in (0, t_max) along the ray (unit direction), or t_max; where it lies
 * in *uv (profile coordinate, azimuth). */
inline float intersect_curve_shape(__global const AnalyticShape *s, float3 origin, float3 direction, float t_max,
                                   float2 *uv)
{
#if SCENE_HAS_CURVE_RIBBONS
    if (curve_row_type(s) != CURVE_TYPE_TUBE) return intersect_curve_ribbon(s, origin, direction, t_max, uv);
#endif
    float3 a = s->sphere.xyz, b = s->to_world[0].xyz;
    float ra = s->sphere.w, rb = s->to_world[0].w;
    CurveHit hit = intersect_curve_segment(origin, direction, 0.0f, t_max, a, ra, b, rb);
    if (!(hit.t < t_max) || dot(hit.n, direction) >= 0.0f) return t_max;
    float l = length(b - a);
    float sin_phi = (ra - rb) / l;  /* the cone's tilt: the normal's part along w on the cone */
    float sin_psi = clamp(dot(hit.n, hit.w), -1.0f, 1.0f);
    float profile = hit.u;
    if (hit.u <= 0.0f && sin_psi < sin_phi) {
        float phi = asin(sin_phi);
        profile = (asin(sin_psi) - phi) / (phi + CURVE_HALF_PI);
    } else if (hit.u >= 1.0f && sin_psi > sin_phi) {
        float phi = asin(sin_phi);
        profile = 1.0f + (asin(sin_psi) - phi) / (CURVE_HALF_PI - phi);
    }
    /* An open end (a B-spline curve's first and last point) has no sphere: the ray that meets it enters the tube
     * and meets only back faces after. */
    if ((profile < 0.0f && s->to_world[1].z == 0.0f) || (profile > 1.0f && s->to_world[1].w == 0.0f)) return t_max;
    /* Surface inside a neighbouring segment (the inner side of a bend, most of a joint's sphere) is inside the tube,
     * not its surface. */
    float3 p = origin + hit.t * direction;
    float4 before2 = s->to_object[0], before = s->to_object[1], after = s->to_object[2], after2 = s->to_world[2];
    if (curve_inside_segment(p, before, s->sphere) || curve_inside_segment(p, before2, before) ||
        curve_inside_segment(p, s->to_world[0], after) || curve_inside_segment(p, after, after2))
        return t_max;
    float3 e1, e2;
    curve_frame(hit.w, &e1, &e2);
    float turns = atan2(dot(hit.n, e2), dot(hit.n, e1)) * (1.0f / SHAPE_TWO_PI);
    *uv = (float2)(profile, turns < 0.0f ? turns + 1.0f : turns);
    return hit.t;
}

/* The point, outward normal and tangents at a hit's (profile, azimuth): dp/du along the fibre per unit of the
 * curve's texture u, dp/dv across it (2 r, the width v spans). */
inline void curve_shape_local(__global const AnalyticShape *s, float2 where, float3 *point, float3 *normal,
                              float3 *tangent_u, float3 *tangent_v)
{
#if SCENE_HAS_CURVE_RIBBONS
    if (curve_row_type(s) != CURVE_TYPE_TUBE) {
        curve_ribbon_local(s, where, point, normal, tangent_u, tangent_v);
        return;
    }
#endif
    float3 a = s->sphere.xyz, b = s->to_world[0].xyz;
    float ra = s->sphere.w, rb = s->to_world[0].w;
    float3 axis = b - a;
    float l = length(axis);
    float3 w = axis / l;
    float phi = asin(clamp((ra - rb) / l, -1.0f, 1.0f));
    float profile = where.x, psi = phi;
    float3 centre;
    float r;
    if (profile < 0.0f) {
        psi = phi + profile * (phi + CURVE_HALF_PI);
        centre = a;
        r = ra;
    } else if (profile > 1.0f) {
        psi = phi + (profile - 1.0f) * (CURVE_HALF_PI - phi);
        centre = b;
        r = rb;
    } else {
        centre = a + profile * axis;
        r = ra + profile * (rb - ra);
    }
    float3 e1, e2;
    curve_frame(w, &e1, &e2);
    float2 azimuth = cos_sin_turns(where.y);
    float3 radial = azimuth.x * e1 + azimuth.y * e2;
    float3 n = cos(psi) * radial + sin(psi) * w;
    *point = centre + r * n;
    *normal = n;
    float du = s->to_world[1].y - s->to_world[1].x;
    *tangent_u = du > 0.0f ? axis / du : axis;
    *tangent_v = 2.0f * r * cross(w, radial);
}

/* Mitsuba 3's texture coordinates at a hit's (profile, azimuth), v along the curve given: u the azimuth of the
 * normal about the segment's axis w in turns, measured from rad = rot × w toward rot, rot the part of +z across
 * the axis (+y where the axis is along z), so that neighbouring segments agree. In the row's space, as Mitsuba
 * takes it in the shape's. */
inline float2 curve_mitsuba_uv(__global const AnalyticShape *s, float2 where, float v)
{
    float3 n, p, dpdu, dpdv;
    curve_shape_local(s, where, &p, &n, &dpdu, &dpdv);
    float3 w = normalize(s->to_world[0].xyz - s->sphere.xyz);
    float3 rot = fabs(w.z) == 1.0f ? (float3)(0.0f, 1.0f, 0.0f) : normalize((float3)(0.0f, 0.0f, 1.0f) - w * w.z);
    float turns = atan2(dot(rot, n), dot(cross(rot, w), n)) * (1.0f / SHAPE_TWO_PI);
    return (float2)(turns < 0.0f ? turns + 1.0f : turns, v);
}

/* The texture coordinates at a hit seen along -wo: u along the curve, v = (1 + h) / 2 with h the signed offset
 * across the fibre (curve.cl's, from the normal n and the fibre's direction); without pbrt_uv Mitsuba 3's, u
 * around the fibre and v along it, which do not depend on the ray. */
inline float2 curve_texture_uv(__global const AnalyticShape *s, float2 where, float3 n, float3 dpdu, float3 wo)
{
#if SCENE_HAS_CURVE_RIBBONS
    if (curve_row_type(s) != CURVE_TYPE_TUBE) return curve_ribbon_uv(s, where, n, wo);
#endif
    float u = s->to_world[1].x + clamp(where.x, 0.0f, 1.0f) * (s->to_world[1].y - s->to_world[1].x);
    if (!s->pbrt_uv) return curve_mitsuba_uv(s, where, u);
    float3 w = normalize(dpdu);
    float3 across = cross(n, w);
    float across_length = length(across);
    float3 wo_normal_plane = wo - dot(wo, w) * w;
    float plane_length = length(wo_normal_plane);
    float h = across_length > 0.0f && plane_length > 0.0f
                  ? clamp(-dot(wo, across) / (across_length * plane_length), -1.0f, 1.0f)
                  : 0.0f;
    return (float2)(u, 0.5f * (1.0f + h));
}

/* u along the curve with v = ½ (the axis), for lookups that have no ray (cut-outs); without pbrt_uv Mitsuba 3's
 * coordinates, which need none. */
inline float2 curve_axis_uv(__global const AnalyticShape *s, float2 where)
{
    float u = s->to_world[1].x + clamp(where.x, 0.0f, 1.0f) * (s->to_world[1].y - s->to_world[1].x);
    return s->pbrt_uv ? (float2)(u, 0.5f) : curve_mitsuba_uv(s, where, u);
}

#endif
