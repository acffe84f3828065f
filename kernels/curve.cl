/* One segment of a linear curve: the surface swept by a sphere whose centre runs from a to b and whose radius runs
 * linearly from ra to rb (Mitsuba 3's `linearcurve`, "cylinders with rounded joints", as Embree's and OptiX's round
 * linear curves; pbrt-v4's `curve` of degree 1 and type `cylinder` is this with equal radii). The surface is the two
 * end spheres joined by the cone tangent to both: in a plane through the axis, with y along w = (b − a)/l from a and
 * x the distance from the axis, the cone is x cos φ + y sin φ = ra with sin φ = (ra − rb)/l, touching sphere a at
 * y = ra sin φ and sphere b at y = l + rb sin φ; below the first the surface is sphere a, above the second sphere b.
 * Requires l > |ra − rb| (neither sphere inside the other). Units: scene units; the direction is unit.
 *
 * What a hit gives the hair BSDF (kernels/bsdf_hair.cl): the fibre's direction w, the outward normal, u ∈ [0, 1]
 * along the segment (the parameter of the centre of the sphere the point lies on) and h ∈ [−1, 1] across it, the
 * ray's signed offset from the fibre's axis over the radius, h = −ωo·(n × w) / |ωo's part normal to w| (Mitsuba
 * 3's convention in its hair BSDF, where ωo and the normal decide h). */
#ifndef SPECTRACE_CURVE_CL
#define SPECTRACE_CURVE_CL

typedef struct {
    float t;       /* distance along the ray; INFINITY: no hit before t_max */
    float u;       /* along the segment, 0 at a, 1 at b */
    float h;       /* across the fibre, [−1, 1] */
    float3 n;      /* outward unit normal */
    float3 w;      /* unit direction of the fibre, a to b */
} CurveHit;

/* The roots of a t² + 2 b t + c = 0, smaller first, in the form that does not cancel (one root twice where a = 0).
 * Returns 0 where none is real. */
inline int curve_roots(float a, float b, float c, float *t0, float *t1)
{
    float discriminant = b * b - a * c;
    if (!(discriminant >= 0.0f)) return 0;
    float q = -(b + copysign(sqrt(discriminant), b));
    if (a == 0.0f) {
        if (b == 0.0f) return 0;
        *t0 = *t1 = -0.5f * c / b;
        return 1;
    }
    float r0 = q / a, r1 = q != 0.0f ? c / q : r0;
    *t0 = fmin(r0, r1);
    *t1 = fmax(r0, r1);
    return 1;
}

/* The nearest point of the segment's surface along origin + t·direction, t ∈ (t_min, t_max). */
inline CurveHit intersect_curve_segment(float3 origin, float3 direction, float t_min, float t_max, float3 a,
                                        float ra, float3 b, float rb)
{
    CurveHit hit;
    hit.t = INFINITY;
    float3 axis = b - a;
    float l = length(axis);
    if (!(l > fabs(ra - rb))) return hit;
    float3 w = axis / l;
    float s = (ra - rb) / l, c2 = 1.0f - s * s;
    float y_a = ra * s, y_b = l + rb * s;  /* where the cone touches each sphere */
    float3 oa = origin - a;
    float y0 = dot(oa, w), dy = dot(direction, w), od = dot(oa, direction), oo = dot(oa, oa);
    float best = t_max;
    int part = -1;  /* 0: cone, 1: sphere a, 2: sphere b */
    /* Cone: (|q|² − y²) cos²φ = (ra − y sin φ)² on the nappe where ra − y sin φ ≥ 0, q = oa + t d. */
    float t0, t1;
    if (curve_roots(c2 - dy * dy, c2 * od - y0 * dy + ra * s * dy, c2 * oo - y0 * y0 - ra * ra + 2.0f * ra * s * y0,
                    &t0, &t1)) {
        float roots[2] = {t0, t1};
        for (int i = 0; i < 2; ++i) {
            float t = roots[i], y = y0 + t * dy;
            if (t > t_min && t < best && y >= y_a && y <= y_b && ra - y * s >= 0.0f) {
                best = t;
                part = 0;
            }
        }
    }
    /* The end spheres, each outside the cone's reach: |q − centre|² = r², via the ray's closest approach. */
    for (int k = 0; k < 2; ++k) {
        float3 oc = k == 0 ? oa : origin - b;
        float r = k == 0 ? ra : rb;
        float along = dot(oc, direction);
        float3 closest = oc - along * direction;
        float d2 = r * r - dot(closest, closest);
        if (!(d2 >= 0.0f)) continue;
        float root = sqrt(d2);
        float roots[2] = {-along - root, -along + root};
        for (int i = 0; i < 2; ++i) {
            float t = roots[i], y = y0 + t * dy;
            if (t > t_min && t < best && (k == 0 ? y <= y_a : y >= y_b)) {
                best = t;
                part = k + 1;
            }
        }
    }
    if (part < 0) return hit;
    float3 q = oa + best * direction;
    float y = dot(q, w);
    float3 n;
    if (part == 0) {
        float3 radial = q - y * w;
        float x = length(radial);
        n = (x > 0.0f ? radial / x : (float3)(0.0f)) * sqrt(c2) + w * s;
        hit.u = clamp((y - y_a) / (l * c2), 0.0f, 1.0f);
    } else {
        n = part == 1 ? q : q - axis;
        hit.u = part == 1 ? 0.0f : 1.0f;
    }
    hit.n = normalize(n);
    hit.w = w;
    hit.t = best;
    float3 wo = -direction;
    float3 across = cross(hit.n, w);
    float across_length = length(across);
    float3 wo_normal_plane = wo - dot(wo, w) * w;
    float plane_length = length(wo_normal_plane);
    hit.h = across_length > 0.0f && plane_length > 0.0f
                ? clamp(-dot(wo, across) / (across_length * plane_length), -1.0f, 1.0f)
                : 0.0f;
    return hit;
}

#endif
