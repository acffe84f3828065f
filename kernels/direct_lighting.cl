/* Next-event estimation: light arriving at a surface point from one sampled light, times the BSDF. */
#ifndef SPECTRACE_DIRECT_LIGHTING_CL
#define SPECTRACE_DIRECT_LIGHTING_CL

#include "scene.cl"
#include "shading_normal.cl"
#include "lights.cl"
#include "material.cl"
#include "rng.cl"

/* The identity of a visibility query for the cut-outs' choices (scene.cl, surface_met): the point its sample has
 * reached (sampler_identity: seed, pixel or sensor item, sample index, draws so far), the vertex along its path
 * (segment and boundaries crossed, or 0 where the sampler's state alone tells it) and its kind (QUERY_PATH,
 * QUERY_SHADOW). All are carried alike by both kernel shapes (the wavefront keeps the sampler and the path state in
 * its slots), and none depends on a ray's bits. */
inline uint opacity_query(const Sampler *sampler, uint vertex, uint kind)
{
    return hash_u32(hash_u32(sampler_identity(sampler) ^ kind) ^ vertex);
}

/* Picks one light by its pmf and samples a point of it as seen from x, both from one 2D draw (pick_light_reusing):
 * 0 when nothing arrives. The draw is made whether or not a light exists, so the sampler's dimensions stay
 * aligned. */
inline int sample_one_light(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, float3 x,
                            __global const Light **light, LightSample *ls)
{
    __global const RenderParams *params = scene->params;
    float2 u_light = sample_2d(sampler);
    if (params->light_count == 0) return 0;
    *light = &scene->lights[pick_light_reusing(scene->light_cdf, params->light_count, &u_light)];
    LightBuffers buffers = light_buffers(scene);
    if (!sample_light(*light, &buffers, w, x, u_light, ls)) return 0;
    return any(ls->arriving != (float4)(0.0f));
}

/* Radiance reflected toward wo by light from one sampled light: f·cos·L / pdf, weighted against BSDF sampling by
 * the power heuristic when use_mis (delta lights always weigh 1: BSDF sampling cannot find them). The BSDF's frame
 * follows the shading normal, the shadow ray leaves by the geometric one (shading_normal.cl). The shadow ray starts
 * in the medium on its side of the surface: medium_beyond of the surface's `interior` for a path that arrived in
 * `medium`. `query` names the shadow ray (opacity_query). */
inline float4 estimate_direct_light(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, float3 p,
                                    float3 n_geometric, float3 n_shading, float3 wo,
                                    __global const Material *material, const SurfaceContext *sc, int interior,
                                    int medium, int use_mis, uint query, uint *rays_traced)
{
    __global const Light *light;
    LightSample ls;
    if (!sample_one_light(scene, w, sampler, p, &light, &ls)) return (float4)(0.0f);
    if (!shading_side_agrees(n_geometric, n_shading, ls.wi)) return (float4)(0.0f);
    float4 f_cos = material_eval(material, sc, w, n_shading, wo, ls.wi);
    if (all(f_cos == (float4)(0.0f))) return (float4)(0.0f);

    float3 from = offset_ray_origin(p, n_geometric, ls.wi);
    int to_infinity = isinf(ls.distance);
    float3 to = ls.point;
    if (LIGHT_ON_SURFACE(light)) to = offset_ray_origin(ls.point, ls.normal, -ls.wi);
    /* Not scene_occluded: index-matched medium boundaries let light through, attenuated by the medium. */
    int medium_out = medium_beyond(interior, n_geometric, ls.wi, medium);
    float4 transmittance = scene_transmittance(scene, w, medium_out, from, to, ls.wi, to_infinity, query,
                                               rays_traced);
    if (all(transmittance == (float4)(0.0f))) return (float4)(0.0f);

    float weight = 1.0f;
    if (use_mis && !ls.is_delta) {
        weight = power_heuristic(ls.pdf, material_pdf(material, sc, w, n_shading, wo, ls.wi));
    }
    return f_cos * ls.arriving * transmittance * (weight / ls.pdf);
}

/* The same at a scattering point x inside `medium`, for light that travelled along `travel` before scattering:
 * the phase function takes the place of f·cos, and the shadow ray's transmittance includes the stretch inside
 * the medium. MIS weighs it against phase-function sampling. */
inline float4 estimate_direct_light_in_medium(const Scene *scene, const SampledWavelengths *w, Sampler *sampler,
                                              float3 x, float3 travel, int medium, float g, uint query,
                                              uint *rays_traced)
{
    __global const Light *light;
    LightSample ls;
    if (!sample_one_light(scene, w, sampler, x, &light, &ls)) return (float4)(0.0f);
    float phase = henyey_greenstein(dot(travel, ls.wi), g);
    float3 to = LIGHT_ON_SURFACE(light) ? offset_ray_origin(ls.point, ls.normal, -ls.wi) : ls.point;
    float4 transmittance = scene_transmittance(scene, w, medium, x, to, ls.wi, isinf(ls.distance), query,
                                               rays_traced);
    if (all(transmittance == (float4)(0.0f))) return (float4)(0.0f);
    float weight = ls.is_delta ? 1.0f : power_heuristic(ls.pdf, phase);
    return ls.arriving * transmittance * (phase * weight / ls.pdf);
}

#endif
