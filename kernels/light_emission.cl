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
        float pdf_area = 0.0f;
#define X(name, NAME) \
        if (LIGHT_IS(light, LIGHT_##NAME)) pdf_area = light_##name##_sample_point(light, buffers, u_position, &p, &n, &e->uv);
        LIGHT_LIST_AREA(X)
#undef X
        if (!(pdf_area > 0.0f) || !isfinite(pdf_area)) return 0;
        float side;
        float3 d = area_light_sample_direction(light, n, u_direction, &side);
        float sides = light->two_sided ? 2.0f : 1.0f;
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
    if (LIGHT_KIND_POSITION(light)) {
        float3 d = (float3)(0.0f);
        float4 intensity = (float4)(0.0f);
#define X(name, NAME) \
        if (LIGHT_IS(light, LIGHT_##NAME)) intensity = light_##name##_sample_le(light, buffers, w, u_direction, &d);
        LIGHT_LIST_POSITION(X)
#undef X
        e->weight = intensity / light->pmf;
        e->ray.origin = light->position.xyz;
        e->ray.direction = d;
        return any(e->weight != (float4)(0.0f));
    }
    /* At infinity: the direction toward the light (a distant light's own, at its pick probability) and the
     * irradiance across the beam over that direction's density. */
    float3 travel = (float3)(0.0f);
    float4 per_area = (float4)(0.0f);
#define X(name, NAME)                                                                                   \
    if (LIGHT_IS(light, LIGHT_##NAME)) {                                                                \
        float pdf;                                                                                      \
        float3 toward = light_##name##_sample_wi(light, buffers->map_cdf, u_direction, &pdf);          \
        if (!(pdf > 0.0f)) return 0;                                                                    \
        travel = -toward;                                                                               \
        per_area = light_##name##_radiance(light, buffers->spectra, buffers->texels, w, toward) / pdf; \
    }
    LIGHT_LIST_INFINITE(X)
#undef X
    float r = scene_sphere.w;
    e->ray.origin = sample_disk_across(scene_sphere.xyz - r * travel, travel, r, u_position);
    e->ray.direction = travel;
    e->weight = per_area * (PI_F * r * r);
    return any(e->weight != (float4)(0.0f));
}

#endif
