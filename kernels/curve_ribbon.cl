/* pbrt-v4's flat and ribbon curves (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., sec. 6.7:
 * its Curve of type Flat and Ribbon) on one linear segment of a curve shape: a strip of half-width r(s) = ra + s (rb
 * − ra) about the axis from a (s = 0) to b (s = 1), with no thickness and open, square ends. Units: scene units; the
 * ray's direction is unit.
 *
 * Flat (CURVE_TYPE_FLAT): the strip always faces the ray. For a ray of direction d it is the part of the plane
 * through the axis whose normal is d's part across the axis, m = d − (d·w) w (w the unit axis), within r(s) of the
 * axis: the ray meets that plane at t = −(o − a)·m / |m|², and the hit is on the strip where 0 <= s <= 1 and the
 * offset across, along e = n × w with n = −m / |m| (facing the ray), is within ±r(s). The strip's projection on the
 * plane across the ray is then the segment's projected axis widened by ±r(s) at right angles to it, and the hit's
 * distance the depth of the axis point, which is what pbrt's test (the ray's distance from the projected curve
 * against half the width, at the depth of the curve's point) gives for a linear piece: this is that test in closed
 * form. The normal faces every ray, so a diffuse flat curve shades as a flat strip turned to the viewer.
 *
 * Ribbon (CURVE_TYPE_RIBBON): a strip of fixed orientation. The row holds the strip's normals na, nb at its ends
 * (pbrt interpolates its `N` by slerp along the curve; the host cuts a curve into pieces that turn by at most a few
 * degrees, geometry/curves.py, so that a piece is its bilinear patch within a fraction of a percent of its width):
 * P(s, x) = a + s (b − a) + x ((1 − s) ha + s hb), x in [−1, 1], ha = ra (na × w)/|na × w| and hb likewise, the
 * bilinear patch of its four corners. It is intersected exactly as such (Reshetov 2019, "Cool Patches: A Geometric
 * Approach to Ray/Bilinear Patch Intersections", Ray Tracing Gems ch. 8): the ray meets the ruling at s where d,
 * P(s, 0) − o and ∂P/∂x are coplanar, d · ((P(s, 0) − o) × ∂P/∂x) = 0, a quadratic in s; x and t then follow from
 * the two lines' meeting. This is chosen over pbrt's own test, which widens the projected axis by r |n·d| and
 * puts the hit at the axis point's depth: that is exact only for rays at right angles to the axis (seen at an angle
 * θ to it, pbrt's strip is sin θ narrower than the strip itself, and its hits lie off the strip), while the bilinear
 * patch is the strip itself and shares its edges with the next piece's, so a ribbon has no gaps or overlaps at the
 * pieces' joins. Seen edge-on (d in the strip's plane) the quadratic vanishes: no hit.
 * The normal is the patch's, ∂P/∂s × ∂P/∂x, which is the interpolated strip normal on the axis.
 *
 * Both are two-sided. A strip stands for a fibre's silhouette (pbrt offsets its spawned rays by the whole width for
 * that reason): a ray that starts within r(s) of the segment's axis (a ray leaving the strip, reflected or
 * transmitted) does not meet the segment, whose strip facing the new direction would otherwise cross it.
 *
 * The hit record (Hit.b12): a ribbon's (s, x); a flat strip's (s, k + f), k the azimuth of its normal about w in
 * 1/CURVE_FLAT_AZIMUTHS turns (frame: shape_curve.cl's curve_frame) and f = (1 + x)/2 kept within (0, 1): the
 * normal rebuilt from the record is within half a step (0.09°) of the ray's. The texture coordinates are pbrt's: u
 * along the curve, v = (1 + h)/2 with h = x on the side the ray comes from (h's sign turned where the ray sees the
 * strip's back), which is the offset across the fibre the hair BSDF reads (bsdf_hair.cl): the same h as the tube's
 * (curve.cl) for the ray that meets the tube at the same offset. */
#ifndef SPECTRACE_CURVE_RIBBON_CL
#define SPECTRACE_CURVE_RIBBON_CL

#include "curve.cl"
#include "ray.cl"

#define CURVE_FLAT_AZIMUTHS 2048.0f

/* A curve row's type (CURVE_TYPE_*, geometry/curves.py): kept in its cut_min, which only partial shapes read. */
inline int curve_row_type(__global const AnalyticShape *s)
{
    return (int)s->cut_min;
}

/* Whether p lies within r(s) of the segment's axis, s the parameter of its projection (clamped), with a margin of
 * twice the step a spawned ray takes off its surface (ray.cl). */
inline int curve_ribbon_origin_inside(float3 p, float3 a, float ra, float3 b, float rb)
{
    float3 axis = b - a;
    float s = clamp(dot(p - a, axis) / dot(axis, axis), 0.0f, 1.0f);
    float r = ra + s * (rb - ra);
    return length(p - (a + s * axis)) < r + 2.0e-5f * (1.0f + max_abs_component(p));
}

/* The strip's across vectors at a and b: r (n × w) / |n × w|. */
inline void curve_ribbon_across(__global const AnalyticShape *s, float3 w, float3 *ha, float3 *hb)
{
    *ha = s->sphere.w * normalize(cross(s->to_object[0].xyz, w));
    *hb = s->to_world[0].w * normalize(cross(s->to_object[1].xyz, w));
}

/* The nearest hit of a flat or ribbon segment in (0, t_max) along the ray, or t_max; its record in *uv. */
inline float intersect_curve_ribbon(__global const AnalyticShape *s, float3 origin, float3 direction, float t_max,
                                    float2 *uv)
{
    float3 a = s->sphere.xyz, b = s->to_world[0].xyz;
    float ra = s->sphere.w, rb = s->to_world[0].w;
    if (curve_ribbon_origin_inside(origin, a, ra, b, rb)) return t_max;
    float3 axis = b - a;
    float l = length(axis);
    if (!(l > 0.0f)) return t_max;
    float3 w = axis / l;
    float3 oa = origin - a;
    if (curve_row_type(s) == CURVE_TYPE_FLAT) {
        float3 m = direction - dot(direction, w) * w;
        float mm = dot(m, m);
        if (!(mm > 1.0e-12f)) return t_max;
        float t = -dot(oa, m) / mm;
        if (!(t > 0.0f && t < t_max)) return t_max;
        float3 q = oa + t * direction;
        float along = dot(q, w) / l;
        if (!(along >= 0.0f && along <= 1.0f)) return t_max;
        float3 n = -m / sqrt(mm);
        float x = dot(q, cross(n, w)) / (ra + along * (rb - ra));
        if (!(fabs(x) <= 1.0f)) return t_max;
        float3 e1, e2;
        curve_frame(w, &e1, &e2);
        float turns = atan2(dot(n, e2), dot(n, e1)) * (1.0f / SHAPE_TWO_PI);
        float step = floor((turns < 0.0f ? turns + 1.0f : turns) * CURVE_FLAT_AZIMUTHS + 0.5f);
        if (step >= CURVE_FLAT_AZIMUTHS) step = 0.0f;
        *uv = (float2)(along, step + 0.0005f + 0.999f * 0.5f * (1.0f + x));
        return t;
    }
    float3 ha, hb;
    curve_ribbon_across(s, w, &ha, &hb);
    float3 b1 = hb - ha;
    float3 a0 = -oa;  /* P(s, 0) − o = a0 + s axis; ∂P/∂x = ha + s b1 */
    float c2 = dot(direction, cross(axis, b1));
    float c1 = dot(direction, cross(a0, b1) + cross(axis, ha));
    float c0 = dot(direction, cross(a0, ha));
    float r0, r1;
    if (!curve_roots(c2, 0.5f * c1, c0, &r0, &r1)) return t_max;
    float roots[2] = {r0, r1};
    float best = t_max;
    for (int i = 0; i < 2; ++i) {
        float along = roots[i];
        if (!(along >= 0.0f && along <= 1.0f)) continue;
        float3 base = a0 + along * axis, across = ha + along * b1;
        float3 across_d = cross(across, direction);
        float denominator = dot(across_d, across_d);
        if (!(denominator > 0.0f)) continue;
        float x = -dot(cross(base, direction), across_d) / denominator;
        if (!(fabs(x) <= 1.0f)) continue;
        float3 point = base + x * across;
        float t = dot(point, direction);
        /* The lines must meet: a near-vanishing quadratic (a ray grazing the strip's plane) has roots of rounding. */
        if (!(t > 0.0f && t < best) || length(point - t * direction) > 1.0e-3f * length(across)) continue;
        best = t;
        *uv = (float2)(along, x);
    }
    return best;
}

/* The parameter s and the offset x ∈ [−1, 1] across a flat or ribbon hit record; a flat one's normal in *n. */
inline float2 curve_ribbon_where(__global const AnalyticShape *s, float2 where, float3 w, float3 *n)
{
    if (curve_row_type(s) != CURVE_TYPE_FLAT) return where;
    float step = floor(where.y);
    float x = clamp(((where.y - step) - 0.0005f) / 0.999f * 2.0f - 1.0f, -1.0f, 1.0f);
    float3 e1, e2;
    curve_frame(w, &e1, &e2);
    float2 azimuth = cos_sin_turns(step * (1.0f / CURVE_FLAT_AZIMUTHS));
    *n = azimuth.x * e1 + azimuth.y * e2;
    return (float2)(where.x, x);
}

/* The point, unit normal and tangents of a flat or ribbon hit record: dp/du along the fibre per unit of the curve's
 * texture u, dp/dv across it (the strip's whole width, which v spans). */
inline void curve_ribbon_local(__global const AnalyticShape *s, float2 where, float3 *point, float3 *normal,
                               float3 *tangent_u, float3 *tangent_v)
{
    float3 a = s->sphere.xyz, b = s->to_world[0].xyz;
    float ra = s->sphere.w, rb = s->to_world[0].w;
    float3 axis = b - a;
    float3 w = normalize(axis);
    float3 n = (float3)(0.0f, 0.0f, 1.0f);
    float2 sx = curve_ribbon_where(s, where, w, &n);
    float du = s->to_world[1].y - s->to_world[1].x;
    float along_scale = du > 0.0f ? 1.0f / du : 1.0f;
    if (curve_row_type(s) == CURVE_TYPE_FLAT) {
        float3 across = (ra + sx.x * (rb - ra)) * cross(n, w);
        *point = a + sx.x * axis + sx.y * across;
        *normal = n;
        *tangent_u = axis * along_scale;
        *tangent_v = 2.0f * across;
        return;
    }
    float3 ha, hb;
    curve_ribbon_across(s, w, &ha, &hb);
    float3 across = ha + sx.x * (hb - ha);
    float3 dp_ds = axis + sx.y * (hb - ha);
    *point = a + sx.x * axis + sx.y * across;
    *normal = normalize(cross(dp_ds, across));
    *tangent_u = dp_ds * along_scale;
    *tangent_v = 2.0f * across;
}

/* pbrt's texture coordinates at a flat or ribbon hit seen along −wo (n the hit's normal): u along the curve, v =
 * (1 + h)/2 with h the offset across, its sign turned where wo sees the normal's back. */
inline float2 curve_ribbon_uv(__global const AnalyticShape *s, float2 where, float3 n, float3 wo)
{
    float3 w = normalize(s->to_world[0].xyz - s->sphere.xyz), flat_n;
    float2 sx = curve_ribbon_where(s, where, w, &flat_n);
    float u = s->to_world[1].x + sx.x * (s->to_world[1].y - s->to_world[1].x);
    float h = dot(wo, n) >= 0.0f ? sx.y : -sx.y;
    return (float2)(u, 0.5f * (1.0f + h));
}

#endif
