/* The local model (Whitted-style ray tracing): light emitted toward the eye, direct light at every non-specular
 * surface by next-event estimation, and perfect specular reflection/refraction followed recursively. No
 * light bounces diffusely more than once. It walks the same PathState as the global model (path_state.cl). */
#ifndef SPECTRACE_WHITTED_CL
#define SPECTRACE_WHITTED_CL

#include "path_state.cl"
#include "fluorescence.cl"

/* One segment of the local model: the counterpart of path_segment (path_tracer.cl), with the same contract. */
inline int direct_segment(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                          float4 *radiance, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int last_segment = max_segments(params);
    Hit hit = far_clipped(params, s, scene_intersect(scene, s->ray, path_query(sampler, s, QUERY_PATH), rays_traced));
    /* The local model carries only the light a medium does not scatter: its transmittance to the surface. */
    if (s->medium >= 0) {
#if SCENE_HAS_GRID_MEDIA
        if (scene->media[s->medium].grid >= 0) {
            s->throughput *= grid_transmittance(&scene->media[s->medium], scene->spectra, w, s->ray.origin,
                                                s->ray.direction, hit.t, sampler_identity(sampler));
        } else
#endif
        s->throughput *= beer_lambert(medium_sigma_t(&scene->media[s->medium], scene->spectra, w), hit.t);
    }
    if (hit.triangle < 0) {
        int hidden = (params->hide_emitters & HIDE_ENVIRONMENT) && s->segments == 1;  /* the camera's rays see black */
        if (SCENE_HAS_ENVIRONMENT && params->environment_light >= 0 && !hidden) {
            __global const Light *env = &scene->lights[params->environment_light];
            float4 emitted = environment_radiance(env, scene->spectra, scene->texels, w, s->ray.direction);
            *radiance += s->throughput * emitted;
#if FILM_AOVS
            record_camera_emission(scene, w, s, emitted, 1.0f, 0, hit);
#endif
        }
        return 0;
    }
    PathVertex v = path_vertex(scene, hit, s->ray);
    int live;
    if (record_surface_reached(s, &v, hit.t, params, &live)) return live;
    if (v.info.light >= 0) {
        float4 emitted = vertex_emission(scene, w, &v, hit);
        *radiance += s->throughput * emitted;
#if FILM_AOVS
        record_camera_emission(scene, w, s, emitted, 1.0f, &v, hit);
#endif
    }
    if (v.info.material == TRIANGLE_NO_MATERIAL) return cross_null_boundary(s, &v);
    if (s->segments >= last_segment) return 0;
#if SCENE_HAS_FLUORESCENCE
    /* a dye's re-emission of the direct light at λi (its diffuse lobe ends the path), or its base */
    fluorescent_vertex(scene, w, sampler, s, &v);
    w = path_wavelengths(s, w);
#endif

    /* Follow the specular lobes only: a sampled non-specular direction ends the path (its light was counted
     * by next-event estimation), which keeps the specular part unbiased. */
    BSDFSample bs;
    int sampled = light_and_sample_vertex(scene, w, sampler, s, &v, 0, radiance, rays_traced, &bs);
#if FILM_AOVS
    aov_at_bsdf_sample(&s->aov, material_has_non_delta_lobe(&scene->materials[v.info.material]), sampled,
                       s->throughput / s->radiance_scale, bs.weight);
#endif
    if (!sampled || !bs.is_delta) return 0;
    follow_bsdf_sample(s, &v, &bs);
    if (all(s->throughput == (float4)(0.0f))) return 0;
    ++s->segments;
    return 1;
}

/* The local model's radiance from state `*s` onward; the state is the caller's, so what the path records on the way
 * (its AOVs) stays with it. */
inline float4 trace_direct_state(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                                 uint *rays_traced)
{
    float4 radiance = (float4)(0.0f);
    int goes_on = s->segments <= max_segments(scene->params);
    while (goes_on) goes_on = direct_segment(scene, w, sampler, s, &radiance, rays_traced);
    return radiance;
}

inline float4 trace_direct(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray,
                           uint *rays_traced)
{
    PathState s = camera_path(ray);
    return trace_direct_state(scene, w, sampler, &s, rays_traced);
}

#endif
