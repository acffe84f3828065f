/* Light leaving the lights: a first ray of a light path drawn from every light type, with the power it carries,
 * for integrators that start paths at the lights (light tracing, kernels/light_tracer.cl). Next-event estimation
 * samples lights from a point instead (lights.cl); both use the same Light rows and pick probabilities.
 *
 * A sample's `weight` is Le·|cos θ| / (pmf · p_A(x) · p_ω(ω)) in the light's spectral units times m² sr: the flux
 * (W/nm) the ray carries, per wavelength. Per type (Veach 1997, sec. 8.1; pbrt-v4's Light::SampleLe):
 * - emitting triangles and analytic shapes: a point uniform over the area, a cosine-distributed direction on the
 *   emitting side (either side, each with probability ½, when two-sided): weight Le·π·area/pmf (doubled two-sided);
 *   the point itself is a path vertex the camera can see (first_vertex);
 * - point: uniform over the sphere, weight I·4π/pmf; spot: uniform within the cutoff cone, weight
 *   I·falloff(θ)·2π(1 − cos θ_cutoff)/pmf;
 * - distant: a direction fixed, the origin uniform on a disk of the scene's bounding sphere's radius R facing it,
 *   outside the sphere: weight E·πR²/pmf;
 * - environment (constant or map): the direction toward the environment drawn as next-event estimation draws it
 *   (pdf p_ω, pick included), the origin on that direction's disk as for the distant light: weight L·πR²/p_ω.
 * Point, spot, distant and environment lights have no vertex the pinhole camera could see (a point on a delta
 * position or at infinity), as for path tracing. */
#ifndef SPECTRACE_LIGHT_EMISSION_CL
#define SPECTRACE_LIGHT_EMISSION_CL

#include "lights.cl"
#include "ray.cl"

typedef struct {
    Ray ray;            /* leaves the light (offset off its surface) */
    float4 weight;      /* W/nm carried, per wavelength (see above) */
    int first_vertex;   /* 1: the light point is a surface vertex (area lights), connectable to the camera */
    float3 point;       /* that vertex */
    float3 normal;      /* its geometric normal (the winding's front) */
    float2 uv;          /* its texture coordinates, for an emission texture */
    float pdf_area;     /* pmf · p_A(point), 1/m² */
} EmissionSample;

/* A direction uniform within the cone of half-angle acos(cos_max) about axis. */
inline float3 sample_uniform_cone_about(float3 axis, float cos_max, float2 u)
{
    float cos_theta = 1.0f - u.x * (1.0f - cos_max);
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float2 circle = sin_theta * cos_sin_turns(u.y);
    float3 t, b;
    orthonormal_basis(axis, &t, &b);
    return circle.x * t + circle.y * b + cos_theta * axis;
}

/* A point of the disk of radius r about centre, perpendicular to the unit direction d. */
inline float3 sample_disk_across(float3 centre, float3 d, float r, float2 u)
{
    float3 t, b;
    orthonormal_basis(d, &t, &b);
    float2 circle = sqrt(u.x) * r * cos_sin_turns(u.y);
    return centre + circle.x * t + circle.y * b;
}

/* Emission from light `light` (picked with light->pmf), from two 2D draws u_position and u_direction.
 * scene_sphere: the scene's bounding sphere, centre (xyz) and radius (w). Returns 0 when nothing leaves. */
inline int sample_emission(__global const Light *light, const LightBuffers *buffers, const SampledWavelengths *w,
                           float4 scene_sphere, float2 u_position, float2 u_direction, EmissionSample *e)
{
    e->first_vertex = 0;
    e->uv = (float2)(0.0f);
    if (!(light->pmf > 0.0f)) return 0;
    if (LIGHT_ON_SURFACE(light)) {
        float3 p, n;
        float pdf_area;
        if (LIGHT_IS(light, LIGHT_TRIANGLE)) {
            float2 b12 = sample_triangle_uniform(u_position);
            p = triangle_point(buffers->triangle_vertices, light->triangle, b12);
            n = triangle_normal(buffers->triangle_vertices, light->triangle);
            e->uv = triangle_uv(buffers->triangle_uvs, light->triangle, b12);
            pdf_area = 1.0f / light->area;
        } else {
            __global const AnalyticShape *shape = &buffers->shapes[light->triangle];
            e->uv = shape_sample_uv(shape, u_position);
            ShapeSurface g = shape_surface(shape, e->uv);
            p = g.p;
            n = g.n;
            pdf_area = shape_area_pdf(shape, g.area_stretch);
        }
        if (!(pdf_area > 0.0f) || !isfinite(pdf_area)) return 0;
        float side = 1.0f, sides = 1.0f;
        if (light->two_sided) {
            sides = 2.0f;
            if (u_direction.x < 0.5f) {
                side = -1.0f;
                u_direction.x *= 2.0f;
            } else {
                u_direction.x = fmin(2.0f * u_direction.x - 1.0f, 0x1.fffffep-1f);
            }
        }
        float3 d = sample_cosine_about(side * n, u_direction);
        float cos_theta = dot(side * n, d);
        if (!(cos_theta > 0.0f)) return 0;
        float4 radiance = area_light_emitted(light, &buffers->textures, w, n, d, e->uv);
        e->weight = radiance * (PI_F * sides / (light->pmf * pdf_area));
        e->ray.origin = offset_ray_origin(p, n, d);
        e->ray.direction = d;
        e->first_vertex = 1;
        e->point = p;
        e->normal = n;
        e->pdf_area = light->pmf * pdf_area;
        return any(e->weight != (float4)(0.0f));
    }
    if (LIGHT_IS(light, LIGHT_POINT) || LIGHT_IS(light, LIGHT_SPOT)) {
        float3 d;
        float4 intensity = light_spectrum(light, buffers->spectra, w);
        if (LIGHT_IS(light, LIGHT_SPOT)) {
            float3 axis = light->direction.xyz;
            d = sample_uniform_cone_about(axis, light->cos_cutoff, u_direction);
            float solid_angle = TWO_PI * (1.0f - light->cos_cutoff);
            intensity *= spot_falloff(light, dot(d, axis)) * solid_angle;
            if (SCENE_HAS_LIGHT_IMAGES && light->texture != NO_TEXTURE) {
                intensity *= spot_slide(light, &buffers->textures, w, d);
            }
        } else {
            d = sample_uniform_sphere(u_direction);
            intensity *= 4.0f * PI_F;
        }
        e->weight = intensity / light->pmf;
        e->ray.origin = light->position.xyz;
        e->ray.direction = d;
        return any(e->weight != (float4)(0.0f));
    }
    float3 travel;
    float4 per_area;  /* irradiance on a plane across the beam, divided by the direction's pdf */
    if (LIGHT_IS(light, LIGHT_DISTANT)) {
        travel = light->direction.xyz;
        per_area = light_spectrum(light, buffers->spectra, w) / light->pmf;
    } else {
#if !SCENE_HAS_ENVIRONMENT
        return 0;
#else
        float pdf;
        float3 toward = environment_sample(light, buffers->map_cdf, u_direction, &pdf);
        if (!(pdf > 0.0f)) return 0;
        travel = -toward;
        per_area = environment_radiance(light, buffers->spectra, buffers->texels, w, toward) / pdf;
#endif
    }
    float r = scene_sphere.w;
    e->ray.origin = sample_disk_across(scene_sphere.xyz - r * travel, travel, r, u_position);
    e->ray.direction = travel;
    e->weight = per_area * (PI_F * r * r);
    return any(e->weight != (float4)(0.0f));
}

#endif
