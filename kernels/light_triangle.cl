/* An emitting triangle of an area light (light_area.cl; Light.triangle: its slot in the triangle arrays), sampled
 * uniformly over its area (pdf 1/Light.area per m², Light.area > 0) on both the light's and the eye's side.
 * Radiance W/(m² sr nm). The triangle lookups here (its point, winding normal and texture coordinates at
 * barycentrics) are also those of the scene's hits (scene.cl). */
#ifndef SPECTRACE_LIGHT_TRIANGLE_CL
#define SPECTRACE_LIGHT_TRIANGLE_CL

#include "light_area.cl"

/* The unit geometric normal of the winding, which the host stores in the w of the triangle's three vertices
 * (render/scene_buffers.py). */
inline float3 triangle_normal(__global const float4 *triangle_vertices, int triangle)
{
    return (float3)(triangle_vertices[3 * triangle].w, triangle_vertices[3 * triangle + 1].w,
                    triangle_vertices[3 * triangle + 2].w);
}

inline float3 triangle_point(__global const float4 *triangle_vertices, int triangle, float2 b12)
{
    float3 v0 = triangle_vertices[3 * triangle].xyz;
    float3 v1 = triangle_vertices[3 * triangle + 1].xyz;
    float3 v2 = triangle_vertices[3 * triangle + 2].xyz;
    return (1.0f - b12.x - b12.y) * v0 + b12.x * v1 + b12.y * v2;
}

inline float2 triangle_uv(__global const float2 *triangle_uvs, int triangle, float2 b12)
{
    return (1.0f - b12.x - b12.y) * triangle_uvs[3 * triangle] + b12.x * triangle_uvs[3 * triangle + 1]
         + b12.y * triangle_uvs[3 * triangle + 2];
}

/* Next-event estimation from p: a point uniform over the triangle. Returns 0 when the sample carries no light. */
inline int light_triangle_sample_li(__global const Light *light, const LightBuffers *buffers,
                                    const SampledWavelengths *w, float3 p, float2 u, LightSample *s)
{
    __global const float4 *triangle_vertices = buffers->triangle_vertices;
    float2 b12 = sample_triangle_uniform(u);
    float3 q = triangle_point(triangle_vertices, light->triangle, b12);
    float3 n_light = triangle_normal(triangle_vertices, light->triangle);
    float d = area_light_toward(p, q, n_light, s);
    if (!(d > 0.0f)) return 0;
    s->arriving = area_light_emitted(light, &buffers->textures, w, n_light, -s->wi,
                                     triangle_uv(buffers->triangle_uvs, light->triangle, b12));
    s->pdf = area_light_pdf(light, d, fabs(dot(n_light, s->wi)));
    return s->pdf > 0.0f;
}

/* Solid-angle density (pick included) with which light_triangle_sample_li reaches p (normal n, seen along -wo
 * from `from`). */
inline float light_triangle_pdf_li(__global const Light *light, __global const AnalyticShape *shapes, float3 from,
                                   float3 p, float3 n, float3 wo, float2 uv)
{
    return area_light_pdf(light, distance(from, p), fabs(dot(n, wo)));
}

/* The origin of a light path: a point uniform over the triangle, its winding normal and texture coordinates;
 * returns its area density (1/m², pick not included). */
inline float light_triangle_sample_point(__global const Light *light, const LightBuffers *buffers, float2 u,
                                         float3 *p, float3 *n, float2 *uv)
{
    float2 b12 = sample_triangle_uniform(u);
    *p = triangle_point(buffers->triangle_vertices, light->triangle, b12);
    *n = triangle_normal(buffers->triangle_vertices, light->triangle);
    *uv = triangle_uv(buffers->triangle_uvs, light->triangle, b12);
    return 1.0f / light->area;
}

/* The area density (pick included) with which a light path starts at the triangle's point of texture coordinates
 * uv: uniform. */
inline float light_triangle_pdf_point(__global const Light *light, __global const AnalyticShape *shapes, float2 uv)
{
    return light->pmf / light->area;
}

/* Whether `light` is an emitting triangle (else an analytic shape's emitter, light_shape.cl): for code outside the
 * lights that needs the surface a sample came from. */
inline int light_is_triangle(__global const Light *light)
{
    return LIGHT_IS(light, LIGHT_TRIANGLE);
}

#endif
