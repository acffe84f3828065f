/* Fluorescent (bispectral) surfaces in bidirectional path tracing (bdpt.cl; the material and its choice at a vertex:
 * fluorescence.cl). BDPT's strategies join two subpaths that carry the same wavelengths, which a change of wavelength
 * at any vertex would break (a join would have to evaluate the re-radiation between two wavelengths neither subpath
 * chose, and its MIS densities would mix two spectral measures). So path space is partitioned, each part estimated
 * by strategies that all sample it:
 * - elastic paths, with no re-emission event: ordinary BDPT, every strategy. A subpath that meets a dye keeps its
 *   base (elastic part) with the probability the path tracer's or the light tracer's choice gives it there
 *   (fluorescent_vertex, fluorescent_light_vertex: 1 − P at the hero wavelength, the throughput divided by it), and
 *   a join at a dye vertex evaluates the base alone. Every density a vertex samples onward with includes the keeping
 *   probability of the side that samples (the camera's where the camera subpath leaves the vertex, the light's where
 *   the light subpath does), in the walks and in the densities a join computes alike, so that each strategy's MIS
 *   density is its true one and the weights of a path still sum to one (Veach 1997, sec. 9.2: any weights that sum
 *   to one over the strategies that can make a path keep the combination unbiased). A light subpath that chooses the
 *   re-emission stops there: its vertex still serves for joins, and the paths beyond it belong to the other part.
 * - inelastic paths, with at least one re-emission: estimated from the camera side alone. Where the camera subpath
 *   chooses the re-emission (probability P, weight and wavelength switch as in the path tracer, Mojzík et al. 2018,
 *   "Handling Fluorescence in a Uni-directional Spectral Path Tracer", CGF 37(4)), the rest of the path is the path
 *   tracer's own estimator (path_scatter, trace_path_state: next-event estimation at λ_in with MIS against BSDF hits,
 *   hero wavelength only), added with weight 1: no BDPT strategy makes such a path, whose first re-emission (seen
 *   from the camera) lies at that vertex.
 * The camera subpath up to the re-emission is drawn as the path tracer's (BSDF sampling, the same choice at each
 * dye; only its Russian roulette starts earlier), so the inelastic part is the path tracer's estimate, its paths
 * bounded by max_depth as BDPT's own are (BDPT takes max_depth 1..16).
 *
 * Units: keeping probabilities are dimensionless; densities as in bdpt.cl. bdpt.cl includes this file only in scenes
 * with the material (SCENE_HAS_FLUORESCENCE), whose other kernels and bits stay as they were. */
#ifndef SPECTRACE_BDPT_FLUORESCENCE_CL
#define SPECTRACE_BDPT_FLUORESCENCE_CL

#include "path_tracer.cl"

/* The probability with which the light (light_side) or the camera subpath keeps the base at surface vertex v, 1 at
 * any vertex but a dye's. */
inline float bdpt_dye_keep(const BdptVertex *v, int light_side)
{
    if (v->kind != BDPT_SURFACE) return 1.0f;
    return light_side ? v->keep_light : v->keep_camera;
}

/* A subpath meets surface pv, stored as v: a dye's vertex is shaded by its base (a join evaluates that alone), and
 * keeps both sides' probabilities of choosing the base there, at the hero wavelength: fluorescence.cl's 1 − P,
 * 1 / (1 + F) from the same odds F the camera's and the light's choices draw with (a separable dye's or a matrix's).
 * Only the MIS densities read them (the walks' weights are fluorescence.cl's own), so were that choice to change,
 * the weights would still sum to one. */
inline void bdpt_dye_resolve(const Scene *scene, const SampledWavelengths *w, const PathVertex *pv, BdptVertex *v)
{
    v->keep_camera = 1.0f;
    v->keep_light = 1.0f;
    if (pv->info.material == TRIANGLE_NO_MATERIAL) return;
    __global const Material *m = &scene->materials[pv->info.material];
    if (m->type != MATERIAL_FLUORESCENT) return;
    v->material = fluorescent_base(scene, m, pv);
    if (!(m->alpha > 0.0f)) return;
    float quantum_yield = fluorescent_yield(scene, m, pv);
    v->keep_camera = 1.0f / (1.0f + fluorescent_odds(scene, m, quantum_yield, w, 0).odds);
    v->keep_light = 1.0f / (1.0f + fluorescent_odds(scene, m, quantum_yield, w, 1).odds);
}

/* The choice at a dye's vertex pv of a subpath about to sample onward from it (s its walk's state, scatter its
 * Russian roulette weights): the base goes on (the throughput divided by the keeping probability, pv shaded by the
 * base), returning 0. A re-emission ends the subpath, returning 1: on the light side with nothing more; on the camera
 * side after the path tracer's estimate of the inelastic rest, added to *inelastic. Any other vertex draws nothing. */
inline int bdpt_dye_choice(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                           PathVertex *pv, int adjoint, float4 *scatter, float4 *inelastic, uint *rays_traced)
{
    __global const Material *m = &scene->materials[pv->info.material];
    if (m->type != MATERIAL_FLUORESCENT) return 0;
    if (adjoint) {
        SampledWavelengths emitted = *w; /* the light subpath's wavelengths stay those the camera subpaths share */
        fluorescent_light_vertex(scene, &emitted, sampler, s, pv, scatter);
        return pv->info.material == m->k_offset;
    }
    float4 before = s->throughput;
    fluorescent_vertex(scene, w, sampler, s, pv);
    if (!s->fluoresced) {
        *scatter *= before.x != 0.0f ? s->throughput.x / before.x : 1.0f;
        return 0;
    }
#ifndef BDPT_ONE_STRATEGY /* test builds keep one of BDPT's strategies, which this part is none of */
    float4 radiance = (float4)(0.0f);
    if (path_scatter(scene, path_wavelengths(s, w), sampler, s, pv, &radiance, rays_traced)) {
        radiance += trace_path_state(scene, w, sampler, s, rays_traced);
    }
    *inelastic += radiance;
#endif
    return 1;
}

/* The densities a join of strategy (s, t) gives the vertices beside it (bdpt_mis_weight's), each sampled from a
 * vertex of the other side, take that side's keeping probability there: pt and pt_minus reached from qs and pt as the
 * light subpath would (s >= 2, s >= 1), qs and qs_minus from pt and qs as the camera subpath would (t >= 2, s >= 2). */
inline void bdpt_dye_join_pdfs(const BdptVertex *pt, const BdptVertex *qs, int s, int t, float *pt_rev,
                               float *pt_minus_rev, float *qs_rev, float *qs_minus_rev)
{
    if (t > 1 && s > 1) *pt_rev *= bdpt_dye_keep(qs, 1);
    if (t > 1 && s > 0) *pt_minus_rev *= bdpt_dye_keep(pt, 1);
    if (t > 1 && s > 0) *qs_rev *= bdpt_dye_keep(pt, 0);
    if (s > 1) *qs_minus_rev *= bdpt_dye_keep(qs, 0);
}

#endif
