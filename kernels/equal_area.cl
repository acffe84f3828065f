/* Clarberg's equal-area octahedral mapping between the unit square and the sphere of directions (P. Clarberg,
 * "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", Journal of Graphics Tools 13(3), 2008; pbrt-v4's
 * EqualAreaSquareToSphere, EqualAreaSphereToSquare): every part of the square maps to a solid angle 4π times its
 * area. The square [0, 1]² is taken to [-1, 1]² as (u, v); the diamond |u| + |v| <= 1 holds the hemisphere z >= 0,
 * the four corners outside it the other one. On the diamond's edge of "radius" r = 1 − |1 − (|u| + |v|)| (0 at the
 * centre and at the corners, 1 on the diamond), z = ±(1 − r²) (so the area below any r grows as r², the square's
 * own area), and the azimuth in the quadrant is a linear function of the position along that edge,
 * φ = (π/4)(1 + (|v| − |u|)/r); the direction is (r √(2 − r²) cos φ, r √(2 − r²) sin φ, z) with the signs of
 * (u, v). Used by the equal-area camera (camera_equal_area.cl) and the goniometric light (light_goniometric.cl). */
#ifndef SPECTRACE_EQUAL_AREA_CL
#define SPECTRACE_EQUAL_AREA_CL

#define EQUAL_AREA_PI 3.14159265358979f

/* The unit direction of the point p of the square [0, 1]². */
inline float3 equal_area_square_to_sphere(float2 p)
{
    float u = 2.0f * p.x - 1.0f, v = 2.0f * p.y - 1.0f;
    float a = fabs(u), b = fabs(v);
    float inside = 1.0f - (a + b);  /* > 0 within the diamond: the upper hemisphere */
    float r = 1.0f - fabs(inside);
    float phi = (r > 0.0f ? (b - a) / r + 1.0f : 1.0f) * (0.25f * EQUAL_AREA_PI);
    float z = copysign(1.0f - r * r, inside);
    float ring = r * sqrt(fmax(0.0f, 2.0f - r * r));
    return (float3)(copysign(cos(phi) * ring, u), copysign(sin(phi) * ring, v), z);
}

/* The point of [0, 1]² whose direction is the unit vector d (equal_area_square_to_sphere's inverse). */
inline float2 equal_area_sphere_to_square(float3 d)
{
    float a = fabs(d.x), b = fabs(d.y);
    float r = sqrt(fmax(0.0f, 1.0f - fabs(d.z)));
    /* The position along the diamond's edge, 0 on the u axis to 1 on the v axis: φ / (π/2) in the quadrant. */
    float t = (a > 0.0f || b > 0.0f) ? atan2(b, a) * (2.0f / EQUAL_AREA_PI) : 0.0f;
    float along_v = r * t, along_u = r - r * t;  /* |v|, |u| in the upper hemisphere's diamond */
    if (d.z < 0.0f) {  /* the lower hemisphere: the same edge mirrored out into the corner */
        float u_lower = 1.0f - along_v, v_lower = 1.0f - along_u;
        along_u = u_lower;
        along_v = v_lower;
    }
    return (float2)(0.5f * (copysign(along_u, d.x) + 1.0f), 0.5f * (copysign(along_v, d.y) + 1.0f));
}

#endif
