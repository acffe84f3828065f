/* Rays and the offsets that keep a spawned ray from re-hitting the surface it leaves. */
#ifndef SPECTRACE_RAY_CL
#define SPECTRACE_RAY_CL

typedef struct {
    float3 origin;
    float3 direction;  /* unit length */
} Ray;

inline float max_abs_component(float3 v)
{
    float3 a = fabs(v);
    return fmax(a.x, fmax(a.y, a.z));
}

/* Move p off its surface along the geometric normal, to the side `toward` points to. The step grows with the
 * coordinates' magnitude because float spacing does. */
inline float3 offset_ray_origin(float3 p, float3 geometric_normal, float3 toward)
{
    float step = 1.0e-5f * (1.0f + max_abs_component(p));
    float side = dot(geometric_normal, toward) >= 0.0f ? step : -step;
    return p + side * geometric_normal;
}

#endif
