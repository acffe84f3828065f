/* The light tracer (particle tracing): paths start on the lights and every vertex the camera could see is
 * connected to it, adding to the pixel the connection lands in (Veach 1997, sec. 10.2 "light tracing"; Arvo &
 * Kirk 1990). It reaches what a camera path cannot: caustics of point, spot and distant lights seen on diffuse
 * surfaces through smooth glass and mirrors (paths L S+ D E).
 *
 * Light flows along a light path the way the path is traced, so each vertex needs the BSDF for light arriving from
 * the previous vertex (ωlight) and leaving toward the next: material_eval(wo = next, wi = ωlight), radiance's own
 * convention, which is how the connection to the camera evaluates it. A sampled direction comes from
 * material_sample(wo = ωlight), the BSDF with its arguments swapped (its adjoint, Veach 1997, ch. 5), which differs
 * in two ways: refraction's radiance compression (n_o/n_i)² is the one for light flowing the other way, so the
 * sample's weight is divided by its radiance_scale (the BSDFs are otherwise symmetric), and with shading normals the
 * weight needs |ωo·ns||ωi·ng| / (|ωo·ng||ωi·ns|), ωo = ωlight (Veach 1997, eq. 5.19; pbrt's CorrectShadingNormal).
 * At a connection the cosine of the camera's side is the geometric one, and f·|ωlight·ns| is divided by
 * |ωlight·ng| (the same shading-normal rule: the BSDF with shading normals is f·|ωi·ns|/|ωi·ng| per geometric
 * cosine, whichever way a path is traced).
 *
 * max_depth counts path segments from the camera as the path integrator does: light vertex i (1 = the first surface
 * the light reaches, 0 = a point on an area light or in a glowing medium: light_glowing_media.cl) seen by the camera
 * closes a path of i + 1 segments.
 *
 * The splats a path makes land in arbitrary pixels. To keep the film deterministic they are not added here: each
 * is written as a record (pixel, XYZ) in its work-item's slots, in the order the path makes them, and the host adds
 * the records to the film in the order (sample index, work-item, record), the same however the render is split
 * into passes (spectrace.engine.light_tracer). */
#ifndef SPECTRACE_LIGHT_TRACER_CL
#define SPECTRACE_LIGHT_TRACER_CL

#include "camera.cl"
#include "camera_importance.cl"
#include "film.cl"
#include "light_emission.cl"
#include "path_state.cl"
#include "fluorescence.cl"

/* Where a work-item's splat records go: slots [0, capacity) of its own, for the records numbered begin .. begin +
 * capacity − 1 of its path (the host launches the path again for later ones); count is every record it makes. */
typedef struct {
    __global float4 *xyz;  /* XYZ estimate, w = 1 for a dropped (non-finite) one */
    __global int *pixel;   /* -1 for an unused slot */
    int begin;
    int capacity;
    int count;
    __global float4 *band_value; /* with SPECTRAL_FILM: each lane's band-averaged radiance estimate, W/(m² sr nm) */
    __global int4 *band;         /* with SPECTRAL_FILM: each lane's band, -1 outside the bands or when dropped */
    __global float2 *film;       /* with a filter other than the box: the film position, pixels */
} SplatRecords;

/* The arguments every splatting pass kernel takes after SCENE_KERNEL_PARAMS (integrator_light.cl, integrator_bdpt.cl),
 * in the order spectrace.engine.light_tracer sets them: one list, so the two kernels cannot drift apart. */
#define SPLAT_PASS_PARAMS                                                                                            \
    __global const float4 *cmf, float4 scene_sphere, int hide_environment, int sample_index,                        \
        __global const int *items, int item_count, int record_begin, int capacity, __global float4 *splat_xyz,      \
        __global int *splat_pixel, __global int *splat_counts, __global float4 *splat_band_value,                   \
        __global int4 *splat_band, __global float2 *splat_film, __global float4 *own_xyz, __global uint *ray_counts

/* Work-item `slot`'s records in a pass's splat buffers (its `capacity` slots), emptied (pixel -1) before the path
 * writes any. */
inline SplatRecords slot_splat_records(int slot, int record_begin, int capacity, __global float4 *splat_xyz,
                                       __global int *splat_pixel, __global float4 *splat_band_value,
                                       __global int4 *splat_band, __global float2 *splat_film)
{
    for (int k = 0; k < capacity; ++k) splat_pixel[slot * capacity + k] = -1;
    SplatRecords records = {splat_xyz + slot * capacity, splat_pixel + slot * capacity, record_begin, capacity, 0,
                            splat_band_value + slot * capacity, splat_band + slot * capacity,
                            splat_film + slot * capacity};
    return records;
}

/* A splat's XYZ estimate, w = 1 (and XYZ 0) where it is not finite: the film counts it as a dropped sample. */
inline float4 splat_xyz_estimate(float4 value, __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 xyz = spectrum_to_xyz_estimate(value, cmf, w);
    int dropped = !(isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z));
    return dropped ? (float4)(0.0f, 0.0f, 0.0f, 1.0f) : xyz;
}

inline void record_splat(SplatRecords *r, int pixel, float2 film, float4 value, __global const float4 *cmf,
                         const SampledWavelengths *w, __global const RenderParams *params)
{
    int slot = r->count++ - r->begin;
    if (slot < 0 || slot >= r->capacity) return;
    /* The host spreads the splat over the pixels whose filter covers it (spectrace.engine.light_tracer). */
    if (!PIXEL_FILTER_IS(params, PIXEL_FILTER_BOX)) r->film[slot] = film;
    float4 xyz = splat_xyz_estimate(value, cmf, w);
    int dropped = xyz.w != 0.0f;
    r->xyz[slot] = xyz;
    r->pixel[slot] = pixel;
#ifdef SPECTRAL_FILM
    /* As add_to_spectral_film (film.cl) adds a camera path's sample, lane by lane; the host adds them in order. */
    const float band = spectral_band_nm(params);
    float4 lanes = 0.25f * value / (w->pdf * band);
    int4 bins = convert_int4(floor((w->lambda - (float4)(params->spectral_min_nm)) / band));
    bins = select((int4)(-1), bins, bins >= (int4)(0) && bins < (int4)(params->spectral_bins));
    r->band_value[slot] = lanes;
    r->band[slot] = dropped ? (int4)(-1) : bins;
#endif
}

/* Veach's shading-normal factor for adjoint transport: |ωo·ns||ωi·ng| / (|ωo·ng||ωi·ns|), ωo toward where the light
 * came from, ωi where it goes; 1 where the vertex shades with its geometric normal. */
inline float shading_normal_adjoint(float3 ng, float3 ns, float3 wo, float3 wi)
{
    if (all(ns == ng)) return 1.0f;
    float denominator = fabs(dot(wo, ng)) * fabs(dot(wi, ns));
    return denominator > 0.0f ? fabs(dot(wo, ns)) * fabs(dot(wi, ng)) / denominator : 0.0f;
}

/* The lens point's sample for a connection: drawn only by the thin lens, so the other cameras' paths draw the same
 * numbers as before it existed. */
inline float2 lens_sample(__global const RenderParams *params, Sampler *sampler)
{
    return CAMERA_IS(params, CAMERA_THINLENS) ? sample_2d(sampler) : (float2)(0.0f);
}

/* The fraction of light that leaves `from` (offset off its surface toward the camera, or a point in a medium) in
 * `medium` and reaches the camera's lens point: 0 when something blocks it, the media's transmittance between
 * (scene_transmittance; in scenes without media the plain occlusion test). */
inline float4 camera_transmittance(const Scene *scene, const SampledWavelengths *w, int medium,
                                   const CameraConnection *c, float3 from, uint query, uint *rays_traced)
{
    return scene_transmittance(scene, w, medium, from, c->lens, c->to_camera, 0, query, rays_traced);
}

/* The environment seen straight from the camera (a path of one segment): a light path cannot end in a pinhole, so
 * the work-item traces the camera ray of its own pixel for it. The jitter is drawn in every build, so a kernel
 * specialised to a scene without an environment draws the same numbers as one built for every scene. */
inline void environment_seen_directly(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, int item,
                                      int hide_environment, SplatRecords *records, __global const float4 *cmf,
                                      uint *rays_traced)
{
    float2 jitter = sample_2d(sampler);
#if SCENE_HAS_ENVIRONMENT
    __global const RenderParams *params = scene->params;
    if (params->environment_light < 0 || hide_environment) return;
    float2 film = (float2)((float)(item % params->width) + jitter.x, (float)(item / params->width) + jitter.y);
    Ray ray = camera_ray(params, film, sampler); /* only the thin lens draws more: its lens point */
    PathState s = camera_path(ray);
    float4 transmittance = (float4)(1.0f);
    if (SCENE_HAS_MEDIA && (params->medium_count > 0 || params->null_surfaces)) {
        /* Through index-matched media the light that is not scattered away arrives; the scattered light is the
         * light paths' to bring. */
        transmittance = scene_transmittance(scene, w, -1, ray.origin, ray.origin, ray.direction, 1,
                                            path_query(sampler, &s, QUERY_PATH), rays_traced);
        if (all(transmittance == (float4)(0.0f))) return;
    } else {
        Hit hit = far_clipped(params, &s, scene_intersect(scene, ray, path_query(sampler, &s, QUERY_PATH), rays_traced));
        if (hit.triangle >= 0) return;
    }
    __global const Light *env = &scene->lights[params->environment_light];
    float4 radiance = environment_radiance(env, scene->spectra, scene->texels, w, ray.direction);
    record_splat(records, item, film, radiance * transmittance, cmf, w, params);
#endif
}

/* Russian roulette as the path tracer's (rr_depth, survival min(max weight, 0.95)), on the scattering weights
 * alone (`scatter`: the adjoint BSDF and the media's weights): 0 ends the path, as does a zero throughput. */
inline int light_path_survives(PathState *s, float4 *scatter, __global const RenderParams *params, Sampler *sampler)
{
    if (s->segments >= params->rr_depth) {
        float4 t = *scatter;
        float q = fmin(fmax(fmax(t.x, t.y), fmax(t.z, t.w)), 0.95f);
        if (!(sample_1d(sampler) < q)) return 0;
        s->throughput /= q;
        *scatter /= q;
    }
    return any(s->throughput != (float4)(0.0f));
}

/* What a light path's ray met (light_path_meets). */
#define LIGHT_PATH_ENDS 0     /* nothing, or a boundary it may not cross again: the path ends */
#define LIGHT_PATH_CROSSES 1  /* an index-matched medium boundary, crossed: the path's segment goes on */
#define LIGHT_PATH_SURFACE 2  /* a surface with a material, the path's next vertex */

/* The first step the light tracer's walk and SPPM's photons take where the ray s->ray ends at `hit`: *v is the
 * surface it meets; one without material (an index-matched medium boundary) is crossed, and at a dispersive
 * material the path keeps only its hero wavelength from there on (terminate_secondary). */
inline int light_path_meets(const Scene *scene, const SampledWavelengths *w, PathState *s, Hit hit, PathVertex *v)
{
    if (hit.triangle < 0) return LIGHT_PATH_ENDS;
    *v = path_vertex(scene, hit, s->ray);
    if (v->info.material == TRIANGLE_NO_MATERIAL)
        return cross_null_boundary(s, v) ? LIGHT_PATH_CROSSES : LIGHT_PATH_ENDS;
    if (material_disperses(&scene->materials[v->info.material], w))
        terminate_secondary(&s->throughput, &s->secondary_terminated);
    return LIGHT_PATH_SURFACE;
}

/* The last step the light tracer's walk and SPPM's photons take at a surface vertex v: the path goes on along a
 * direction drawn from v's material, weighted by the adjoint BSDF (this file's header), then Russian roulette
 * (light_path_survives), and s->segments counts the new segment. Returns 0 when the path ends. */
inline int continue_light_path(const PathVertex *v, __global const Material *material, const SurfaceContext *sc,
                               const SampledWavelengths *w, __global const RenderParams *params, Sampler *sampler,
                               PathState *s, float4 *scatter)
{
    float uc = sample_1d(sampler);
    float2 u = sample_2d(sampler);
    BSDFSample bs;
    if (!material_sample(material, sc, w, v->ns, v->wo, uc, u, &bs) || !shading_side_agrees(v->n, v->ns, bs.wi))
        return 0;
    float4 weight = bs.weight * (shading_normal_adjoint(v->n, v->ns, v->wo, bs.wi) / bs.radiance_scale);
    s->throughput *= weight;
    *scatter *= weight;
    s->previous_point = v->p;
    s->medium = medium_beyond(v->info.interior, v->n, bs.wi, s->medium);
    s->ray.origin = offset_ray_origin(v->p, v->n, bs.wi);
    s->ray.direction = bs.wi;
    if (!light_path_survives(s, scatter, params, sampler)) return 0;
    ++s->segments;
    return 1;
}

/* Inside a medium, the light path's flight toward the surface at hit_t may end at a scattering point x (a vertex,
 * numbered s->segments like a surface's): x is connected to the camera (the phase function toward it, the media's
 * transmittance on the way) and the path goes on in a direction drawn from the phase function, *scattered = 1.
 * Free flights as the path tracer's (medium_sample_flight). Returns 0 when the path ends. */
inline int scatter_light_in_medium(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                                   float hit_t, int last_segment, __global const float4 *cmf, SplatRecords *records,
                                   float4 *scatter, int *scattered, uint *rays_traced)
{
    *scattered = 0;
    if (!SCENE_HAS_MEDIA || s->medium < 0) return 1;
    __global const RenderParams *params = scene->params;
    __global const Medium *medium = &scene->media[s->medium];
    FreeFlight flight = path_free_flight(scene, w, sampler, s, medium, hit_t);
    *scatter *= flight.weight;
    if (!flight.scattered) return any(s->throughput != (float4)(0.0f));
    *scattered = 1;
    float3 x = s->ray.origin + flight.distance * s->ray.direction;
    float3 travel = s->ray.direction;
    CameraConnection c = connect_to_camera_sampled(params, x, lens_sample(params, sampler));
    if (c.pixel >= 0) {
        float4 value = s->throughput * (henyey_greenstein(dot(travel, c.to_camera), medium->g) * c.importance);
        if (any(value != (float4)(0.0f))) {
            value *= camera_transmittance(scene, w, s->medium, &c, x, path_query(sampler, s, QUERY_SHADOW),
                                          rays_traced);
            if (any(value != (float4)(0.0f))) record_splat(records, c.pixel, c.film, value, cmf, w, params);
        }
    }
    if (s->segments + 2 > last_segment) return 0;
    s->ray.direction = sample_henyey_greenstein(travel, medium->g, sample_2d(sampler));
    s->ray.origin = x;
    s->previous_point = x;
    if (!light_path_survives(s, scatter, params, sampler)) return 0;
    ++s->segments;
    return 1;
}

/* A light path from its vertex s->segments on (a light's point, or a glowing medium's): each vertex joined to
 * the camera, until max_depth, Russian roulette or the scene's edge ends it. */
inline void light_path_walk(const Scene *scene, SampledWavelengths *w, Sampler *sampler, PathState *s,
                            float4 *scatter, int last_segment, __global const float4 *cmf, SplatRecords *records,
                            uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    /* s->segments: the index of the vertex s->ray is about to reach. */
    while (s->segments + 1 <= last_segment) {
        Hit hit = scene_intersect(scene, s->ray, path_query(sampler, s, QUERY_PATH), rays_traced);
        int scattered = 0;
        if (!scatter_light_in_medium(scene, w, sampler, s, hit.t, last_segment, cmf, records, scatter,
                                     &scattered, rays_traced)) {
            return;
        }
        if (scattered) continue;
        PathVertex v;
        int met = light_path_meets(scene, w, s, hit, &v);
        if (met == LIGHT_PATH_ENDS) return;
        if (met == LIGHT_PATH_CROSSES) continue;
#if SCENE_HAS_FLUORESCENCE
        fluorescent_light_vertex(scene, w, sampler, s, &v, scatter);
#endif
        __global const Material *material = &scene->materials[v.info.material];
        SurfaceContext sc = shading_context(scene, v.uv, v.p, v.footprint, v.ns_base, v.dpdu, v.tangent_w, 1);
        SURFACE_AT_HIT(sc, v);
        if (material_has_non_delta_lobe(material)) {
            CameraConnection c = connect_to_camera_sampled(params, v.p, lens_sample(params, sampler));
            if (c.pixel >= 0 && shading_side_agrees(v.n, v.ns, c.to_camera)) {
                float4 f_cos = material_eval(material, &sc, w, v.ns, c.to_camera, v.wo);
                /* f_cos holds |ωlight·ns|: times |ωcamera·ng| / |ωlight·ng| (see the top of this file). */
                float cos_light = fabs(dot(v.wo, v.n));
                float cosines = cos_light > 0.0f ? fabs(dot(c.to_camera, v.n)) / cos_light : 0.0f;
                float4 value = s->throughput * f_cos * (cosines * c.importance);
                if (any(value != (float4)(0.0f))) {
                    int medium = medium_beyond(v.info.interior, v.n, c.to_camera, s->medium);
                    value *= camera_transmittance(scene, w, medium, &c, offset_ray_origin(v.p, v.n, c.to_camera),
                                                  path_query(sampler, s, QUERY_SHADOW), rays_traced);
                    if (any(value != (float4)(0.0f))) record_splat(records, c.pixel, c.film, value, cmf, w, params);
                }
            }
        }
        if (s->segments + 2 > last_segment) return;
        if (!continue_light_path(&v, material, &sc, w, params, sampler, s, scatter)) return;
    }
}

#if SCENE_HAS_MEDIUM_EMISSION
#include "light_glowing_media.cl"
#endif

/* One light path of pixel sample `sample_index` of work-item `item`: its splats go to `records`. hide_environment:
 * the camera's own rays see black where they leave the scene (the scene's hide_environment). */
inline void trace_light_path(const Scene *scene, int item, int sample_index, float4 scene_sphere,
                             int hide_environment, __global const float4 *cmf, SplatRecords *records,
                             uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    Sampler sampler = sampler_start((uint)params->seed, (uint)item, (uint)sample_index);
    SampledWavelengths w = sample_wavelengths(sample_1d(&sampler));
    int last_segment = max_segments(params);
    environment_seen_directly(scene, &w, &sampler, item, hide_environment, records, cmf, rays_traced);

    float2 u_pick = sample_2d(&sampler);
    float2 u_direction = sample_2d(&sampler);
    float4 scatter = (float4)(1.0f);  /* product of the adjoint BSDF weights alone, for Russian roulette */
    float light_odds = 1.0f;          /* the probability of starting on a light (light_glowing_media.cl) */
#if SCENE_HAS_MEDIUM_EMISSION
    PathState glowing;
    int glow = glowing_light_path_start(scene, &w, &sampler, &u_pick, u_direction, &light_odds, cmf, records,
                                        &glowing, rays_traced);
    if (glow != 0) {
        if (glow > 0) light_path_walk(scene, &w, &sampler, &glowing, &scatter, last_segment, cmf, records, rays_traced);
        return;
    }
#endif
    if (params->light_count == 0) return;
    __global const Light *light = &scene->lights[pick_light_reusing(scene->light_cdf, params->light_count, &u_pick)];
    LightBuffers buffers = light_buffers(scene);
    EmissionSample e;
    if (!sample_emission(light, &buffers, &w, scene_sphere, u_pick, u_direction, &e)) return;

    /* The path's state as a camera path keeps it (path_state.cl), for the same queries and medium bookkeeping. */
    PathState s = camera_path(e.ray);
    s.throughput = e.weight / light_odds;
    s.medium = scene_medium_at(scene, e.ray.origin); /* the light's medium, on the side its light leaves */

    if (e.first_vertex) {
        CameraConnection c = connect_to_camera_sampled(params, e.point, lens_sample(params, &sampler));
        if (c.pixel >= 0) {
            float cos_light = fabs(dot(e.normal, c.to_camera));
            TextureBuffers textures = buffers.textures;
            float4 emitted = area_light_emitted(light, &textures, &w, e.normal, c.to_camera, e.uv);
            if (any(emitted != (float4)(0.0f))) {
                /* A one-sided lamp is seen from the side its light leaves: the path's medium. */
                float4 transmittance = camera_transmittance(scene, &w, s.medium, &c,
                                                            offset_ray_origin(e.point, e.normal, c.to_camera),
                                                            path_query(&sampler, &s, QUERY_SHADOW), rays_traced);
                if (any(transmittance != (float4)(0.0f))) {
                    float weight = cos_light * c.importance / (e.pdf_area * light_odds);
                    record_splat(records, c.pixel, c.film, emitted * transmittance * weight, cmf, &w, params);
                }
            }
        }
    }

    light_path_walk(scene, &w, &sampler, &s, &scatter, last_segment, cmf, records, rays_traced);
}

#endif
