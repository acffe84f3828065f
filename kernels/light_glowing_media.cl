/* Glowing media (medium_emission.cl) in the light tracer and in BDPT: where light paths start in a glowing medium,
 * and how BDPT's camera subpaths gather the glow they cross.
 *
 * Sources (read to learn, not copied): Veach 1997, sec. 8.1 and ch. 10 (path space with volume vertices, emission
 * sampling); pbrt-v4's VolPathIntegrator (the emission a camera path gathers at every majorant collision);
 * pbrt-v4's and Mitsuba 3's BDPT do not handle medium emission, so the design below is this renderer's own.
 *
 * Units and contract. A glowing medium emits σa(λ, x) Le(λ, x) of radiance per unit length, the same in every
 * direction: per unit volume, σa Le of radiant intensity per unit solid angle (W/(m³ sr nm) in scene units). The
 * glow table (spectrace.engine.glowing_media, RenderParams.glow_table, -1: none) lists boxes around the shapes whose
 * interior glows, each picked with probability P_i, and the share q of light paths that start in them.
 *
 * Light tracer. With probability q a light path starts in a glow box instead of on a light (a light's path is then
 * divided by 1 − q): box i picked with P_i, a point x uniform in it, a direction uniform on the sphere. Boxes may
 * overlap, so x's density is the sum over every box that holds it, p(x) = q Σ_i P_i [x ∈ box_i] / V_i (one-sample
 * MIS with the balance heuristic over the boxes: overlaps are not counted twice). The medium at x is found by
 * scene_medium_at (0 emission outside glowing media: the path ends). x is the path's vertex 0, like a point on an
 * area light: joined to the camera it closes a path of one segment, with value σa Le(x) / p(x) times the camera's
 * importance and the transmittance between (the isotropic emission in place of a light's cosine); the path goes on
 * with throughput 4π σa Le(x) / p(x), in x's medium, as from a scattering point.
 *
 * BDPT. Light subpaths start on the lights only, and the camera subpaths gather the glow they cross by the path
 * tracer's estimator (closed form through a homogeneous medium, at delta tracking's tentative collisions through a
 * grid), with weight 1: medium emission is counted by that one strategy (s = 0), which no other makes (no light
 * vertex is ever a point of a glowing medium, next-event estimation samples lights alone), so nothing is counted
 * twice and the MIS weights of every other strategy are those of the scene without the glow. A glowing medium then
 * lights a BDPT image as it lights the path tracer's, with the path tracer's noise for that light; weighing it
 * against light subpaths that start in the medium would need the emission density of every camera subpath's medium
 * stretches, which the free-flight estimators do not give pointwise. The light tracer has no camera subpaths, so it
 * takes the glow as a light. */
#ifndef SPECTRACE_LIGHT_GLOWING_MEDIA_CL
#define SPECTRACE_LIGHT_GLOWING_MEDIA_CL

/* σa(λ, x) Le(λ, x) of `medium` at point x (0 outside media and for media that do not glow), as the free flights
 * weigh it: a grid's σa is its density times σt less the albedo's share of σs. */
inline float4 medium_emission_at(const Scene *scene, const SampledWavelengths *w, int medium, float3 x)
{
    if (medium < 0) return (float4)(0.0f);
    __global const Medium *m = &scene->media[medium];
    if (m->emission < 0) return (float4)(0.0f);
    float4 sigma_a = spectrum_at(scene->spectra, m->sigma_a_offset, w);
    float4 le = medium_emission_spectrum(m, scene->spectra, w);
#if SCENE_HAS_GRID_MEDIA
    if (m->grid >= 0) {
        float4 albedo;
        float4 density = grid_density_albedo(scene->spectra, m->grid, x, w->lambda, &albedo);
        sigma_a = density * (medium_sigma_t(m, scene->spectra, w) - albedo * medium_sigma_s(m, scene->spectra, w));
        le *= grid_emission_factor(scene->spectra, m->grid, x, w->lambda);
    }
#endif
    return sigma_a * le;
}

#define GLOW_BOX(spectra, table, k, i) ((spectra)[(table) + 4 + 8 * (k) + (i)])

/* The density (per unit volume) with which a glowing start picks point x, given that it starts in a glow box:
 * Σ_i P_i [x ∈ box_i] / V_i. */
inline float glow_point_density(__global const float *spectra, int table, float3 x)
{
    int n = (int)spectra[table];
    float density = 0.0f;
    for (int k = 0; k < n; ++k) {
        float3 lo = (float3)(GLOW_BOX(spectra, table, k, 0), GLOW_BOX(spectra, table, k, 1),
                             GLOW_BOX(spectra, table, k, 2));
        float3 hi = (float3)(GLOW_BOX(spectra, table, k, 4), GLOW_BOX(spectra, table, k, 5),
                             GLOW_BOX(spectra, table, k, 6));
        if (all(x >= lo) && all(x <= hi)) density += GLOW_BOX(spectra, table, k, 3) * GLOW_BOX(spectra, table, k, 7);
    }
    return density;
}

/* Where a light path starts: in a glowing medium (returns 1, *s the path leaving its vertex 0, already joined to
 * the camera), on a light (returns 0, u_pick->x remapped for the light's pick and *light_odds the probability of
 * that choice, which the light's path divides by), or nowhere (returns -1: a point outside the glow). */
inline int glowing_light_path_start(const Scene *scene, const SampledWavelengths *w, Sampler *sampler,
                                    float2 *u_pick, float2 u_direction, float *light_odds,
                                    __global const float4 *cmf, SplatRecords *records, PathState *s,
                                    uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int table = params->glow_table;
    if (table < 0) return 0;
    __global const float *spectra = scene->spectra;
    float share = spectra[table + 1];
    if (!(u_pick->x < share)) {
        *light_odds = 1.0f - share;
        u_pick->x = fmin((u_pick->x - share) / *light_odds, 0x1.fffffep-1f);
        return 0;
    }
    /* u_pick.x / share picks the box (the rest of it reused along the way), the other three place the point. */
    float u = u_pick->x / share;
    int n = (int)spectra[table];
    int k = 0;
    for (; k < n - 1; ++k) {
        float p = GLOW_BOX(spectra, table, k, 3);
        if (u < p) break;
        u -= p;
    }
    float3 lo = (float3)(GLOW_BOX(spectra, table, k, 0), GLOW_BOX(spectra, table, k, 1), GLOW_BOX(spectra, table, k, 2));
    float3 hi = (float3)(GLOW_BOX(spectra, table, k, 4), GLOW_BOX(spectra, table, k, 5), GLOW_BOX(spectra, table, k, 6));
    float3 x = clamp(lo + (hi - lo) * (float3)(u_pick->y, u_direction.x, u_direction.y), lo, hi);
    float pdf = share * glow_point_density(spectra, table, x);
    int medium = scene_medium_at(scene, x);
    float4 glow = medium_emission_at(scene, w, medium, x);
    if (!(pdf > 0.0f) || all(glow == (float4)(0.0f))) return -1;
    glow /= pdf;

    Ray ray;
    ray.origin = x;
    ray.direction = sample_uniform_sphere(sample_2d(sampler));
    *s = camera_path(ray);
    s->medium = medium;
    s->previous_point = x;
    s->throughput = glow * (4.0f * PI_F);

    CameraConnection c = connect_to_camera_sampled(params, x, lens_sample(params, sampler));
    if (c.pixel >= 0) {
        float4 value = glow * c.importance;
        value *= camera_transmittance(scene, w, medium, &c, x, path_query(sampler, s, QUERY_SHADOW), rays_traced);
        if (any(value != (float4)(0.0f))) record_splat(records, c.pixel, c.film, value, cmf, w, params);
    }
    return 1;
}

/* The glow a BDPT camera subpath gathers over its flight through `medium` toward the surface at hit_t (see the top
 * of this file), given its throughput `before` the flight; 0 for a light subpath (adjoint). */
inline float4 bdpt_glow_on_flight(const Scene *scene, const SampledWavelengths *w, __global const Medium *medium,
                                  const FreeFlight *flight, float4 before, float hit_t, int adjoint)
{
    if (adjoint || medium->emission < 0) return (float4)(0.0f);
    return before * (medium->grid >= 0 ? flight->emitted
                                       : medium_emitted_homogeneous(medium, scene->spectra, w, (float4)(1.0f), hit_t));
}

#endif
