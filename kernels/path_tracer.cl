/* The global model: unidirectional path tracing with next-event estimation and multiple importance sampling
 * (power heuristic), Russian roulette, four wavelengths per path. */
#ifndef SPECTRACE_PATH_TRACER_CL
#define SPECTRACE_PATH_TRACER_CL

#include "direct_lighting.cl"

/* Longest path when max_depth is unbounded (-1): Russian roulette ends paths long before this. */
#define UNBOUNDED_DEPTH 1024

/* Where a path stands between two bounces; lets sensors start paths at a surface point as well as a camera. */
typedef struct {
    Ray ray;
    float4 throughput;
    float previous_pdf;      /* solid-angle pdf of the direction that produced `ray`; 0 for a camera ray */
    int previous_delta;      /* `ray` left a specular lobe (or a camera): emission found by it is not MIS-weighted */
    float3 previous_point;
    int segments;            /* the segment `ray` is: 1 for a camera ray */
    int secondary_terminated;
    int medium;              /* index of the medium `ray` travels in, -1 for none (kernels/medium.cl) */
    float radiance_scale;    /* product of the refractions' (n_o/n_i)² factors in `throughput` */
    int null_crossings;      /* medium boundaries crossed without a vertex, bounded by MAX_NULL_CROSSINGS */
} PathState;

inline PathState camera_path(Ray ray)
{
    PathState s;
    s.ray = ray;
    s.throughput = (float4)(1.0f);
    s.previous_pdf = 0.0f;
    s.previous_delta = 1;
    s.previous_point = ray.origin;
    s.segments = 1;
    s.secondary_terminated = 0;
    s.medium = -1;  /* cameras and sensors stand outside every medium */
    s.radiance_scale = 1.0f;
    s.null_crossings = 0;
    return s;
}

/* After a dispersive event only the hero wavelength goes on; scaling it by 4 keeps the 4-wavelength average
 * unbiased (pbrt-v4's TerminateSecondary). */
inline void terminate_secondary_wavelengths(PathState *s)
{
    if (s->secondary_terminated) return;
    s->throughput = (float4)(4.0f * s->throughput.x, 0.0f, 0.0f, 0.0f);
    s->secondary_terminated = 1;
}

inline int max_segments(__global const RenderParams *params)
{
    return params->max_depth < 0 ? UNBOUNDED_DEPTH : params->max_depth;
}

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

/* At a material-less (index-matched) medium boundary the ray goes on unchanged into or out of the shape's
 * interior: no vertex, and the segment it is goes on too. */
inline void cross_null_boundary(PathState *s, TriangleInfo info, float3 p, float3 n)
{
    s->medium = medium_beyond(info.interior, n, s->ray.direction);
    s->ray.origin = offset_ray_origin(p, n, s->ray.direction);
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
    float u_lane = sample_1d(sampler);
    float u_distance = sample_1d(sampler);
    FreeFlight flight = medium_sample_flight(medium, scene->spectra, w, hit_t, s->secondary_terminated, u_lane,
                                             u_distance);
    s->throughput *= flight.weight;
    if (!flight.scattered) return 0;
    if (s->segments >= last_segment) {
        *ended = 1;
        return 1;
    }
    float3 x = s->ray.origin + flight.distance * s->ray.direction;
    float3 travel = s->ray.direction;
    *radiance += s->throughput * estimate_direct_light_in_medium(scene, w, sampler, x, travel, medium->g,
                                                                 rays_traced);
    s->ray.direction = sample_henyey_greenstein(travel, medium->g, sample_2d(sampler));
    s->ray.origin = x;
    s->previous_point = x;
    s->previous_pdf = henyey_greenstein(dot(travel, s->ray.direction), medium->g);
    s->previous_delta = 0;
    *ended = !survives_russian_roulette(s, scene->params, sample_1d(sampler))
          || all(s->throughput == (float4)(0.0f));
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

    Hit hit = scene_intersect(scene, s->ray, rays_traced);
    if (scatter_in_medium(scene, w, sampler, s, hit.t, last_segment, radiance, &ended, rays_traced)) {
        return !ended && ++s->segments <= last_segment;
    }
    if (hit.triangle < 0) {
        if (SCENE_HAS_ENVIRONMENT && params->environment_light >= 0) {
            __global const Light *env = &scene->lights[params->environment_light];
            float3 d = s->ray.direction;
            float weight = s->previous_delta
                         ? 1.0f : power_heuristic(s->previous_pdf, environment_pdf(env, scene->map_cdf, d));
            *radiance += s->throughput * environment_radiance(env, scene->spectra, scene->texels, w, d) * weight;
        }
        return 0;
    }

    TriangleInfo info = scene->triangle_info[hit.triangle];
    float3 p = triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
    float3 n = triangle_normal(scene->triangle_vertices, hit.triangle);
    float3 wo = -s->ray.direction;

    if (info.light >= 0) {
        __global const Light *light = &scene->lights[info.light];
        float4 emitted = area_light_emitted(light, scene->spectra, scene->texels, w, n, wo,
                                             triangle_uv(scene->triangle_uvs, hit.triangle, hit.b12));
        float weight = 1.0f;
        if (!s->previous_delta) {
            float pdf_light = area_light_pdf(light, distance(s->previous_point, p), fabs(dot(n, wo)));
            weight = power_heuristic(s->previous_pdf, pdf_light);
        }
        *radiance += s->throughput * emitted * weight;
    }
    if (info.material == TRIANGLE_NO_MATERIAL) {
        if (++s->null_crossings > MAX_NULL_CROSSINGS) return 0;
        cross_null_boundary(s, info, p, n);
        return 1;  /* the same segment goes on beyond the boundary */
    }
    if (s->segments >= last_segment) return 0;

    __global const Material *material = &scene->materials[info.material];
    /* A dispersive surface keeps only the hero wavelength for everything that follows, direct light included
     * (its BSDF is evaluated at the hero's index of refraction). */
    if (material_disperses(material, w)) terminate_secondary_wavelengths(s);
    if (material_has_non_delta_lobe(material)) {
        *radiance += s->throughput * estimate_direct_light(scene, w, sampler, p, n, wo, material, 1, rays_traced);
    }

    float uc = sample_1d(sampler);
    float2 u = sample_2d(sampler);
    BSDFSample bs;
    if (!material_sample(material, scene->spectra, w, n, wo, uc, u, &bs)) return 0;
    s->throughput *= bs.weight;
    s->radiance_scale *= bs.radiance_scale;
    if (bs.terminate_secondary) terminate_secondary_wavelengths(s);
    s->previous_pdf = bs.pdf;
    s->previous_delta = bs.is_delta;
    s->medium = medium_beyond(info.interior, n, bs.wi);

    if (!survives_russian_roulette(s, params, sample_1d(sampler))) return 0;
    if (all(s->throughput == (float4)(0.0f))) return 0;

    s->previous_point = p;
    s->ray.origin = offset_ray_origin(p, n, bs.wi);
    s->ray.direction = bs.wi;
    ++s->segments;  /* below last_segment here, so the next one is allowed */
    return 1;
}

/* Radiance carried back along the path from state `s` onward, including emission met by s.ray. */
inline float4 continue_path(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState s,
                            uint *rays_traced)
{
    float4 radiance = (float4)(0.0f);
    int goes_on = s.segments <= max_segments(scene->params);
    while (goes_on) goes_on = path_segment(scene, w, sampler, &s, &radiance, rays_traced);
    return radiance;
}

inline float4 trace_path(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray,
                         uint *rays_traced)
{
    return continue_path(scene, w, sampler, camera_path(ray), rays_traced);
}

#endif
