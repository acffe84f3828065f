/* Test harness: a scene's lights seen both ways a path tracer sees them, at four fixed wavelengths:
 * - light_samples: next-event estimation's sample from given points, as direct_lighting.cl draws it: a light picked
 *   by the scene's light CDF and sampled (lights.cl pick_light_reusing, sample_light) from one 2D number: the
 *   direction, its pdf (pick probability included), the light point and the radiance (or, for delta lights, the
 *   irradiance) arriving;
 * - light_hits: what a BSDF-sampled ray meets, as path_tracer.cl's path_segment weighs it for multiple importance
 *   sampling: at an emitter, emitter_hit_pdf from the ray's origin and vertex_emission; on a miss, the
 *   environment's environment_pdf and environment_radiance. Kept to the same calls, so a change there shows here;
 * - light_emissions: the first ray of a light path, as light_tracer.cl draws it (light_emission.cl
 *   sample_emission after the same pick), with the flux it carries.
 * Directions are unit and world-space; points need no ray offset (tests place them in free space). Built without
 * scene-feature defines, so one program serves every light type (kernels/scene_features.h). */
#include "kernel_entry.h"
#include "path_state.cl"
#include "light_emission.cl"

inline SampledWavelengths harness_wavelengths(__global const float *lambda)
{
    return fixed_wavelengths((float4)(lambda[0], lambda[1], lambda[2], lambda[3]));
}

/* wi_pdf: (wi, pdf); target: (the light point, its distance; INFINITY for distant and environment lights);
 * arriving: the sample's radiance or delta irradiance; flags: bit 0 the sampler succeeded, bit 1 a delta light,
 * the bits above the index of the light picked. */
KERNEL void light_samples(SCENE_KERNEL_PARAMS, __global const float *lambda,
                          __global const float4 *points, __global const float2 *u, __global float4 *wi_pdf,
                          __global float4 *target, __global float4 *arriving, __global int *flags, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = harness_wavelengths(lambda);
    LightBuffers buffers = light_buffers(&scene);
    LightSample s;
    s.pdf = 0.0f;
    s.is_delta = 0;
    float2 v = u[i];
    int picked = pick_light_reusing(light_cdf, params->light_count, &v);
    int ok = sample_light(&scene.lights[picked], &buffers, &w, points[i].xyz, v, &s);
    wi_pdf[i] = ok ? (float4)(s.wi, s.pdf) : (float4)(0.0f);
    target[i] = ok ? (float4)(s.point, s.distance) : (float4)(0.0f);
    arriving[i] = ok ? s.arriving : (float4)(0.0f);
    flags[i] = (ok ? 1 : 0) | (s.is_delta ? 2 : 0) | (picked << 2);
}

/* pdf: the light's solid-angle pdf (pick included) of the ray's direction, as the path tracer's MIS weight takes
 * it; emitted: the radiance the ray brings back; light: the light's index, -1 when it meets none; t: the hit's
 * distance, INFINITY on a miss. */
KERNEL void light_hits(SCENE_KERNEL_PARAMS, __global const float *lambda, __global const float4 *origins,
                       __global const float4 *directions, __global float *pdf, __global float4 *emitted,
                       __global int *light, __global float *t, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = harness_wavelengths(lambda);
    Ray ray;
    ray.origin = origins[i].xyz;
    ray.direction = directions[i].xyz;
    pdf[i] = 0.0f;
    emitted[i] = (float4)(0.0f);
    light[i] = -1;
    t[i] = INFINITY;
    Hit hit = trace_scene(&scene, ray, INFINITY, 0);
    if (hit.triangle < 0) {
        int env = params->environment_light;
        if (SCENE_HAS_ENVIRONMENT && env >= 0) {
            pdf[i] = environment_pdf(&scene.lights[env], scene.map_cdf, ray.direction);
            emitted[i] = environment_radiance(&scene.lights[env], scene.spectra, scene.texels, &w, ray.direction);
            light[i] = env;
        }
        return;
    }
    t[i] = hit.t;
    PathVertex v = path_vertex(&scene, hit, ray);
    if (v.info.light < 0) return;
    pdf[i] = emitter_hit_pdf(&scene.lights[v.info.light], scene.shapes, ray.origin, v.p, v.n, v.wo, hit.b12);
    emitted[i] = vertex_emission(&scene, &w, &v, hit);
    light[i] = v.info.light;
}

/* weight: the flux (W/nm) the ray carries, 0 when nothing leaves; u: (pick and position, direction) numbers.
 * scene_sphere: the bounding sphere distant and environment lights shine across, centre (xyz) and radius (w). */
KERNEL void light_emissions(SCENE_KERNEL_PARAMS, __global const float *lambda, float4 scene_sphere,
                            __global const float4 *u, __global float4 *weight, int count)
{
    int i = get_global_id(0);
    if (i >= count) return;
    Scene scene = SCENE_FROM_KERNEL_PARAMS;
    SampledWavelengths w = harness_wavelengths(lambda);
    LightBuffers buffers = light_buffers(&scene);
    float2 u_pick = u[i].xy;
    __global const Light *light = &scene.lights[pick_light_reusing(light_cdf, params->light_count, &u_pick)];
    EmissionSample e;
    weight[i] = sample_emission(light, &buffers, &w, scene_sphere, u_pick, u[i].zw, &e) ? e.weight : (float4)(0.0f);
}
