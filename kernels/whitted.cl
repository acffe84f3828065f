/* The local model (Whitted-style ray tracing): light emitted toward the eye, direct light at every non-specular
 * surface by next-event estimation, and perfect specular reflection/refraction followed recursively. No
 * light bounces diffusely more than once. */
#ifndef SPECTRACE_WHITTED_CL
#define SPECTRACE_WHITTED_CL

#include "path_tracer.cl"

inline float4 trace_direct(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, Ray ray,
                           uint *rays_traced)
{
    __global const RenderParams *params = scene->params;
    int last_segment = max_segments(params);
    PathState s = camera_path(ray);
    float4 radiance = (float4)(0.0f);
    int null_crossings = 0;

    for (; s.segments <= last_segment; ++s.segments) {
        Hit hit = scene_intersect(scene, s.ray, rays_traced);
        /* The local model carries only the light a medium does not scatter: its transmittance to the surface. */
        if (s.medium >= 0) {
            s.throughput *= beer_lambert(medium_sigma_t(&scene->media[s.medium], scene->spectra, w), hit.t);
        }
        if (hit.triangle < 0) {
            if (SCENE_HAS_ENVIRONMENT && params->environment_light >= 0) {
                __global const Light *env = &scene->lights[params->environment_light];
                radiance += s.throughput * environment_radiance(env, scene->spectra, scene->texels, w,
                                                                s.ray.direction);
            }
            break;
        }
        TriangleInfo info = scene->triangle_info[hit.triangle];
        float3 p = triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
        float3 n = triangle_normal(scene->triangle_vertices, hit.triangle);
        float3 wo = -s.ray.direction;
        if (info.light >= 0) {
            radiance += s.throughput * area_light_emitted(&scene->lights[info.light], scene->spectra, scene->texels,
                                                                  w, n, wo,
                                                                  triangle_uv(scene->triangle_uvs, hit.triangle,
                                                                              hit.b12));
        }
        if (info.material == TRIANGLE_NO_MATERIAL) {
            if (++null_crossings > MAX_NULL_CROSSINGS) break;
            cross_null_boundary(&s, info, p, n);
            --s.segments;  /* undo the loop's count: the segment goes on */
            continue;
        }
        if (s.segments >= last_segment) break;

        __global const Material *material = &scene->materials[info.material];
        /* A dispersive surface keeps only the hero wavelength for everything that follows, direct light included
         * (its BSDF is evaluated at the hero's index of refraction). */
        if (material_disperses(material, w)) terminate_secondary_wavelengths(&s);
        if (material_has_non_delta_lobe(material)) {
            radiance += s.throughput * estimate_direct_light(scene, w, sampler, p, n, wo, material, 0, rays_traced);
        }
        /* Follow the specular lobes only: a sampled non-specular direction ends the path (its light was counted
         * by next-event estimation), which keeps the specular part unbiased. */
        float uc = sample_1d(sampler);
        float2 u = sample_2d(sampler);
        BSDFSample bs;
        if (!material_sample(material, scene->spectra, w, n, wo, uc, u, &bs) || !bs.is_delta) break;
        s.throughput *= bs.weight;
        if (bs.terminate_secondary) terminate_secondary_wavelengths(&s);
        if (all(s.throughput == (float4)(0.0f))) break;
        s.medium = medium_beyond(info.interior, n, bs.wi);
        s.ray.origin = offset_ray_origin(p, n, bs.wi);
        s.ray.direction = bs.wi;
    }
    return radiance;
}

#endif
