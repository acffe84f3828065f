/* Bidirectional path tracing (Veach 1997, ch. 10; Veach & Guibas 1995): a light subpath and a camera subpath per
 * pixel sample, every pair of their prefixes (s light vertices, t camera vertices) joined into a full path, each
 * weighted by multiple importance sampling over all the strategies that could have made the same path. The MIS
 * weight uses the power heuristic evaluated, as in pbrt-v4's BDPT (Pharr, Jakob & Humphreys, "Physically Based
 * Rendering", 4th ed., sec. 13.4), from running ratios of the area densities with which each vertex is reached
 * forward (along the subpath that made it) and in reverse (from the other side); vertices reached by a delta lobe
 * or a delta light take part only through the strategies that can make them. Each walk keeps at every vertex the
 * sum of those ratios' squares up to it (mis_sum), so that a connection's weight costs O(1): the densities it
 * changes at the four vertices beside it, and the two sums beyond.
 *
 * Strategies (max_depth counts segments from the camera, as for the path tracer: s + t − 1 <= max_depth):
 * - s = 0: a camera vertex on an emitter (with t = 2 and s = 1 absent, an emitter seen directly weighs 1);
 * - s = 1: a point sampled on a light, by the same densities light paths start with (light_emission.cl), joined to a
 *   camera vertex: next-event estimation;
 * - t = 1: a light vertex joined to the camera, as the light tracer does (light_tracer.cl): its value lands in any
 *   pixel and is written as a splat record, reduced on the host in a fixed order;
 * - s, t >= 2: a light vertex joined to a camera vertex through a shadow ray.
 * The sum of each pixel's own strategies goes to the pixel's row of own_xyz. A work-item renders a pixel
 * sample of bdpt_pixels_per_light_path neighbouring pixels whose camera subpaths share one light subpath
 * (trace_bdpt): the light walk and the t = 1 joins are made once for those pixel samples, which the t = 1 strategy's
 * value and MIS weight count.
 *
 * Light subpath vertices use the adjoint BSDF (light_tracer.cl's conventions: the sample weight divided by the
 * radiance scale, Veach's shading-normal factor). A vertex's beta is its subpath's throughput as it arrives there:
 * importance (camera side, 1 at the eye) or flux (light side, 1/p at the light's point), all four wavelengths kept;
 * `hero` says a dispersive vertex lies on the subpath at or before it. A joined path with a hero vertex on either
 * side keeps its hero wavelength alone (×4, terminate_secondary), once, whatever the side; the MIS densities are
 * the hero wavelength's on both sides (the BSDFs draw dispersive directions for the hero).
 *
 * Vertices at infinity (pbrt-v4's infinite lights, Pharr et al. sec. 13.4): a distant or environment light's
 * subpath starts with a direction toward the light and a point on the disk of the scene's bounding sphere's radius R
 * across it (light_emission.cl): its first surface vertex has the area density 1/(πR²)·|cos| (no cosine at a vertex
 * a delta lobe leaves: per unit area across the beam, the projected-solid-angle measure of bdpt_to_area's chains),
 * its own point the density of its direction (pick included; a distant light's is a delta). A camera subpath that
 * leaves the scene ends on the environment, a vertex whose forward density is the solid angle one. The orthographic
 * camera's rays are parallel too: its eye vertex is a point of the view rectangle (density 1/A across the beam).
 *
 * Cameras: the pinhole, the thin lens (the eye vertex is the lens point, the t = 1 strategy draws its own
 * lens point as the light tracer does) and the orthographic camera (camera_importance.cl's connections).
 * Homogeneous media: bdpt_medium.cl (scattering points as vertices, transmittance on every connection, to a light
 * at infinity too). Glowing media: light_glowing_media.cl (the camera subpaths gather their glow). Fluorescent
 * surfaces: bdpt_fluorescence.cl (paths without a re-emission by every strategy, those with one by the path tracer
 * from the camera side). Subpaths hold at most BDPT_MAX_VERTICES vertices. */
#ifndef SPECTRACE_BDPT_CL
#define SPECTRACE_BDPT_CL

#include "light_tracer.cl"

/* max_depth 16 at most: a camera subpath of 17 vertices (the eye and 16 surfaces), a light one of 16. */
#define BDPT_MAX_SEGMENTS 16
#define BDPT_MAX_VERTICES (BDPT_MAX_SEGMENTS + 1)
/* Neighbouring pixels (in row-major order) whose camera subpaths share one light subpath (trace_bdpt), 1..16:
 * RenderParams.bdpt_pixels_per_light_path, which the host sets from the scene
 * (spectrace.integrators.bdpt.pixels_per_light_path); a run-time value, so that one program serves every grouping. */
inline int bdpt_pixels_per_light_path(__global const RenderParams *params)
{
    return params->bdpt_pixels_per_light_path;
}

/* Test builds only: BDPT_ONE_STRATEGY keeps the one strategy (RenderParams.bdpt_only_s, bdpt_only_t), a run-time
 * choice so that one program serves every strategy; BDPT_UNWEIGHTED drops the MIS weights, so that one strategy
 * alone estimates the light of paths of s + t − 1 segments by itself. */

#define BDPT_CAMERA 0
#define BDPT_LIGHT 1
#define BDPT_SURFACE 2

typedef struct {
    float3 p;           /* scene units; at infinity: a point on its ray (the disk point of a light's) */
    float3 n;           /* geometric normal; 0 for a point without a surface (eye, point and spot lights) */
    float3 ns;          /* shading normal (surfaces) */
    float3 ns_base;     /* surfaces: the shading normal before a normal or bump map turned it (PathVertex) */
    float3 dpdu;        /* surfaces: dp/du where the material's frame follows it, else 0 (PathVertex) */
    float tangent_w;    /* surfaces: dpdu's handedness (PathVertex) */
    float3 wo;          /* unit, back toward the previous vertex of its subpath (surfaces); at infinity: toward the
                           light, from the scene */
    float4 beta;        /* subpath throughput arriving here, per wavelength (see the top of the file) */
    float4 le;          /* camera vertices on emitters: radiance emitted toward wo, W/(m² sr nm) */
    float2 uv;          /* texture coordinates, or an analytic shape's own (u, v) */
    int triangle;       /* surfaces: the hit's triangle slot and barycentrics (PathVertex) */
    float2 b12;
    float footprint;    /* texture footprint in uv units */
    float pdf_fwd;      /* area density (1/m²) of reaching it along its own subpath; the light's point: pmf · p_A;
                           where `delta`, per projected solid angle at the vertex before (bdpt_to_area) */
    float pdf_fwd_area; /* where `delta`: pdf_fwd as an area density, for the strategies that end the subpath here
                           (bdpt_connection_end) */
    float pdf_rev;      /* area density of reaching it from the other side's next vertex */
    float mis_sum;      /* Σ r_i² over the strategies that would make this subpath's vertices 0 (light) or 1 (camera)
                           up to this one from the other side, r_i the product of pdf_rev / pdf_fwd from vertex i to
                           this one (both remapped): bdpt_mis_weight's sum for them, kept as the walk goes */
    float beam_pdf;     /* rays leaving it are parallel (lights at infinity, the orthographic camera): their density
                           per unit area across the beam, 1/m²; 0 otherwise */
    int kind;           /* BDPT_CAMERA, BDPT_LIGHT, BDPT_SURFACE, BDPT_MEDIUM (bdpt_medium.cl) */
    int delta;          /* its subpath left it by a delta lobe (of a BSDF that may have others: plastic's smooth coat
                           over its diffuse base); a strategy that joins it to the other side leaves it by the join
                           instead (bdpt_connection_end) */
    int delta_light;    /* a light's point with a delta position (point, spot) */
    int material;       /* surfaces: material index */
    int light;          /* index of the light it lies on, or -1 */
    int hero;           /* a dispersive vertex at or before it on its subpath */
    int medium;         /* the medium around it: a surface's subpath arrived in it (bdpt_medium.cl) */
    int interior;       /* surfaces: the shape's interior medium, or -1 */
    int at_infinity;    /* a distant or environment light's vertex (its direction in wo) */
#if SCENE_HAS_FLUORESCENCE
    float keep_camera, keep_light; /* surfaces: each side's probability of keeping a dye's base (bdpt_fluorescence.cl) */
#endif
} BdptVertex;

/* The density with which a solid-angle density pdf_dir at `from` reaches `to`, for the MIS ratios: the area density
 * at `to` (× |cos| at `to` / d², no cosine where `to` is a point without a surface), except where `to` is a vertex a
 * delta lobe left: then the density per projected solid angle at `from` (÷ |cos| at `from`). A chain of delta
 * vertices carries projected solid angle unchanged (the generalized geometry term between its ends is symmetric),
 * so two strategies' densities of a path through glass compare correctly in this measure, where areas at the
 * chain's inner vertices would not (they would favour the camera path that hits a small lamp through glass over
 * the light path that lights the screen, by the ratio of the two end segments' geometry terms). */
inline float bdpt_to_area(float pdf_dir, const BdptVertex *from, const BdptVertex *to)
{
    if (to->at_infinity) return pdf_dir; /* directions are its measure */
    if (from->beam_pdf > 0.0f) {
        float3 along = from->at_infinity ? -from->wo : to->p - from->p;
        float cos_to = (to->delta || all(to->n == (float3)(0.0f))) ? 1.0f : fabs(dot(to->n, normalize(along)));
        return from->beam_pdf * cos_to;
    }
    float3 d = to->p - from->p;
    float d2 = dot(d, d);
    if (!(d2 > 0.0f)) return 0.0f;
    if (to->delta) {
        float cos_from = all(from->n == (float3)(0.0f)) ? 1.0f : fabs(dot(from->n, d)) * rsqrt(d2);
        return cos_from > 0.0f ? pdf_dir / cos_from : 0.0f;
    }
    float cos_to = all(to->n == (float3)(0.0f)) ? 1.0f : fabs(dot(to->n, d)) * rsqrt(d2);
    return pdf_dir * cos_to / d2;
}

/* The area A = 4 |camera_right| |camera_up| of the image plane at unit distance (the orthographic camera's view
 * rectangle), camera_importance.cl. */
inline float camera_plane_area(__global const RenderParams *params)
{
    return 4.0f * length(params->camera_right.xyz) * length(params->camera_up.xyz);
}

/* The solid-angle density 1/(A cos³θ) of a camera ray along unit d (one the camera made) from its eye or lens point
 * (camera_importance.cl; pbrt-v4's PerspectiveCamera::PDF_We). */
inline float camera_direction_pdf(__global const RenderParams *params, float3 d)
{
    float cos_theta = dot(d, params->camera_forward.xyz);
    if (!(cos_theta > 0.0f)) return 0.0f;
    return 1.0f / (camera_plane_area(params) * cos_theta * cos_theta * cos_theta);
}

/* The unit direction from vertex a toward vertex b, either at infinity. */
inline float3 bdpt_direction(const BdptVertex *a, const BdptVertex *b)
{
    if (b->at_infinity) return b->wo;
    if (a->at_infinity) return -a->wo;
    return normalize(b->p - a->p);
}

/* Solid-angle density with which light `light`'s emission sampling (light_emission.cl) leaves its point (normal n,
 * 0 for point and spot lights) along unit d. */
inline float light_direction_pdf(__global const Light *light, __global const float4 *texels, float3 n, float3 d)
{
    if (LIGHT_ON_SURFACE(light)) return area_light_pdf_direction(light, n, d);
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_direction(light, texels, d);
    LIGHT_LIST_POSITION(X)
#undef X
    return 0.0f;
}

/* Radiance (intensity for point and spot lights) that light vertex v emits along unit d. */
inline float4 light_vertex_emitted(const Scene *scene, const SampledWavelengths *w, const BdptVertex *v, float3 d)
{
    __global const Light *light = &scene->lights[v->light];
    TextureBuffers textures = light_buffers(scene).textures;
    if (LIGHT_ON_SURFACE(light)) return area_light_emitted(light, &textures, w, v->n, d, v->uv);
    if (v->at_infinity) {
        /* a distant light's: its irradiance, W/(m² nm) */
#define X(name, NAME) \
        if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_radiance(light, scene->spectra, scene->texels, w, v->wo);
        LIGHT_LIST_INFINITE(X)
#undef X
        return (float4)(0.0f);
    }
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_intensity(light, &textures, w, d);
    LIGHT_LIST_POSITION(X)
#undef X
    return (float4)(0.0f);
}

/* Area density (pick included) with which a light subpath starts at surface vertex v of an emitter; for a vertex
 * at infinity, the density of its direction (solid angle). */
inline float light_origin_pdf(const Scene *scene, const BdptVertex *v)
{
    __global const Light *light = &scene->lights[v->light];
    if (v->at_infinity) {
        /* a delta direction's: its pick probability */
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_wi(light, scene->map_cdf, v->wo);
        LIGHT_LIST_INFINITE(X)
#undef X
        return 0.0f;
    }
#define X(name, NAME) if (LIGHT_IS(light, LIGHT_##NAME)) return light_##name##_pdf_point(light, scene->shapes, v->uv);
    LIGHT_LIST_AREA(X)
#undef X
    return 0.0f;
}

inline float bdpt_remap(float f) { return f != 0.0f ? f : 1.0f; }

/* Sets path[k].mis_sum once its pdf_rev is known (the walk has sampled vertex k + 1): S_k = ρ_k² (S_{k−1} + c_k),
 * ρ_k = pdf_rev / pdf_fwd (remapped), c_k = 1 where neither vertex k nor the one before it (a light's point: a delta
 * light) is delta, S_{−1} = 0 on a light subpath; a camera subpath's vertex 0 (the eye) takes no part, S_0 = 0.
 * A camera subpath's c_1 is the light-to-camera strategy's (t = 1), counted light_share² times: it has light_share
 * samples per pixel sample (bdpt_light_share; the power heuristic weighs n_i p_i). */
inline void bdpt_extend_mis_sum(BdptVertex *path, int k, int adjoint, float light_share)
{
    BdptVertex *v = &path[k];
    if (k == 0 && !adjoint) {
        v->mis_sum = 0.0f;
        return;
    }
    int before_delta = k == 0 ? v->delta_light : path[k - 1].delta;
    float before_sum = k == 0 ? 0.0f : path[k - 1].mis_sum;
    float rho = bdpt_remap(v->pdf_rev) / bdpt_remap(v->pdf_fwd);
    float c = (v->delta || before_delta) ? 0.0f : (k == 1 && !adjoint ? light_share * light_share : 1.0f);
    v->mis_sum = rho * rho * (before_sum + c);
}

/* Light subpaths per pixel sample, n_light / n_pixels: trace_bdpt traces one for each
 * bdpt_pixels_per_light_path pixels. */
inline float bdpt_light_share(__global const RenderParams *params)
{
    int pixels = params->width * params->height;
    int group = bdpt_pixels_per_light_path(params);
    return (float)((pixels + group - 1) / group) / (float)pixels;
}

#include "bdpt_medium.cl"
#if SCENE_HAS_FLUORESCENCE
#include "bdpt_fluorescence.cl"
#endif

/* A light's point as the origin of a light subpath, from one 2D draw that picks the light and then the point
 * (pick_light_reusing; the position part of sample_emission), or for a light at infinity its direction (an
 * environment's drawn as next-event estimation draws it): 0 when the light gives nothing. beta = 1 / pdf_fwd.
 * beam_pdf: 1/(πR²) for the scene's bounding sphere of radius R. */
inline int sample_light_origin(const Scene *scene, float2 u_position, float beam_pdf, BdptVertex *v)
{
    __global const RenderParams *params = scene->params;
    if (params->light_count == 0) return 0;
    int index = pick_light_reusing(scene->light_cdf, params->light_count, &u_position);
    __global const Light *light = &scene->lights[index];
    if (!(light->pmf > 0.0f)) return 0;
    v->kind = BDPT_LIGHT;
    v->light = index;
    v->material = -1;
    v->delta = 0;
    v->hero = 0;
    v->uv = (float2)(0.0f);
    v->footprint = 0.0f;
    v->pdf_fwd = 0.0f;
    v->pdf_rev = 0.0f;
    v->mis_sum = 0.0f;
    v->beam_pdf = 0.0f;
    v->at_infinity = 0;
    v->le = (float4)(0.0f);
    v->wo = (float3)(0.0f);
    if (LIGHT_ON_SURFACE(light)) {
        LightBuffers buffers = light_buffers(scene);
        float pdf_area = 0.0f;
#define X(name, NAME) \
        if (LIGHT_IS(light, LIGHT_##NAME)) pdf_area = light_##name##_sample_point(light, &buffers, u_position, &v->p, &v->n, &v->uv);
        LIGHT_LIST_AREA(X)
#undef X
        if (!(pdf_area > 0.0f) || !isfinite(pdf_area)) return 0;
        v->ns = v->n;
        v->ns_base = v->n;
        v->delta_light = 0;
        v->pdf_fwd = light->pmf * pdf_area;
    } else if (LIGHT_KIND_POSITION(light)) {
        v->p = light->position.xyz;
        v->n = (float3)(0.0f);
        v->ns = v->n;
        v->ns_base = v->n;
        v->delta_light = 1;
        v->pdf_fwd = light->pmf;
    } else {
        v->at_infinity = 1;
        v->beam_pdf = beam_pdf;
        v->n = (float3)(0.0f);
        v->ns = v->n;
        v->ns_base = v->n;
        v->p = (float3)(0.0f); /* set where a subpath starts from it */
        /* a delta direction: its own, at its pick probability */
        v->delta_light = 0;
#define X(name, NAME)                                                                      \
        if (LIGHT_IS(light, LIGHT_##NAME)) {                                               \
            v->wo = light_##name##_sample_wi(light, scene->map_cdf, u_position, &v->pdf_fwd); \
            v->delta_light = LIGHT_##NAME##_DELTA;                                         \
        }
        LIGHT_LIST_INFINITE(X)
#undef X
        if (!(v->pdf_fwd > 0.0f)) return 0;
    }
    v->beta = (float4)(1.0f / v->pdf_fwd);
    v->interior = -1;
    v->medium = v->at_infinity ? -1 : bdpt_light_medium(scene, v); /* at infinity: from outside the scene */
    return 1;
}

/* The environment's vertex at infinity where a camera subpath leaves the scene along s->ray, having left its last
 * vertex with solid-angle density pdf_dir: 1 when the scene has an environment, 0 otherwise. */
inline int bdpt_environment_vertex(const Scene *scene, const SampledWavelengths *w, const PathState *s, float pdf_dir,
                                   int hero, float beam_pdf, BdptVertex *v)
{
#if SCENE_HAS_ENVIRONMENT
    __global const RenderParams *params = scene->params;
    if (params->environment_light < 0) return 0;
    v->kind = BDPT_LIGHT;
    v->light = params->environment_light;
    v->material = -1;
    v->p = s->ray.origin + s->ray.direction;
    v->n = (float3)(0.0f);
    v->ns = v->n;
    v->ns_base = v->n;
    v->wo = s->ray.direction;
    v->beta = s->throughput;
    v->le = environment_radiance(&scene->lights[v->light], scene->spectra, scene->texels, w, v->wo);
    v->uv = (float2)(0.0f);
    v->footprint = 0.0f;
    v->pdf_fwd = pdf_dir;
    v->pdf_rev = 0.0f;
    v->mis_sum = 0.0f;
    v->beam_pdf = beam_pdf;
    v->delta = 0;
    v->delta_light = 0;
    v->hero = hero;
    v->at_infinity = 1;
    v->medium = -1;
    v->interior = -1;
    return 1;
#else
    return 0;
#endif
}

/* Defined below, where the strategies are joined; the walk counts the lights it sees through with them. */
inline float bdpt_mis_weight(const Scene *scene, const SampledWavelengths *w, const BdptVertex *light,
                             const BdptVertex *camera, const BdptVertex *sampled, int s, int t, float3 to_q,
                             float camera_rev, float light_share);
inline float4 bdpt_hero(float4 value, int hero);
inline int bdpt_keeps(__global const RenderParams *params, int s, int t);

/* Follows a subpath from its first vertex path[0] along ray (leaving with solid-angle density pdf_dir and
 * throughput beta) until it has max_vertices vertices, leaves the scene, or Russian roulette or a BSDF ends it.
 * adjoint: a light subpath (the adjoint BSDF). A camera subpath that leaves the scene ends on the environment's
 * vertex at infinity, when the scene has one (beam_pdf: its disk's density, 1/(πR²)). Returns the vertex count.
 *
 * A surface without material (a medium's index-matched boundary, a light seen through: Mitsuba's null bsdf) is no
 * vertex: both subpaths cross it unchanged. A light there is still met by the camera subpath, as the path tracer
 * meets it: that strategy (s = 0, with the path so far and the light's point as its last vertex, built in
 * path[count] and then left to be overwritten) is weighted here and added to *seen_through; the strategies that
 * reach the same point as a light vertex count it among theirs, as for any light. A camera subpath's re-emission at
 * a fluorescent surface ends it, the path tracer's estimate of the rest added to *seen_through too
 * (bdpt_fluorescence.cl). */
inline int bdpt_walk(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray, float4 beta,
                     float pdf_dir, int adjoint, BdptVertex *path, int max_vertices, uint query_base,
                     float beam_pdf, float light_share, float4 *seen_through, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    PathState s = camera_path(ray);
    s.throughput = beta;
    s.medium = path[0].medium;
    float4 scatter = (float4)(1.0f);
    int count = 1;
    int hero = 0;
    while (count < max_vertices) {
        Hit hit = scene_intersect(scene, s.ray, path_query(sampler, &s, QUERY_PATH) ^ query_base, rays_traced);
        if (!adjoint) hit = far_clipped(params, &s, hit);
        int in_medium = bdpt_medium_step(scene, w, sampler, &s, hit.t, path, &count, max_vertices, &pdf_dir,
                                         &scatter, hero, adjoint, light_share, seen_through);
        if (in_medium < 0) break;
        if (in_medium > 0) continue;
        if (hit.triangle < 0) {
            /* Left the scene: in a medium only through a flight that did not scatter (its weight in the throughput). */
            if (!adjoint) count += bdpt_environment_vertex(scene, w, &s, pdf_dir, hero, beam_pdf, &path[count]);
            break;
        }
        PathVertex pv = path_vertex(scene, hit, s.ray);
        int seen_light = !adjoint && pv.info.material == TRIANGLE_NO_MATERIAL && pv.info.light >= 0;
        if (pv.info.material == TRIANGLE_NO_MATERIAL && !seen_light) {
            if (!cross_null_boundary(&s, &pv)) break;
            continue;
        }
        BdptVertex *v = &path[count];
        BdptVertex *prev = &path[count - 1];
        v->kind = BDPT_SURFACE;
        v->p = pv.p;
        v->n = pv.n;
        v->ns = pv.ns;
        v->ns_base = pv.ns_base;
        v->dpdu = pv.dpdu;
        v->tangent_w = pv.tangent_w;
        v->wo = pv.wo;
        v->uv = pv.uv;
        v->triangle = pv.triangle;
        v->b12 = pv.b12;
        v->footprint = pv.footprint;
        v->beta = s.throughput;
        v->material = pv.info.material;
        v->light = pv.info.light;
        v->medium = s.medium;
        v->interior = pv.info.interior;
        v->le = (float4)(0.0f);
        if (!adjoint && pv.info.light >= 0) v->le = vertex_emission(scene, w, &pv, hit);
        v->delta = 0;
        v->delta_light = 0;
        v->beam_pdf = 0.0f;
        v->at_infinity = 0;
        v->pdf_fwd = bdpt_to_area(pdf_dir, prev, v);
        v->pdf_rev = 0.0f;
        v->mis_sum = 0.0f;
#if SCENE_HAS_FLUORESCENCE
        bdpt_dye_resolve(scene, w, &pv, v);
#endif
        if (seen_light) {
            v->hero = hero;
            if (bdpt_keeps(scene->params, 0, count + 1) && any(v->le != (float4)(0.0f))) {
                float weight = bdpt_mis_weight(scene, w, path, path, 0, 0, count + 1, (float3)(0.0f), 0.0f,
                                               light_share);
                *seen_through += bdpt_hero(v->beta * v->le, hero) * weight;
            }
            if (!cross_null_boundary(&s, &pv)) break;
            continue;
        }
        ++count;
        __global const Material *material = &scene->materials[v->material];
        if (material_disperses(material, w)) hero = 1;
        v->hero = hero;
        if (count >= max_vertices) break;
#if SCENE_HAS_FLUORESCENCE
        if (bdpt_dye_choice(scene, w, sampler, &s, &pv, adjoint, &scatter, seen_through, rays_traced)) break;
#endif
        SurfaceContext sc = shading_context(scene, pv.uv, pv.p, pv.footprint,
                                            pv.ns_base, pv.dpdu, pv.tangent_w, adjoint);
        SURFACE_AT_HIT(sc, pv);
        float uc = sample_1d(sampler);
        float2 u = sample_2d(sampler);
        BSDFSample bs;
        if (!material_sample(material, &sc, w, pv.ns, pv.wo, uc, u, &bs) || !shading_side_agrees(pv.n, pv.ns, bs.wi))
            break;
        float4 weight = bs.weight;
        if (adjoint) weight *= shading_normal_adjoint(pv.n, pv.ns, pv.wo, bs.wi) / bs.radiance_scale;
        float pdf_reverse = 0.0f;
        if (bs.is_delta) {
            v->delta = 1;
            v->pdf_fwd_area = v->pdf_fwd;
            v->pdf_fwd = bdpt_to_area(pdf_dir, prev, v); /* now per projected solid angle at prev */
            pdf_dir = 0.0f;
        } else {
            pdf_dir = bs.pdf;
            pdf_reverse = material_pdf(material, &sc, w, pv.ns, bs.wi, pv.wo);
        }
#if SCENE_HAS_FLUORESCENCE
        pdf_dir *= bdpt_dye_keep(v, adjoint);
        pdf_reverse *= bdpt_dye_keep(v, !adjoint);
#endif
        prev->pdf_rev = bdpt_to_area(pdf_reverse, v, prev);
        bdpt_extend_mis_sum(path, count - 2, adjoint, light_share);
        s.throughput *= weight;
        scatter *= weight / (adjoint ? 1.0f : bs.radiance_scale);
        s.previous_point = pv.p;
        s.medium = medium_beyond(pv.info.interior, pv.n, bs.wi, s.medium);
        s.ray.origin = offset_ray_origin(pv.p, pv.n, bs.wi);
        s.ray.direction = bs.wi;
        /* Russian roulette with the path tracer's survival min(max weight, 0.95), on the BSDF weights without
         * refraction's radiance compression, from a quarter of rr_depth (the first surface vertex for the default
         * 5): a BDPT sample joins every vertex of one subpath to every vertex of the other, so a deep vertex costs
         * more rays than a path tracer's. Measured on the Cornell box (max_depth 8, rr_depth 5): 17.7 rays per
         * sample from rr_depth, 10.9 from half of it, 9.4 from a quarter, whose MSE × time was 17 % lower than
         * from half. */
        if (count - 1 >= params->rr_depth / 4) {
            float q = fmin(fmax(fmax(scatter.x, scatter.y), fmax(scatter.z, scatter.w)), 0.95f);
            if (!(sample_1d(sampler) < q)) break;
            s.throughput /= q;
            scatter /= q;
        }
        if (all(s.throughput == (float4)(0.0f))) break;
        ++s.segments;
    }
    return count;
}

/* The density with which surface or medium vertex v, arrived at from unit direction wo (toward the vertex before
 * it), samples unit wi toward vertex `next` (the BSDF's, or the phase function's), as an area density at next. The
 * caller passes the directions it knows (a vertex's own wo, the connection's), which a join would otherwise
 * normalise again for each of its four densities. */
inline float bdpt_vertex_pdf(const Scene *scene, const SampledWavelengths *w, const BdptVertex *v, float3 wo,
                             float3 wi, const BdptVertex *next)
{
    if (v->kind == BDPT_MEDIUM) return bdpt_to_area(bdpt_phase(scene, v, -wo, wi), v, next);
    __global const Material *material = &scene->materials[v->material];
    SurfaceContext sc = surface_context(scene, v->uv, v->footprint);
    SURFACE_AT_HIT(sc, *v);
    sc.p = v->p;
    sc.dpdu = v->dpdu;
    sc.tangent_w = v->tangent_w;
    return bdpt_to_area(material_pdf(material, &sc, w, v->ns, wo, wi), v, next);
}

/* The area density at next of the light's emission leaving its point v along unit d toward next (from a light at
 * infinity: its disk's density across the beam, d unused). */
inline float bdpt_light_pdf(const Scene *scene, const BdptVertex *v, float3 d, const BdptVertex *next)
{
    if (v->at_infinity) return bdpt_to_area(0.0f, v, next);
    return bdpt_to_area(light_direction_pdf(&scene->lights[v->light], scene->texels, v->n, d), v, next);
}

/* Vertex v as the last vertex of its subpath in a strategy that joins it to the other side (or, on a camera subpath,
 * ends it on an emitter): the join, not the lobe the walk sampled there, leaves it, so it is no delta vertex of that
 * path, and its densities are area densities, as the reverse ones the join gives it are. A BSDF with a delta lobe
 * beside others (smooth plastic) has delta set at some vertices only; read as delta, such a vertex's ratio would
 * compare a projected-solid-angle density with an area one, and the weights of a path would sum to more than one.
 * pbrt-v4's BDPT MIS weight clears both ends' delta flags alike. */
inline BdptVertex bdpt_connection_end(const BdptVertex *v)
{
    BdptVertex end = *v;
    if (end.delta) {
        end.delta = 0;
        end.pdf_fwd = end.pdf_fwd_area;
    }
    return end;
}

/* The MIS weight (power heuristic) of strategy (s, t) for the path its vertices make: light[0 .. s-1] (light[0]
 * replaced by *sampled when s = 1) and camera[0 .. t-1]. The densities the strategy changes at the four vertices
 * beside the connection are computed here; the subpaths' stored ones serve for the rest. to_q: the unit direction
 * from camera[t − 1] (the camera, t = 1) toward the light side's vertex joined to it (s >= 1). camera_rev (t = 1): the
 * area density at light[s-1] of the camera's ray through it, from the lens point the connection drew. */
inline float bdpt_mis_weight(const Scene *scene, const SampledWavelengths *w, const BdptVertex *light,
                             const BdptVertex *camera, const BdptVertex *sampled, int s, int t, float3 to_q,
                             float camera_rev, float light_share)
{
#ifdef BDPT_UNWEIGHTED
    return 1.0f;
#endif
    if (s + t == 2) return 1.0f;
    BdptVertex qs_end, pt_end = bdpt_connection_end(&camera[t - 1]);
    if (s > 0) qs_end = bdpt_connection_end(s == 1 ? sampled : &light[s - 1]);
    const BdptVertex *qs = s > 0 ? &qs_end : 0;
    const BdptVertex *qs_minus = s > 1 ? &light[s - 2] : 0;
    const BdptVertex *pt = &pt_end;
    const BdptVertex *pt_minus = t > 1 ? &camera[t - 2] : 0;

    /* Reverse densities the connection gives. */
    float pt_rev = 0.0f, pt_minus_rev = 0.0f, qs_rev = 0.0f, qs_minus_rev = 0.0f;
    if (t > 1) {
        /* pt and qs (s >= 2) are surface or medium vertices: their wo points back along their own subpaths. */
        if (s == 0) pt_rev = light_origin_pdf(scene, pt);
        else if (s == 1) pt_rev = bdpt_light_pdf(scene, qs, -to_q, pt);
        else pt_rev = bdpt_vertex_pdf(scene, w, qs, qs->wo, -to_q, pt);
        if (s == 0) pt_minus_rev = bdpt_light_pdf(scene, pt, pt->wo, pt_minus);
        else pt_minus_rev = bdpt_vertex_pdf(scene, w, pt, to_q, pt->wo, pt_minus);
    }
    if (s > 0) {
        if (t == 1) qs_rev = camera_rev;
        else qs_rev = bdpt_vertex_pdf(scene, w, pt, pt->wo, to_q, qs);
        if (s > 1) qs_minus_rev = bdpt_vertex_pdf(scene, w, qs, -to_q, qs->wo, qs_minus);
    }
#if SCENE_HAS_FLUORESCENCE
    bdpt_dye_join_pdfs(pt, qs, s, t, &pt_rev, &pt_minus_rev, &qs_rev, &qs_minus_rev);
#endif

    /* The ratios at the two vertices either side of the connection and their neighbours, then the rest of each
     * subpath's sum as its walk kept it (mis_sum): O(1) per strategy. */
    float sum = 0.0f;
    float t1 = light_share * light_share; /* the light-to-camera strategy's n² (bdpt_extend_mis_sum) */
    if (t > 1) {
        float r = bdpt_remap(pt_rev) / bdpt_remap(pt->pdf_fwd);
        if (!camera[t - 2].delta) sum += r * r * (t == 2 ? t1 : 1.0f);
        if (t > 2) {
            r *= bdpt_remap(pt_minus_rev) / bdpt_remap(pt_minus->pdf_fwd);
            if (!pt_minus->delta && !camera[t - 3].delta) sum += r * r * (t == 3 ? t1 : 1.0f);
            if (t > 3) sum += r * r * camera[t - 3].mis_sum;
        }
    }
    if (s > 0) {
        float r = bdpt_remap(qs_rev) / bdpt_remap(qs->pdf_fwd);
        if (!(s > 1 ? qs_minus->delta : qs->delta_light)) sum += r * r;
        if (s > 1) {
            r *= bdpt_remap(qs_minus_rev) / bdpt_remap(qs_minus->pdf_fwd);
            if (!qs_minus->delta && !(s > 2 ? light[s - 3].delta : light[0].delta_light)) sum += r * r;
            if (s > 2) sum += r * r * light[s - 3].mis_sum;
        }
    }
    if (t == 1) sum /= t1; /* relative to its own n² */
    return 1.0f / (1.0f + sum);
}

/* Keeps the hero wavelength alone (×4) when either side's vertex says the path dispersed. */
inline float4 bdpt_hero(float4 value, int hero)
{
    int hero_only = 0;
    if (hero) terminate_secondary(&value, &hero_only);
    return value;
}

inline int bdpt_keeps(__global const RenderParams *params, int s, int t)
{
#ifdef BDPT_ONE_STRATEGY
    return s == params->bdpt_only_s && t == params->bdpt_only_t;
#else
    return 1;
#endif
}

/* The camera's own vertex for a pixel sample's camera ray: the eye (pinhole), the lens point the ray left from
 * (thin lens), or the point of the orthographic camera's view rectangle (parallel rays, density 1/A across them);
 * near clipping moved the ray's origin forward along it. */
inline void bdpt_camera_vertex(__global const RenderParams *params, Ray ray, float filter_weight, BdptVertex *v)
{
    float near = params->camera_origin.w;
    v->kind = BDPT_CAMERA;
    v->p = ray.origin - (near / dot(ray.direction, params->camera_forward.xyz)) * ray.direction;
    if (CAMERA_IS(params, CAMERA_PERSPECTIVE)) v->p = params->camera_origin.xyz;
    v->n = (float3)(0.0f);
    v->ns = v->n;
    v->ns_base = v->n;
    v->wo = v->n;
    v->beta = (float4)(filter_weight);
    v->le = (float4)(0.0f);
    v->uv = (float2)(0.0f);
    v->footprint = 0.0f;
    v->pdf_fwd = 1.0f;
    v->pdf_rev = 0.0f;
    v->mis_sum = 0.0f;
    v->beam_pdf = CAMERA_IS(params, CAMERA_ORTHOGRAPHIC) ? 1.0f / camera_plane_area(params) : 0.0f;
    v->delta = 0;
    v->delta_light = 0;
    v->material = -1;
    v->light = -1;
    v->hero = 0;
    v->at_infinity = 0;
    v->medium = -1; /* cameras stand outside every medium */
    v->interior = -1;
}

/* Starts the light subpath from light[0] (sample_light_origin's): the ray leaving it, with its solid-angle density
 * and the flux it carries; a light at infinity's from a point on its disk across the scene's bounding sphere
 * (centre xyz, radius w), as sample_emission draws it. 0 when nothing leaves. */
inline int bdpt_light_ray(const Scene *scene, const SampledWavelengths *w, float4 scene_sphere, float2 u_direction,
                          BdptVertex *origin, Ray *ray, float *pdf_dir, float4 *flux)
{
    __global const Light *l = &scene->lights[origin->light];
    if (origin->at_infinity) {
        float3 travel = -origin->wo;
        float r = scene_sphere.w;
        origin->p = sample_disk_across(scene_sphere.xyz - r * travel, travel, r, u_direction);
        ray->origin = origin->p;
        ray->direction = travel;
        *pdf_dir = 0.0f; /* unused: the first vertex's density is the disk's (bdpt_to_area) */
        *flux = light_vertex_emitted(scene, w, origin, travel) * origin->beta / origin->beam_pdf;
        return any(*flux != (float4)(0.0f));
    }
    float3 d;
    if (LIGHT_ON_SURFACE(l)) {
        float side;
        d = area_light_sample_direction(l, origin->n, u_direction, &side);
    } else {
        d = (float3)(0.0f);
#define X(name, NAME) if (LIGHT_IS(l, LIGHT_##NAME)) d = light_##name##_sample_direction(l, scene->texels, u_direction);
        LIGHT_LIST_POSITION(X)
#undef X
    }
    *pdf_dir = light_direction_pdf(l, scene->texels, origin->n, d);
    float cos_light = LIGHT_ON_SURFACE(l) ? fabs(dot(origin->n, d)) : 1.0f;
    *flux = light_vertex_emitted(scene, w, origin, d) * (cos_light / *pdf_dir) * origin->beta;
    ray->origin = LIGHT_ON_SURFACE(l) ? offset_ray_origin(origin->p, origin->n, d) : origin->p;
    ray->direction = d;
    return *pdf_dir > 0.0f && any(*flux != (float4)(0.0f));
}

/* Strategy (s, 1), s >= 2: light vertex light[s − 1] joined to the camera (a lens point drawn from the sampler),
 * written as a splat record for the pixel it lands in. */
inline void bdpt_splat(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, const BdptVertex *light,
                       const BdptVertex *camera, int s, float light_share, __global const float4 *cmf,
                       SplatRecords *records, uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    uint query = opacity_query(sampler, ((uint)s << 8) ^ 1u, QUERY_SHADOW);
    const BdptVertex *qs = &light[s - 1];
    if (qs->kind == BDPT_MEDIUM) {
        CameraConnection c = connect_to_camera_sampled(params, qs->p, lens_sample(params, sampler));
        if (c.pixel < 0) return;
        float4 value = qs->beta * (bdpt_phase(scene, qs, -qs->wo, c.to_camera) * c.importance);
        if (all(value == (float4)(0.0f))) return;
        value *= camera_transmittance(scene, w, qs->medium, &c, qs->p, query, rays_traced);
        if (all(value == (float4)(0.0f))) return;
        /* No surface at qs: the camera's area density there has no cosine. */
        float weight =
            bdpt_mis_weight(scene, w, light, camera, 0, s, 1, -c.to_camera, c.importance, light_share) / light_share;
        record_splat(records, c.pixel, c.film, bdpt_hero(value, qs->hero) * weight, cmf, w, params);
        return;
    }
    if (qs->kind != BDPT_SURFACE || qs->material < 0) return;
    __global const Material *material = &scene->materials[qs->material];
    if (!material_has_non_delta_lobe(material)) return;
    CameraConnection c = connect_to_camera_sampled(params, qs->p, lens_sample(params, sampler));
    if (c.pixel < 0 || !shading_side_agrees(qs->n, qs->ns, c.to_camera)) return;
    SurfaceContext sc = shading_context(scene, qs->uv, qs->p, qs->footprint, qs->ns_base, qs->dpdu, qs->tangent_w, 0);
    SURFACE_AT_HIT(sc, *qs);
    float4 f_cos = material_eval(material, &sc, w, qs->ns, c.to_camera, qs->wo);
    float cos_light = fabs(dot(qs->wo, qs->n));
    float cos_camera = fabs(dot(c.to_camera, qs->n));
    float cosines = cos_light > 0.0f ? cos_camera / cos_light : 0.0f;
    float4 value = qs->beta * f_cos * (cosines * c.importance);
    if (all(value == (float4)(0.0f))) return;
    value *= camera_transmittance(scene, w, medium_beyond(qs->interior, qs->n, c.to_camera, qs->medium),
                                  &c, offset_ray_origin(qs->p, qs->n, c.to_camera), query, rays_traced);
    if (all(value == (float4)(0.0f))) return;
    /* The camera's density of its ray through qs, as an area density there: c.importance holds the
     * direction's 1/(A cos³θ) over d² (1/A for the orthographic camera's parallel rays). */
    float weight = bdpt_mis_weight(scene, w, light, camera, 0, s, 1, -c.to_camera, c.importance * cos_camera,
                                   light_share) /
                   light_share;
    record_splat(records, c.pixel, c.film, bdpt_hero(value, qs->hero) * weight, cmf, w, params);
}

/* The camera vertex pt = camera[t − 1], t >= 2, can be joined to a light vertex: a surface with a non-delta lobe, or
 * a scattering point. */
inline int bdpt_joinable(const Scene *scene, const BdptVertex *pt)
{
    if (pt->kind == BDPT_MEDIUM) return 1;
    return pt->kind == BDPT_SURFACE && pt->material >= 0 && material_has_non_delta_lobe(&scene->materials[pt->material]);
}

/* Strategy (s, t), s >= 1, t >= 2, its camera vertex joinable (bdpt_joinable): the value of the path joining
 * qs (next-event estimation's light point when s = 1, light[s − 1] otherwise) to camera[t − 1] through a shadow
 * ray (opacity `query`), weighted by MIS; 0 where the join gives nothing. */
inline float4 bdpt_connect(const Scene *scene, const SampledWavelengths *w, const BdptVertex *light,
                           const BdptVertex *camera, const BdptVertex *qs, int s, int t, uint query, float light_share,
                           uint *rays_traced)
{
    const BdptVertex *pt = &camera[t - 1];
    int pt_medium = pt->kind == BDPT_MEDIUM;
    __global const Material *pm = &scene->materials[pt_medium ? 0 : pt->material];
    if (s > 1 && qs->kind != BDPT_MEDIUM) {
        if (qs->kind != BDPT_SURFACE || qs->material < 0) return (float4)(0.0f);
        if (!material_has_non_delta_lobe(&scene->materials[qs->material])) return (float4)(0.0f);
    }
    /* G's distance and the light's cosine: none toward a light at infinity (a solid angle measure). */
    float3 to_q;
    float g = 1.0f;
    if (qs->at_infinity) {
        to_q = qs->wo;
    } else {
        float3 d = qs->p - pt->p;
        float d2 = dot(d, d);
        if (!(d2 > 0.0f)) return (float4)(0.0f);
        to_q = d * rsqrt(d2);
        g = (all(qs->n == (float3)(0.0f)) ? 1.0f : fabs(dot(qs->n, to_q))) / d2;
    }
    /* The geometric rejections of both ends first, then the BSDFs: a join that gives nothing costs no evaluation. */
    int qs_surface = s > 1 && qs->kind != BDPT_MEDIUM;
    float cos_in = qs_surface ? fabs(dot(qs->wo, qs->n)) : 1.0f;
    if (qs_surface && (!(cos_in > 0.0f) || !shading_side_agrees(qs->n, qs->ns, -to_q))) return (float4)(0.0f);
    if (!pt_medium && !shading_side_agrees(pt->n, pt->ns, to_q)) return (float4)(0.0f);
    float4 f_p;
    if (pt_medium) {
        f_p = (float4)(bdpt_phase(scene, pt, -to_q, pt->wo));
    } else {
        SurfaceContext psc = shading_context(scene, pt->uv, pt->p, pt->footprint,
                                             pt->ns_base, pt->dpdu, pt->tangent_w, 0);
        SURFACE_AT_HIT(psc, *pt);
        f_p = material_eval(pm, &psc, w, pt->ns, pt->wo, to_q);
    }
    if (all(f_p == (float4)(0.0f))) return (float4)(0.0f);
    float4 f_q;
    if (s == 1) {
        f_q = light_vertex_emitted(scene, w, qs, -to_q);
    } else if (!qs_surface) {
        f_q = (float4)(bdpt_phase(scene, qs, -qs->wo, -to_q));
    } else {
        __global const Material *qm = &scene->materials[qs->material];
        SurfaceContext qsc = shading_context(scene, qs->uv, qs->p, qs->footprint,
                                             qs->ns_base, qs->dpdu, qs->tangent_w, 0);
        SURFACE_AT_HIT(qsc, *qs);
        f_q = material_eval(qm, &qsc, w, qs->ns, -to_q, qs->wo) / cos_in;
    }
    float4 value = qs->beta * f_q * pt->beta * f_p * g;
    if (all(value == (float4)(0.0f))) return (float4)(0.0f);
    value *= bdpt_transmittance(scene, w, pt, qs, query, rays_traced);
    if (all(value == (float4)(0.0f))) return (float4)(0.0f);
    float weight = bdpt_mis_weight(scene, w, light, camera, s == 1 ? qs : 0, s, t, to_q, 0.0f, light_share);
    return bdpt_hero(value, pt->hero || qs->hero) * weight;
}

/* One pixel sample of the pixels of `group` (bdpt_pixels_per_light_path consecutive ones from group × that, those
 * the film has): the light-to-camera strategies (t = 1) written to records as it makes them, each pixel's sum of the
 * others (XYZ, w = 1 where dropped) to its row of own_xyz. The camera subpaths share one light subpath (and its wavelengths): every strategy with s >= 2
 * and t >= 2 joins each camera subpath to a whole light subpath, as with one light subpath per pixel sample, while
 * the light subpath's walk and its joins to the camera (t = 1) are made once for the group's pixel samples. The t = 1
 * strategy then has bdpt_light_share(params) samples per pixel sample, which its splats' value and the MIS weights
 * count. scene_sphere: the scene's bounding sphere (centre xyz, radius w), across which lights at infinity start;
 * hide_environment: the environment seen straight from the camera is black. */
inline void trace_bdpt(const Scene *scene, int group, int sample_index, float4 scene_sphere, int hide_environment,
                       __global const float4 *cmf, SplatRecords *records, __global float4 *own_xyz,
                       uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int last_segment = min(max_segments(params), BDPT_MAX_SEGMENTS);
    float beam_pdf = 1.0f / (PI_F * scene_sphere.w * scene_sphere.w);
    float light_share = bdpt_light_share(params);
    int group_size = bdpt_pixels_per_light_path(params);
    int pixel = group_size * group;
    Sampler sampler;
    SampledWavelengths w;
    float filter_weight;
    Ray ray = start_pixel_sample(params, cmf, pixel, sample_index, &sampler, &w, &filter_weight);

    /* The light subpath's start and the light point of next-event estimation take the sampler's first dimensions
     * after the camera ray's, where a low-discrepancy sampler stratifies them best. */
    float2 u_position = sample_2d(&sampler);
    float2 u_direction = sample_2d(&sampler);
    float2 u_nee_position = sample_2d(&sampler);

    BdptVertex camera[BDPT_MAX_VERTICES];
    BdptVertex light[BDPT_MAX_VERTICES - 1];
    bdpt_camera_vertex(params, ray, filter_weight, &camera[0]);
    float camera_pdf = camera[0].beam_pdf > 0.0f ? 0.0f : camera_direction_pdf(params, ray.direction);
    float4 seen_through = (float4)(0.0f); /* lights the camera subpath crossed (bdpt_walk) */
    int nc = bdpt_walk(scene, &w, &sampler, ray, camera[0].beta, camera_pdf, 0, camera, last_segment + 1, 0u,
                       beam_pdf, light_share, &seen_through, rays_traced);

    int nl = 0;
    if (sample_light_origin(scene, u_position, beam_pdf, &light[0])) {
        nl = 1;
        Ray lray;
        float pdf_dir;
        float4 flux;
        if (bdpt_light_ray(scene, &w, scene_sphere, u_direction, &light[0], &lray, &pdf_dir, &flux)) {
            float4 unused = (float4)(0.0f);
            nl = bdpt_walk(scene, &w, &sampler, lray, flux, pdf_dir, 1, light, last_segment, 0x9e3779b9u, beam_pdf,
                           light_share, &unused, rays_traced);
        }
    }

    /* t = 1 first, its records in the order of s (lens points from the first pixel's sampler). */
    for (int s = 2; s <= nl && s <= last_segment; ++s) {
        if (bdpt_keeps(params, s, 1)) {
            bdpt_splat(scene, &w, &sampler, light, camera, s, light_share, cmf, records, rays_traced);
        }
    }

    int pixels = params->width * params->height;
    for (int k = 0; k < group_size && pixel < pixels; ++k, ++pixel) {
        if (k > 0) {
            /* The next pixel's camera subpath, with the first one's wavelengths (the light subpath's); its own
             * draws at the dimensions the first pixel's took, the light subpath's start left unused. */
            SampledWavelengths own;
            ray = start_pixel_sample(params, cmf, pixel, sample_index, &sampler, &own, &filter_weight);
            (void)sample_2d(&sampler);
            (void)sample_2d(&sampler);
            u_nee_position = sample_2d(&sampler);
            bdpt_camera_vertex(params, ray, filter_weight, &camera[0]);
            camera_pdf = camera[0].beam_pdf > 0.0f ? 0.0f : camera_direction_pdf(params, ray.direction);
            seen_through = (float4)(0.0f);
            nc = bdpt_walk(scene, &w, &sampler, ray, camera[0].beta, camera_pdf, 0, camera, last_segment + 1, 0u,
                           beam_pdf, light_share, &seen_through, rays_traced);
        }
        /* Next-event estimation's light point, one for every camera vertex (the same draw for each). */
        BdptVertex sampled;
        int have_sampled = sample_light_origin(scene, u_nee_position, beam_pdf, &sampled);
        float4 radiance = seen_through;
        for (int t = 2; t <= nc; ++t) {
            BdptVertex *pt = &camera[t - 1];
            if (bdpt_keeps(params, 0, t) && pt->light >= 0 && any(pt->le != (float4)(0.0f)) &&
                !(pt->at_infinity && t == 2 && hide_environment)) {
                float4 value = pt->beta * pt->le;
                float weight = bdpt_mis_weight(scene, &w, light, camera, 0, 0, t, (float3)(0.0f), 0.0f, light_share);
                radiance += bdpt_hero(value, pt->hero) * weight;
            }
            if (t > last_segment || !bdpt_joinable(scene, pt)) continue;
            if (have_sampled && bdpt_keeps(params, 1, t)) {
                uint query = opacity_query(&sampler, (1u << 8) ^ (uint)t, QUERY_SHADOW);
                radiance += bdpt_connect(scene, &w, light, camera, &sampled, 1, t, query, light_share, rays_traced);
            }
            for (int s = 2; s <= nl && s + t - 1 <= last_segment; ++s) {
                if (!bdpt_keeps(params, s, t)) continue;
                uint query = opacity_query(&sampler, ((uint)s << 8) ^ (uint)t, QUERY_SHADOW);
                radiance += bdpt_connect(scene, &w, light, camera, &light[s - 1], s, t, query, light_share,
                                         rays_traced);
            }
        }
        /* The pixel's own sum, in its row of own_xyz (written by the first launch of the sample alone: a relaunch
         * for later records makes the same sum). */
        if (records->begin == 0) own_xyz[pixel] = splat_xyz_estimate(radiance, cmf, &w);
    }
}

#endif
