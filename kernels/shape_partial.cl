/* Partial analytic shapes (pbrt-v4's Sphere, Disk and Cylinder with phimax, zmin/zmax and innerradius; pbrt-v4
 * shapes.h, Pharr, Jakob, Humphreys, "Physically Based Rendering", 4th ed., ch. 6.2-6.4): the whole shape of
 * shapes.cl cut to the azimuths φ in [0, phi_max] and, for the sphere, the heights z in [cut_min, cut_max], for the
 * disk the radii r in [cut_min, 1] (object space, AnalyticShape's units). A shape is partial when phi_max > 0
 * (AnalyticShape.phi_max, radians); whole ones leave it 0 and never reach this file.
 *
 * Intersection: the quadric's two roots, nearest first; a root whose point is cut away gives way to the far one
 * (the ray sees the inside of a cut sphere or cylinder). Texture coordinates: with pbrt_uv, pbrt-v4's own
 * (u = φ/φmax; sphere v = (θ − θ(zmin)) / (θ(zmax) − θ(zmin)), disk v = (1 − r)/(1 − r_inner), cylinder v = z);
 * otherwise the whole shape's (Mitsuba 3's, shapes.cl), the cut-outs simply missing. Area sampling is uniform over
 * the partial surface (z uniform on the sphere's band, Archimedes; r² uniform on the annulus; φ uniform), unlike
 * pbrt-v4's, which samples the whole shape. Units: object space; phi_max in radians. */
#ifndef SPECTRACE_SHAPE_PARTIAL_CL
#define SPECTRACE_SHAPE_PARTIAL_CL

/* A point's parameters (φ in radians, and q: θ for the sphere, r for the disk, z for the cylinder) as the shape's
 * texture coordinates, with their scales: u or v = scale · parameter + offset. */
typedef struct {
    float phi_scale;  /* d(coordinate of φ)/dφ */
    float q_scale;    /* d(coordinate of q)/dq */
    float q_offset;
    int phi_in_v;     /* 1: φ is v (the Mitsuba disk's (r, φ/2π)); else u */
} PartialUvMap;

inline PartialUvMap partial_uv_map(__global const AnalyticShape *s)
{
    PartialUvMap m;
    m.phi_in_v = s->type == SHAPE_DISK && !s->pbrt_uv;
    m.phi_scale = s->pbrt_uv ? 1.0f / s->phi_max : 1.0f / SHAPE_TWO_PI;
    m.q_scale = 1.0f;
    m.q_offset = 0.0f;
    if (s->type == SHAPE_SPHERE) {
        if (s->pbrt_uv) {
            float theta_min = acos(clamp(s->cut_min, -1.0f, 1.0f)), theta_max = acos(clamp(s->cut_max, -1.0f, 1.0f));
            m.q_scale = 1.0f / (theta_max - theta_min);
            m.q_offset = -theta_min * m.q_scale;
        } else {
            m.q_scale = 1.0f / SHAPE_PI;
        }
    } else if (s->type == SHAPE_DISK && s->pbrt_uv) {
        m.q_scale = -1.0f / (1.0f - s->cut_min);
        m.q_offset = 1.0f / (1.0f - s->cut_min);
    }
    return m;
}

inline float2 partial_uv(PartialUvMap m, float phi, float q)
{
    float a = m.phi_scale * phi, b = m.q_scale * q + m.q_offset;
    return m.phi_in_v ? (float2)(b, a) : (float2)(a, b);
}

/* φ (x) and q (y) back from texture coordinates. */
inline float2 partial_parameters(PartialUvMap m, float2 uv)
{
    float a = m.phi_in_v ? uv.y : uv.x, b = m.phi_in_v ? uv.x : uv.y;
    return (float2)(a / m.phi_scale, (b - m.q_offset) / m.q_scale);
}

/* φ of (x, y) in [0, 2π). */
inline float partial_azimuth(float x, float y)
{
    float phi = atan2(y, x);
    return phi < 0.0f ? phi + SHAPE_TWO_PI : phi;
}

/* Whether the object-space point p of the whole shape is kept; its parameters in *phi, *q. */
inline int partial_keeps(__global const AnalyticShape *s, float3 p, float *phi, float *q)
{
    *phi = partial_azimuth(p.x, p.y);
    if (*phi > s->phi_max) return 0;
    if (s->type == SHAPE_SPHERE) {
        *q = acos(clamp(p.z, -1.0f, 1.0f));
        return p.z >= s->cut_min && p.z <= s->cut_max;
    }
    if (s->type == SHAPE_DISK) {
        *q = sqrt(p.x * p.x + p.y * p.y);
        return *q >= s->cut_min && *q <= 1.0f;
    }
    *q = p.z;
    return p.z >= 0.0f && p.z <= 1.0f;
}

/* intersect_shape for a partial shape. */
inline float intersect_partial_shape(__global const AnalyticShape *s, float3 origin, float3 direction, float t_max,
                                     float2 *uv)
{
    float roots[2];
    int count;
    float3 o = origin, d = direction;
    if (s->type == SHAPE_SPHERE) {  /* in world space, as the whole sphere (shapes.cl) */
        float3 f = origin - s->sphere.xyz;
        float radius = s->sphere.w;
        float b = dot(f, direction);
        float3 perpendicular = f - b * direction;
        float discriminant = radius * radius - dot(perpendicular, perpendicular);
        if (discriminant < 0.0f) return t_max;
        count = 2 * stable_roots(1.0f, b, dot(f, f) - radius * radius, sqrt(discriminant), &roots[0], &roots[1]);
    } else {
        o = shape_point_to_object(s, origin);
        d = shape_vector_to_object(s, direction);
        if (s->type == SHAPE_DISK) {
            if (d.z == 0.0f) return t_max;
            roots[0] = -o.z / d.z;
            count = 1;
        } else {
            float a = d.x * d.x + d.y * d.y;
            float b = o.x * d.x + o.y * d.y;
            float cross_z = o.x * d.y - o.y * d.x;
            float discriminant = a - cross_z * cross_z;
            if (!(discriminant >= 0.0f)) return t_max;
            count = 2 * stable_roots(a, b, o.x * o.x + o.y * o.y - 1.0f, sqrt(discriminant), &roots[0], &roots[1]);
        }
    }
    PartialUvMap m = partial_uv_map(s);
    for (int k = 0; k < count; ++k) {
        float t = roots[k];
        if (!(t > 0.0f && t < t_max)) continue;
        float3 p = s->type == SHAPE_SPHERE ? normalize(shape_point_to_object(s, origin + t * direction)) : o + t * d;
        float phi, q;
        if (!partial_keeps(s, p, &phi, &q)) continue;
        *uv = partial_uv(m, phi, q);
        return t;
    }
    return t_max;
}

/* The object-space point, normal and tangents along the texture coordinates at the shape's uv. */
inline void partial_shape_local(__global const AnalyticShape *s, float2 shape_uv, float3 *point, float3 *n_local,
                                float3 *dpdu, float3 *dpdv)
{
    PartialUvMap m = partial_uv_map(s);
    float2 parameters = partial_parameters(m, shape_uv);
    float phi = parameters.x, q = parameters.y;
    float cos_phi = cos(phi), sin_phi = sin(phi);
    float3 dp_dphi, dp_dq;
    if (s->type == SHAPE_SPHERE) {
        float cos_theta = cos(q), sin_theta = sin(q);
        *point = (float3)(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta);
        *n_local = *point;
        dp_dphi = (float3)(-point->y, point->x, 0.0f);
        dp_dq = (float3)(cos_theta * cos_phi, cos_theta * sin_phi, -sin_theta);
    } else if (s->type == SHAPE_DISK) {
        *point = (float3)(q * cos_phi, q * sin_phi, 0.0f);
        *n_local = (float3)(0.0f, 0.0f, 1.0f);
        dp_dphi = (float3)(-point->y, point->x, 0.0f);
        dp_dq = (float3)(cos_phi, sin_phi, 0.0f);
    } else {
        *point = (float3)(cos_phi, sin_phi, q);
        *n_local = (float3)(cos_phi, sin_phi, 0.0f);
        dp_dphi = (float3)(-sin_phi, cos_phi, 0.0f);
        dp_dq = (float3)(0.0f, 0.0f, 1.0f);
    }
    float3 along_phi = dp_dphi / m.phi_scale, along_q = dp_dq / m.q_scale;
    *dpdu = m.phi_in_v ? along_q : along_phi;
    *dpdv = m.phi_in_v ? along_phi : along_q;
}

/* shape_sample_uv for a partial shape: uniform over its object-space area (object_area). */
inline float2 partial_shape_sample_uv(__global const AnalyticShape *s, float2 u)
{
    float phi = u.y * s->phi_max, q;
    if (s->type == SHAPE_SPHERE) {
        q = acos(clamp(s->cut_min + u.x * (s->cut_max - s->cut_min), -1.0f, 1.0f));
    } else if (s->type == SHAPE_DISK) {
        q = sqrt(s->cut_min * s->cut_min + u.x * (1.0f - s->cut_min * s->cut_min));
    } else {
        q = u.x;
    }
    return partial_uv(partial_uv_map(s), phi, q);
}

#endif
