/* The global model: unidirectional path tracing with next-event estimation and multiple importance sampling
 * (power heuristic), Russian roulette, four wavelengths per path. The path's state and the steps it shares with
 * the local model are path_state.cl's. */
#ifndef SPECTRACE_PATH_TRACER_CL
#define SPECTRACE_PATH_TRACER_CL

#include "path_state.cl"
#include "fluorescence.cl"

/* Russian roulette once `segments` bounces have happened (Mitsuba 3's rr_depth): 0 ends the path. The survival
 * probability follows the throughput without the radiance compression of refraction, which light undoes when it
 * leaves the glass again: otherwise a path inside glass (throughput 1/n²) would be culled as if it carried little. */
inline int survives_russian_roulette(PathState *s, __global const RenderParams *params, float u_rr)
{
    if (s->segments < params->rr_depth) return 1;
    float4 t = s->throughput / s->radiance_scale;
    float q = fmin(fmax(fmax(t.x, t.y), fmax(t.z, t.w)), 0.95f);
    if (!(u_rr < q)) return 0;
    s->throughput /= q;
    return 1;
}

/* Inside a medium: the flight toward the surface at hit_t may end at a scattering point instead. Returns 1 when
 * it did and the path goes on from there (next-event estimation added to *radiance, then a new segment drawn
 * from the phase function), 0 otherwise; *ended says the path must stop (scattered on its last allowed segment,
 * or killed by Russian roulette). */
inline int scatter_in_medium(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                             float hit_t, int last_segment, float4 *radiance, int *ended, uint *rays_traced)
{
    *ended = 0;
    if (!SCENE_HAS_MEDIA || s->medium < 0) return 0;
    __global const Medium *medium = &scene->media[s->medium];
#if SCENE_HAS_MEDIUM_EMISSION
    float4 before = s->throughput;
#endif
    FreeFlight flight = path_free_flight(scene, w, sampler, s, medium, hit_t);
#if SCENE_HAS_MEDIUM_EMISSION
    if (medium->emission >= 0) {
        float4 lanes = s->secondary_terminated ? (float4)(1.0f, 0.0f, 0.0f, 0.0f) : (float4)(1.0f);
        float4 emitted = before * (medium->grid >= 0 ? flight.emitted
                                                     : medium_emitted_homogeneous(medium, scene->spectra, w, lanes,
                                                                                  hit_t));
        *radiance += emitted;
        IF_POLARIZED(polarized_gather(&s->pol, emitted));
    }
#endif
    if (!flight.scattered) return 0;
    if (s->segments >= last_segment) {
        *ended = 1;
        return 1;
    }
    float3 x = s->ray.origin + flight.distance * s->ray.direction;
    float3 travel = s->ray.direction;
    PATH_GATHER(s, radiance, estimate_direct_light_in_medium(scene, w, sampler, x, travel, s->medium, medium->g,
                                                             path_query(sampler, s, QUERY_SHADOW), rays_traced));
#if FILM_AOVS
    aov_at_medium_scatter(&s->aov, flight.distance, x, s->throughput / s->radiance_scale);
#endif
    s->ray.direction = sample_henyey_greenstein(travel, medium->g, sample_2d(sampler));
    IF_POLARIZED(polarized_depolarize(&s->pol, s->ray.direction));
    s->ray.origin = x;
    s->previous_point = x;
    s->previous_pdf = henyey_greenstein(dot(travel, s->ray.direction), medium->g);
    s->previous_delta = 0;
    *ended = !survives_russian_roulette(s, scene->params, sample_1d(sampler))
          || all(s->throughput == (float4)(0.0f));
    return 1;
}

/* The rest of path_segment at surface vertex v once its material is settled (a fluorescent one resolved): its
 * direct light, then the next segment drawn from its BSDF. Returns 1 when the path goes on from the updated state.
 * BDPT (bdpt_fluorescence.cl) goes on from a camera subpath's re-emission through it. */
inline int path_scatter(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                        const PathVertex *v, float4 *radiance, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int last_segment = max_segments(params);
    int uncounted_passes = !params->count_thin_passes
                        && MATERIAL_IS(&scene->materials[v->info.material], MATERIAL_THINDIELECTRIC);
    if (s->segments >= last_segment && !uncounted_passes) return 0;

    BSDFSample bs;
    int sampled = light_and_sample_vertex(scene, w, sampler, s, v, 1, radiance, rays_traced, &bs);
#if FILM_AOVS
    aov_at_bsdf_sample(&s->aov, material_has_non_delta_lobe(&scene->materials[v->info.material]), sampled,
                       s->throughput / s->radiance_scale, bs.weight);
#endif
    if (!sampled) return 0;
    /* Straight through a thin sheet, when such passes do not count toward max_depth (count_thin_passes off, as
     * Mitsuba 3's volpath, whose thindielectric transmission is a null lobe): the path goes on with the same
     * segment number, even from its last segment. */
    int uncounted = uncounted_passes && dot(bs.wi, v->n) * dot(v->wo, v->n) < 0.0f;
    if (s->segments >= last_segment && !uncounted) return 0;
    IF_POLARIZED(polarized_scatter_vertex(scene, w, s, v, &bs));
    follow_bsdf_sample(s, v, &bs);
    if (!survives_russian_roulette(s, params, sample_1d(sampler))) return 0;
    if (all(s->throughput == (float4)(0.0f))) return 0;
    if (!uncounted) ++s->segments;  /* below last_segment here, so the next one is allowed */
    return 1;
}

/* One segment of a path: trace s->ray, add the light it finds (emission met, next-event estimation at the vertex
 * or scattering point) to *radiance, then draw the next segment. Returns 1 when the path goes on from the updated
 * state, 0 when it has ended. Call it only while s->segments <= max_segments(params).
 *
 * Both kernel shapes run paths through this one function: the megakernel loops over it in a work-item
 * (continue_path), the wavefront keeps the state in a global buffer and calls it once per launch
 * (kernels/wavefront_pass.cl). */
inline int path_segment(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                        float4 *radiance, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int last_segment = max_segments(params);
    int ended = 0;
#if SCENE_HAS_FLUORESCENCE
    w = path_wavelengths(s, w);
#endif

    Hit hit = far_clipped(params, s, scene_intersect(scene, s->ray, path_query(sampler, s, QUERY_PATH), rays_traced));
    if (scatter_in_medium(scene, w, sampler, s, hit.t, last_segment, radiance, &ended, rays_traced)) {
        return !ended && ++s->segments <= last_segment;
    }
    if (hit.triangle < 0) {
        /* A hidden environment: the camera's own rays (the first segment) see black; reflections still show it. */
        int hidden = (params->hide_emitters & HIDE_ENVIRONMENT) && s->segments == 1;
        if (SCENE_HAS_ENVIRONMENT && params->environment_light >= 0 && !hidden) {
            __global const Light *env = &scene->lights[params->environment_light];
            float3 d = s->ray.direction;
            float weight = s->previous_delta
                         ? 1.0f : power_heuristic(s->previous_pdf, environment_pdf(env, scene->map_cdf, d));
            float4 emitted = environment_radiance(env, scene->spectra, scene->texels, w, d);
            *radiance += s->throughput * emitted * weight;
            IF_POLARIZED(polarized_gather(&s->pol, s->throughput * emitted * weight));
#if FILM_AOVS
            record_camera_emission(scene, w, s, emitted, weight, 0, hit);
#endif
        }
        return 0;
    }

    PathVertex v = path_vertex(scene, hit, s->ray);
    int live;
    if (record_surface_reached(s, &v, hit.t, params, &live)) return live;
    if (v.info.light >= 0) {
        __global const Light *light = &scene->lights[v.info.light];
        float4 emitted = vertex_emission(scene, w, &v, hit);
        float weight = 1.0f;
        if (!s->previous_delta) {
            float pdf_light = emitter_hit_pdf(light, scene->shapes, s->previous_point, v.p, v.n, v.wo, hit.b12);
            weight = power_heuristic(s->previous_pdf, pdf_light);
        }
        IF_POLARIZED(emitted *= polarized_emitter_vertex(scene, s, light, &v, hit, s->throughput * emitted * weight));
        *radiance += s->throughput * emitted * weight;
#if FILM_AOVS
        record_camera_emission(scene, w, s, emitted, weight, &v, hit);
#endif
    }
    /* Beyond a material-less boundary the same segment goes on. */
    if (v.info.material == TRIANGLE_NO_MATERIAL) return cross_null_boundary(s, &v);
#if SCENE_HAS_FLUORESCENCE
    fluorescent_vertex(scene, w, sampler, s, &v);
    w = path_wavelengths(s, w);
#endif
    return path_scatter(scene, w, sampler, s, &v, radiance, rays_traced);
}

/* Radiance carried back along the path from state `*s` onward, including emission met by s->ray; the state is the
 * caller's, so what the path records on the way (its AOVs) stays with it. */
inline float4 trace_path_state(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                               uint *rays_traced)
{
    float4 radiance = (float4)(0.0f);
    int goes_on = s->segments <= max_segments(scene->params);
    while (goes_on) goes_on = path_segment(scene, w, sampler, s, &radiance, rays_traced);
    return radiance;
}

/* trace_path_state of a copy of `s`. */
inline float4 continue_path(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState s,
                            uint *rays_traced)
{
    return trace_path_state(scene, w, sampler, &s, rays_traced);
}

inline float4 trace_path(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray,
                         uint *rays_traced)
{
    return continue_path(scene, w, sampler, camera_path(ray), rays_traced);
}

#endif
