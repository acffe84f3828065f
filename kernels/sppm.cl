/* Stochastic progressive photon mapping (Hachisuka & Jensen 2009, "Stochastic progressive photon mapping";
 * Hachisuka, Ogaki & Jensen 2008 for the progressive radius and flux update; pbrt-v4's SPPMIntegrator read as a
 * reference). It reaches what neither the path tracer nor BDPT can sample: light from a small or delta light that
 * passes smooth glass, lands on a diffuse surface and is seen through smooth glass again (paths L S+ D S+ E, the
 * spectrum on a screen seen through the prism's faces, a caustic seen through a glass).
 *
 * Each iteration (one pixel sample) has three steps:
 * 1. a photon pass (sppm_photon_pass): photon paths start on the lights as the light tracer's do
 *    (light_emission.cl), and at every vertex with a non-delta lobe reached after at least one bounce (light vertex
 *    i >= 2: the light's first surface is lit by next-event estimation instead) write a photon record: position,
 *    the direction the light came from, the geometric normal and the flux carried (W/nm per lane);
 *    and the hash bucket of its cell in a grid of cells as wide as the largest gather radius;
 * 2. the host sorts the record slots by bucket, stably, so each bucket lists its photons in a fixed order
 *    (spectrace.engine.sppm);
 * 3. a gather pass (sppm_gather_pass), one work-item per pixel: the pixel's camera path follows delta lobes to its
 *    first vertex with a non-delta lobe, the visible point, adding the emission it meets and next-event estimation
 *    at the visible point (unweighted: no BSDF sample leaves it) to the pixel's direct sum; then every photon
 *    within the pixel's radius r contributes Φ = Σ flux · f / |ωlight·ng| (the photon density is per geometric
 *    area), and the pixel's statistics follow the progressive update with α = 2/3:
 *      N' = N + αM, r' = r √(N'/(N + M)), τ' = (τ + β·Φ) r'²/r²,
 *    M the photons found and β the camera path's weight. The pixel's estimate after n iterations is
 *    direct/n + τ/(n·π r² · photons per iteration), which the kernel writes to the film times n, as the film's sums.
 *
 * Wavelengths: every camera and photon path of one iteration carries the same four wavelengths (sppm_wavelengths),
 * so a photon's lanes meet the visible point's lanes. At a dispersive event a path keeps only its hero lane, counted
 * 4 times (terminate_secondary); when both the camera path and the photon did so, the product counts it 16 times,
 * so it is divided by 4 (each of the two paths accounts for the same lane choice once).
 *
 * Every sum is made in a fixed order by one work-item, and the grid's cell lists are sorted on the host, so the
 * image is the same however the render is split into passes. */
#ifndef SPECTRACE_SPPM_CL
#define SPECTRACE_SPPM_CL

#include "light_tracer.cl"  /* the light paths' emission and adjoint BSDF weights */
#include "pixel_sample.cl"

/* The progressive radius reduction: the share of new photons kept (Hachisuka et al. 2008). */
#define SPPM_ALPHA (2.0f / 3.0f)

/* The four wavelengths every path of iteration `sample_index` carries: drawn from a stream of its own (the sampler
 * keyed by item `stream`, which no pixel or photon uses). */
inline SampledWavelengths sppm_wavelengths(__global const RenderParams *params, int stream, int sample_index)
{
    Sampler sampler = sampler_start((uint)params->seed, (uint)stream, (uint)sample_index);
    return sample_wavelengths(sample_1d(&sampler));
}

/* The grid cell of point p: cells of width cell_size from origin. */
inline int4 sppm_cell(float3 p, float3 origin, float cell_size)
{
    float3 c = floor((p - origin) / cell_size);
    return (int4)(convert_int3(c), 0);
}

/* The hash bucket of a cell (the primes of Teschner et al. 2003). The photon pass and the gather both use this one
 * function, so a photon is looked for in the bucket it was filed in. */
inline uint sppm_hash(int4 cell, uint table_size)
{
    uint h = ((uint)cell.x * 73856093u) ^ ((uint)cell.y * 19349663u) ^ ((uint)cell.z * 83492791u);
    return h % table_size;
}

/* Where a photon path's records go: slots [0, capacity) of its own. */
typedef struct {
    __global float4 *position;   /* xyz: the point, m; w: 1 when the path keeps only its hero lane */
    __global float4 *direction;  /* xyz: toward where the light came from; w: the light vertex index i */
    __global float4 *normal;     /* xyz: the geometric normal */
    __global float4 *flux;       /* W/nm per lane, divided by nothing (the host's photon count normalises) */
    __global uint *bucket;       /* the hash bucket of the record's grid cell; table_size for an unused slot */
    int capacity;
    int count;
    float3 origin;               /* the grid's: m */
    float cell_size;             /* m */
    uint table_size;
} PhotonRecords;

/* One photon path of iteration `sample_index`, number `item`; its sampler is keyed by `stream` (the film's pixel
 * count + item, so photons and pixels draw independent numbers). Paths with more records than the capacity stop
 * there (the host sizes the capacity from max_depth; beyond 16 bounces Russian roulette has ended nearly all). */
inline void trace_photon(const Scene *scene, int stream, int sample_index, const SampledWavelengths *w,
                         float4 scene_sphere, PhotonRecords *records, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    Sampler sampler = sampler_start((uint)params->seed, (uint)stream, (uint)sample_index);
    int last_segment = max_segments(params);
    float2 u_pick = sample_2d(&sampler);
    float2 u_direction = sample_2d(&sampler);
    if (params->light_count == 0) return;
    __global const Light *light = &scene->lights[pick_light_reusing(scene->light_cdf, params->light_count, &u_pick)];
    LightBuffers buffers = light_buffers(scene);
    EmissionSample e;
    if (!sample_emission(light, &buffers, w, scene_sphere, u_pick, u_direction, &e)) return;

    PathState s = camera_path(e.ray);
    s.throughput = e.weight;
    float4 scatter = (float4)(1.0f); /* the adjoint BSDF weights alone, for Russian roulette */
    /* s.segments: the light vertex index s.ray is about to reach. A photon there can close a path with a visible
     * point one camera segment away at the least, so it needs s.segments + 1 <= last_segment. */
    while (s.segments + 1 <= last_segment) {
        Hit hit = scene_intersect(scene, s.ray, path_query(&sampler, &s, QUERY_PATH), rays_traced);
        PathVertex v;
        int met = light_path_meets(scene, w, &s, hit, &v);
        if (met == LIGHT_PATH_ENDS) return;
        if (met == LIGHT_PATH_CROSSES) continue;
        __global const Material *material = &scene->materials[v.info.material];
        if (s.segments >= 2 && material_has_non_delta_lobe(material)) {
            if (records->count >= records->capacity) return;
            int k = records->count++;
            records->position[k] = (float4)(v.p, (float)s.secondary_terminated);
            records->direction[k] = (float4)(v.wo, (float)s.segments);
            records->normal[k] = (float4)(v.n, 0.0f);
            records->flux[k] = s.throughput;
            records->bucket[k] = sppm_hash(sppm_cell(v.p, records->origin, records->cell_size), records->table_size);
        }
        if (s.segments + 2 > last_segment) return;
        SurfaceContext sc = shading_context(scene, v.uv, v.p, v.footprint, v.ns_base, v.dpdu, v.tangent_w, 1);
        SURFACE_AT_HIT(sc, v);
        if (!continue_light_path(&v, material, &sc, w, params, &sampler, &s, &scatter)) return;
    }
}

/* The photon grid of an iteration, as the host built it: bucket b's photons are the record slots
 * order[cell_start[b] .. cell_start[b + 1]). */
typedef struct {
    __global const float4 *position;
    __global const float4 *direction;
    __global const float4 *normal;
    __global const float4 *flux;
    __global const int *order;       /* the records' slots, sorted by bucket (within one, in the order traced) */
    __global const int *cell_start;
    uint table_size;
    float3 origin;     /* m */
    float cell_size;   /* m, at least every pixel's radius */
} PhotonGrid;

/* Σ flux·f/|ωlight·ng| over the photons within r of the visible point v (camera path of `segments` segments, hero
 * only when camera_hero_only), and their number in *found. */
inline float4 gather_photons(const PhotonGrid *grid, const Scene *scene, const SampledWavelengths *w,
                             const PathVertex *v, __global const Material *material, const SurfaceContext *sc,
                             int segments, int camera_hero_only, float r, float *found)
{
    int last_segment = max_segments(scene->params);
    float4 phi = (float4)(0.0f);
    float count = 0.0f;
    int4 centre = sppm_cell(v->p, grid->origin, grid->cell_size);
    uint seen[27];
    int buckets = 0;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                uint b = sppm_hash(centre + (int4)(dx, dy, dz, 0), grid->table_size);
                /* Neighbouring cells may share a bucket: each bucket is visited once. */
                int repeated = 0;
                for (int k = 0; k < buckets; ++k) repeated |= seen[k] == b;
                if (repeated) continue;
                seen[buckets++] = b;
                for (int i = grid->cell_start[b]; i < grid->cell_start[b + 1]; ++i) {
                    int j = grid->order[i];
                    float4 pos = grid->position[j];
                    float3 d = pos.xyz - v->p;
                    if (dot(d, d) > r * r) continue;
                    float4 dir = grid->direction[j];
                    if (segments + (int)dir.w > last_segment) continue;
                    float3 n = grid->normal[j].xyz;
                    /* Photons on another surface (a thin wall's far side, a corner's other face) do not count. */
                    if (dot(n, v->n) < 0.5f) continue;
                    float3 wi = dir.xyz;
                    float cos_light = fabs(dot(wi, v->n));
                    if (!(cos_light > 0.0f) || !shading_side_agrees(v->n, v->ns, wi)) continue;
                    float4 f_cos = material_eval(material, sc, w, v->ns, v->wo, wi);
                    float4 contribution = grid->flux[j] * f_cos / cos_light;
                    if (camera_hero_only && pos.w > 0.5f) contribution *= 0.25f;
                    phi += contribution;
                    count += 1.0f;
                }
            }
    *found = count;
    return phi;
}

/* The pixel's state between iterations. */
typedef struct {
    __global float4 *direct;  /* Σ over iterations of emission seen and next-event estimation, film XYZ; w: dropped */
    __global float4 *tau;     /* τ, film XYZ (flux per photon emitted per iteration) */
    __global float *radius;   /* r, m; 0 before the pixel's first visible point */
    __global float *photons;  /* N */
} PixelStatistics;

/* Iteration `sample_index` of pixel `pixel`: its camera path, direct light and gather, then the statistics'
 * update and the film's sums. radius_per_metre: the initial radius per metre of camera path (a few pixels'
 * footprint); photons_per_iteration: photon paths traced per iteration. */
inline void sppm_gather(const Scene *scene, const PhotonGrid *grid, __global const float4 *cmf, int pixel,
                        int sample_index, const SampledWavelengths *w, float radius_per_metre,
                        float photons_per_iteration, PixelStatistics *stats, __global float4 *film,
                        uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    Sampler sampler;
    SampledWavelengths own;
    float weight;
    Ray ray = start_pixel_sample(params, cmf, pixel, sample_index, &sampler, &own, &weight);
    int last_segment = max_segments(params);
    PathState s = camera_path(ray);
    s.throughput = (float4)(weight);
    float4 direct = (float4)(0.0f);
    float4 gathered = (float4)(0.0f);  /* β·Φ */
    float found = 0.0f;
    float travelled = 0.0f;
    float r = stats->radius[pixel];
    int have_point = 0;
    while (s.segments <= last_segment) {
        Hit hit = scene_intersect(scene, s.ray, path_query(&sampler, &s, QUERY_PATH), rays_traced);
        if (hit.triangle < 0) {
            int hidden = (params->hide_emitters & HIDE_ENVIRONMENT) && s.segments == 1;
            if (SCENE_HAS_ENVIRONMENT && params->environment_light >= 0 && !hidden) {
                __global const Light *env = &scene->lights[params->environment_light];
                direct += s.throughput * environment_radiance(env, scene->spectra, scene->texels, w, s.ray.direction);
            }
            break;
        }
        travelled += hit.t;
        PathVertex v = path_vertex(scene, hit, s.ray);
        int live;
        if (record_surface_reached(&s, &v, hit.t, params, &live)) {
            if (!live) break;
            continue;
        }
        /* Every vertex the camera path reaches is reached through delta lobes: its emission counts whole. */
        if (v.info.light >= 0) direct += s.throughput * vertex_emission(scene, w, &v, hit);
        if (v.info.material == TRIANGLE_NO_MATERIAL) {
            if (!cross_null_boundary(&s, &v)) break;
            continue;
        }
        if (s.segments >= last_segment) break;
        __global const Material *material = &scene->materials[v.info.material];
        if (material_disperses(material, w)) terminate_secondary(&s.throughput, &s.secondary_terminated);
        SurfaceContext sc = shading_context(scene, v.uv, v.p, v.footprint, v.ns_base, v.dpdu, v.tangent_w, 0);
        SURFACE_AT_HIT(sc, v);
        if (material_has_non_delta_lobe(material)) {
            /* The visible point: no BSDF sample leaves it, so next-event estimation is not MIS-weighted. */
            direct += s.throughput * estimate_direct_light(scene, w, &sampler, v.p, v.n, v.ns, v.wo, material, &sc,
                                                           v.info.interior, s.medium, 0, path_query(&sampler, &s, QUERY_SHADOW), rays_traced);
            /* The first radius: a few pixel footprints, within the cell (less its margin). */
            if (r == 0.0f) r = fmin(radius_per_metre * travelled, 0.98f * grid->cell_size);
            float4 phi = gather_photons(grid, scene, w, &v, material, &sc, s.segments, s.secondary_terminated, r,
                                        &found);
            gathered = s.throughput * phi;
            have_point = 1;
            break;
        }
        float uc = sample_1d(&sampler);
        float2 u = sample_2d(&sampler);
        BSDFSample bs;
        if (!material_sample(material, &sc, w, v.ns, v.wo, uc, u, &bs) || !shading_side_agrees(v.n, v.ns, bs.wi))
            break;
        follow_bsdf_sample(&s, &v, &bs);
        if (all(s.throughput == (float4)(0.0f))) break;
        ++s.segments;
    }

    float4 sum = stats->direct[pixel];
    float4 direct_xyz = spectrum_to_xyz_estimate(direct, cmf, w);
    if (isfinite(direct_xyz.x) && isfinite(direct_xyz.y) && isfinite(direct_xyz.z)) {
        sum += direct_xyz;
    } else {
        sum.w += 1.0f;
    }
    stats->direct[pixel] = sum;

    float4 tau = stats->tau[pixel];
    if (have_point && found > 0.0f) {
        float n = stats->photons[pixel];
        float n_new = n + SPPM_ALPHA * found;
        float r_new = r * sqrt(n_new / (n + found));
        float4 phi_xyz = spectrum_to_xyz_estimate(gathered, cmf, w) / photons_per_iteration;
        if (!(isfinite(phi_xyz.x) && isfinite(phi_xyz.y) && isfinite(phi_xyz.z))) phi_xyz = (float4)(0.0f);
        float shrink = (r_new / r) * (r_new / r);
        tau = (tau + phi_xyz) * shrink;
        stats->tau[pixel] = tau;
        stats->photons[pixel] = n_new;
        r = r_new;
    }
    stats->radius[pixel] = r;
    /* The film's sums, which the host divides by the iterations done: n · (direct/n + τ/(n π r²)). */
    float4 indirect = r > 0.0f ? tau / (M_PI_F * r * r) : (float4)(0.0f);
    film[pixel] = (float4)(sum.xyz + indirect.xyz, sum.w);
}

#endif
