/* An emitting analytic sphere (shapes.cl; Light.triangle: its index among the scene's analytic shapes,
 * Light.position its centre (xyz) and radius (w)), an area light (light_area.cl): radiance W/(m² sr nm). Seen from
 * outside, next-event estimation samples the cone of directions it subtends (pbrt-v4's Sphere::Sample from a
 * reference point; sample_sphere_cone), far less noisy than by area at a distance; from inside or on it, and as the
 * origin of light paths, it is sampled by area as any analytic shape (light_shape.cl). */
#ifndef SPECTRACE_LIGHT_SPHERE_CL
#define SPECTRACE_LIGHT_SPHERE_CL

#include "light_shape.cl"

/* Texture coordinates of the sphere point whose outward world normal is n. */
inline float2 sphere_uv_of_normal(__global const AnalyticShape *shape, float3 n)
{
    float3 object_point = normalize(shape_vector_to_object(shape, n));
    return shape_uv_from_mitsuba(shape, (float2)(shape_azimuth_turns(object_point.x, object_point.y),
                    atan2(sqrt(object_point.x * object_point.x + object_point.y * object_point.y), object_point.z) * (1.0f / SHAPE_PI)));
}

/* Next-event estimation from p: by the cone the sphere subtends when p is outside, otherwise by area. */
inline int light_sphere_sample_li(__global const Light *light, const LightBuffers *buffers,
                                  const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    float one_minus_cos = sphere_cone_one_minus_cos(light->position.xyz, light->position.w, p);
    if (!(one_minus_cos > 0.0f)) return light_shape_sample_li(light, buffers, w, p, u, s);
    __global const AnalyticShape *shape = &buffers->shapes[light->triangle];
    float3 n;
    float pdf_solid_angle = 0.0f;
    float3 q = sample_sphere_cone(light->position.xyz, light->position.w, p, u, &n, &pdf_solid_angle);
    float2 uv = sphere_uv_of_normal(shape, n);
    if (shape->flip_normals) n = -n;
    return analytic_light_arriving(light, buffers, w, p, q, n, uv, pdf_solid_angle, s);
}

/* Solid-angle density (pick included) with which light_sphere_sample_li reaches p (normal n, texture coordinates
 * uv, seen along -wo from `from`). */
inline float light_sphere_pdf_li(__global const Light *light, __global const AnalyticShape *shapes, float3 from,
                                 float3 p, float3 n, float3 wo, float2 uv)
{
    float one_minus_cos = sphere_cone_one_minus_cos(light->position.xyz, light->position.w, from);
    if (one_minus_cos > 0.0f) return light->pmf / (SHAPE_TWO_PI * one_minus_cos);
    return light_shape_pdf_li(light, shapes, from, p, n, wo, uv);
}

inline float light_sphere_sample_point(__global const Light *light, const LightBuffers *buffers, float2 u, float3 *p,
                                       float3 *n, float2 *uv)
{
    return light_shape_sample_point(light, buffers, u, p, n, uv);
}

inline float light_sphere_pdf_point(__global const Light *light, __global const AnalyticShape *shapes, float2 uv)
{
    return light_shape_pdf_point(light, shapes, uv);
}

#endif
