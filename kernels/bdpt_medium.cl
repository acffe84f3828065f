/* Bidirectional path tracing in homogeneous media (bdpt.cl): scattering points inside media are subpath vertices
 * like surface points, and every connection carries the media's transmittance.
 *
 * A subpath flies through a medium as the path tracer's camera paths and the light tracer's light paths do
 * (medium_sample_flight: one free flight for the four wavelengths, each lane weighted against their mixture); where
 * the flight ends before the next surface, the point is a vertex of kind BDPT_MEDIUM: no surface (n = 0, so the
 * area densities at it have no cosine), the Henyey–Greenstein phase function in place of the BSDF, for sampling the
 * next direction, for the MIS densities (the phase function is symmetric: its reverse density equals the forward
 * one) and for connections. The MIS weights leave the free-flight densities out, as pbrt-v3's BDPT does: every
 * strategy's weight is computed by the same function of the same path, so the weights still sum to one and the
 * estimate stays unbiased; only their balance ignores how likely each strategy was to stop at a medium vertex.
 * A light subpath starts in its light's medium (scene_medium_at); connections start in the medium on their side of
 * the vertex they leave (scene_transmittance); a light at infinity's subpath starts outside the scene, in none. A
 * camera subpath that leaves the scene does so through a flight that did not scatter, whose weight its throughput
 * carries to the environment's vertex. Included by bdpt.cl after BdptVertex, bdpt_to_area, bdpt_direction and
 * bdpt_extend_mis_sum. */
#ifndef SPECTRACE_BDPT_MEDIUM_CL
#define SPECTRACE_BDPT_MEDIUM_CL

#define BDPT_MEDIUM 3

#if SCENE_HAS_MEDIUM_EMISSION
inline float4 bdpt_hero(float4 value, int hero);
#endif

/* The medium a segment leaving vertex v along unit d starts in: a surface's side (medium_beyond of the medium its
 * subpath arrived in); a scattering point's, a light point's or the eye's own medium otherwise. */
inline int bdpt_side_medium(const BdptVertex *v, float3 d)
{
    if (v->kind == BDPT_SURFACE) return medium_beyond(v->interior, v->n, d, v->medium);
    return v->medium;
}

/* The medium around a light subpath's first vertex, on the side its light leaves (the front of a surface). */
inline int bdpt_light_medium(const Scene *scene, const BdptVertex *v)
{
    if (!SCENE_HAS_MEDIA || scene->params->medium_count == 0) return -1;
    return scene_medium_at(scene, all(v->n == (float3)(0.0f)) ? v->p : offset_ray_origin(v->p, v->n, v->n));
}

/* The phase function at medium vertex v for light travelling along `in` and leaving along `out` (unit vectors). */
inline float bdpt_phase(const Scene *scene, const BdptVertex *v, float3 in, float3 out)
{
    return henyey_greenstein(dot(in, out), scene->media[v->medium].g);
}

/* The fraction of light that crosses from vertex a to vertex b (each offset off its surface toward the other; b may
 * be a light at infinity, reached along its direction): 0 when a surface blocks it, the media's transmittance
 * between; in scenes without media the occlusion test. */
inline float4 bdpt_transmittance(const Scene *scene, const SampledWavelengths *w, const BdptVertex *a,
                                 const BdptVertex *b, uint query, uint *rays_traced)
{
    if (b->at_infinity) {
        float3 from = all(a->n == (float3)(0.0f)) ? a->p : offset_ray_origin(a->p, a->n, b->wo);
        return scene_transmittance(scene, w, bdpt_side_medium(a, b->wo), from, from, b->wo, 1, query, rays_traced);
    }
    float3 d = b->p - a->p;
    float dist = length(d);
    if (!(dist > 0.0f)) return (float4)(0.0f);
    d /= dist;
    float3 from = all(a->n == (float3)(0.0f)) ? a->p : offset_ray_origin(a->p, a->n, d);
    float3 to = all(b->n == (float3)(0.0f)) ? b->p : offset_ray_origin(b->p, b->n, -d);
    return scene_transmittance(scene, w, bdpt_side_medium(a, d), from, to, d, 0, query, rays_traced);
}

/* One free flight of a subpath in its medium toward the surface at hit_t. Returns 0 when it reaches the surface
 * (the throughput carries the flight's weight) or the subpath is outside media; 1 when it scattered: the point is
 * vertex path[*count] (*count then counts it) and the subpath goes on from it along a phase-sampled direction
 * (*pdf_dir its density); -1 when the subpath ends (no vertex left, Russian roulette, nothing carried). The vertex
 * before it gets its reverse density and running MIS sum as bdpt_walk's surfaces do; adjoint: a light subpath.
 * A camera subpath adds the glow of a glowing medium it crosses to *seen_through (light_glowing_media.cl). */
inline int bdpt_medium_step(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                            float hit_t, BdptVertex *path, int *count, int max_vertices, float *pdf_dir,
                            float4 *scatter, int hero, int adjoint, float light_share, float4 *seen_through)
{
    if (!SCENE_HAS_MEDIA || s->medium < 0) return 0;
    __global const Medium *medium = &scene->media[s->medium];
#if SCENE_HAS_MEDIUM_EMISSION
    float4 before = s->throughput;
#endif
    FreeFlight flight = path_free_flight(scene, w, sampler, s, medium, hit_t);
#if SCENE_HAS_MEDIUM_EMISSION
    *seen_through += bdpt_hero(bdpt_glow_on_flight(scene, w, medium, &flight, before, hit_t, adjoint), hero);
#endif
    *scatter *= flight.weight;
    if (all(s->throughput == (float4)(0.0f))) return -1;
    if (!flight.scattered) return 0;
    float3 travel = s->ray.direction;
    BdptVertex *v = &path[*count];
    BdptVertex *prev = &path[*count - 1];
    v->kind = BDPT_MEDIUM;
    v->p = s->ray.origin + flight.distance * travel;
    v->n = (float3)(0.0f);
    v->ns = v->n;
    v->wo = -travel;
    v->uv = (float2)(0.0f);
    v->footprint = 0.0f;
    v->beta = s->throughput;
    v->le = (float4)(0.0f);
    v->material = -1;
    v->light = -1;
    v->medium = s->medium;
    v->interior = -1;
    v->delta = 0;
    v->delta_light = 0;
    v->hero = hero;
    v->beam_pdf = 0.0f; /* before bdpt_to_area reads the vertex */
    v->at_infinity = 0;
    v->pdf_fwd = bdpt_to_area(*pdf_dir, prev, v);
    v->pdf_rev = 0.0f;
    v->mis_sum = 0.0f;
    ++*count;
    if (*count >= max_vertices) return -1;
    float3 next = sample_henyey_greenstein(travel, medium->g, sample_2d(sampler));
    *pdf_dir = henyey_greenstein(dot(travel, next), medium->g);
    prev->pdf_rev = bdpt_to_area(*pdf_dir, v, prev); /* the phase function is symmetric */
    bdpt_extend_mis_sum(path, *count - 2, adjoint, light_share);
    s->previous_point = v->p;
    s->ray.origin = v->p;
    s->ray.direction = next;
    if (*count - 1 >= scene->params->rr_depth / 4) { /* as bdpt_walk's surfaces */
        float4 t = *scatter;
        float q = fmin(fmax(fmax(t.x, t.y), fmax(t.z, t.w)), 0.95f);
        if (!(sample_1d(sampler) < q)) return -1;
        s->throughput /= q;
        *scatter /= q;
    }
    ++s->segments;
    return 1;
}

#endif
