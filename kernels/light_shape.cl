/* An emitting analytic shape other than a sphere, a disk or a cylinder (shapes.cl; Light.triangle: its index among
 * the scene's analytic shapes), sampled uniformly over its area through its parametrisation (shape_sample_uv, with
 * the area density shape_area_pdf), an area light (light_area.cl): radiance W/(m² sr nm). Also the parts every
 * emitting analytic shape shares (light_sphere.cl samples by area too, seen from inside or on the sphere). */
#ifndef SPECTRACE_LIGHT_SHAPE_CL
#define SPECTRACE_LIGHT_SHAPE_CL

#include "light_area.cl"

/* Ends next-event estimation toward the point q (normal n, texture coordinates uv) of an emitting analytic shape
 * seen from p: pdf_solid_angle its density per steradian, or negative when q was drawn by area with the area
 * density in s->pdf, which is then converted. Returns 0 when the sample carries no light. */
inline int analytic_light_arriving(__global const Light *light, const LightBuffers *buffers,
                                   const SampledWavelengths *w, float3 p, float3 q, float3 n, float2 uv,
                                   float pdf_solid_angle, LightSample *s)
{
    float d = area_light_toward(p, q, n, s);
    if (!(d > 0.0f)) return 0;
    s->arriving = area_light_emitted(light, &buffers->textures, w, n, -s->wi, uv);
    if (pdf_solid_angle < 0.0f) {
        float abs_cos = fabs(dot(n, s->wi));
        pdf_solid_angle = abs_cos > 0.0f ? s->pdf * d * d / abs_cos : 0.0f;
    }
    s->pdf = light->pmf * pdf_solid_angle;
    return s->pdf > 0.0f && isfinite(s->pdf);
}

/* Next-event estimation from p: a point uniform over the shape's area. */
inline int light_shape_sample_li(__global const Light *light, const LightBuffers *buffers,
                                 const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    __global const AnalyticShape *shape = &buffers->shapes[light->triangle];
    float2 uv = shape_sample_uv(shape, u);
    ShapeSurface g = shape_surface(shape, uv);
    s->pdf = shape_area_pdf(shape, g.area_stretch);
    return analytic_light_arriving(light, buffers, w, p, g.p, g.n, uv, -1.0f, s);
}

/* Solid-angle density (pick included) with which light_shape_sample_li reaches p (normal n, texture coordinates
 * uv, seen along -wo from `from`). */
inline float light_shape_pdf_li(__global const Light *light, __global const AnalyticShape *shapes, float3 from,
                                float3 p, float3 n, float3 wo, float2 uv)
{
    __global const AnalyticShape *shape = &shapes[light->triangle];
    float abs_cos = fabs(dot(n, wo));
    if (!(abs_cos > 0.0f)) return 0.0f;
    float d = distance(from, p);
    return light->pmf * shape_area_pdf(shape, shape_surface(shape, uv).area_stretch) * d * d / abs_cos;
}

/* The origin of a light path: a point uniform over the shape's area, its normal and texture coordinates; returns
 * its area density (1/m², pick not included). */
inline float light_shape_sample_point(__global const Light *light, const LightBuffers *buffers, float2 u, float3 *p,
                                      float3 *n, float2 *uv)
{
    __global const AnalyticShape *shape = &buffers->shapes[light->triangle];
    *uv = shape_sample_uv(shape, u);
    ShapeSurface g = shape_surface(shape, *uv);
    *p = g.p;
    *n = g.n;
    return shape_area_pdf(shape, g.area_stretch);
}

/* The area density (pick included) with which a light path starts at the shape's point of texture coordinates
 * uv. */
inline float light_shape_pdf_point(__global const Light *light, __global const AnalyticShape *shapes, float2 uv)
{
    __global const AnalyticShape *shape = &shapes[light->triangle];
    return light->pmf * shape_area_pdf(shape, shape_surface(shape, uv).area_stretch);
}

#endif
