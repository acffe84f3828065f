/* A camera path between two vertices, and the steps both integrators take along it (path_tracer.cl: the global
 * model; whitted.cl: the local model). Sensors start paths at a surface point as well as at a camera (meters.cl),
 * and the wavefront keeps the state in a buffer between launches (wavefront_pass.cl). */
#ifndef SPECTRACE_PATH_STATE_CL
#define SPECTRACE_PATH_STATE_CL

#include "aov.cl"
#include "direct_lighting.cl"
#include "surface_detail.cl"
#include "material_mix.cl"
#if SCENE_POLARIZED
#include "polarized_path.cl"
#define IF_POLARIZED(statement) statement
#else
#define IF_POLARIZED(statement)
#endif

/* Longest path when max_depth is unbounded (-1): Russian roulette ends paths long before this. */
#define UNBOUNDED_DEPTH 1024

typedef struct {
    Ray ray;
    float4 throughput;
    float previous_pdf;      /* solid-angle pdf of the direction that produced `ray`; 0 for a camera ray */
    int previous_delta;      /* `ray` left a specular lobe (or a camera): emission found by it is not MIS-weighted */
    float3 previous_point;
    int segments;            /* the segment `ray` is: 1 for a camera ray */
    int secondary_terminated;  /* only the hero wavelength goes on (terminate_secondary, wavelengths.cl) */
    int medium;              /* index of the medium `ray` travels in, -1 for none (kernels/medium.cl) */
    float radiance_scale;    /* product of the refractions' (n_o/n_i)² factors in `throughput` */
    int null_crossings;      /* medium boundaries crossed without a vertex, bounded by MAX_NULL_CROSSINGS */
#if FILM_AOVS
    AovRecord aov;           /* what the camera path records for the AOVs (aov.cl) */
#endif
#if SCENE_HAS_FLUORESCENCE
    int fluoresced;          /* a fluorescent re-emission changed the path's wavelength (fluorescence.cl) */
    SampledWavelengths fluorescent_wavelengths;  /* the path's wavelengths since then */
#endif
#if SCENE_POLARIZED
    PolarizedPath pol;       /* the path's Mueller matrix and the Stokes vector it gathers (polarized_path.cl) */
#endif
} PathState;

/* *radiance += s->throughput * value, the unpolarised light a path gathers, which a polarised path also adds to
 * its Stokes vector. */
#if SCENE_POLARIZED
#define PATH_GATHER(s, radiance, value)                       \
    do {                                                      \
        float4 gathered_ = (s)->throughput * (value);         \
        *(radiance) += gathered_;                             \
        polarized_gather(&(s)->pol, gathered_);               \
    } while (0)
#else
#define PATH_GATHER(s, radiance, value) (*(radiance) += (s)->throughput * (value))
#endif

/* hit, or a miss where it lies beyond the camera's far clip on the camera's own ray (s's first segment, before any
 * medium boundary is crossed: Mitsuba 3 limits only the sensor's ray). Call it on camera paths only. */
inline Hit far_clipped(__global const RenderParams *params, const PathState *s, Hit hit)
{
#if SCENE_HAS_FAR_CLIP
    if (s->segments == 1 && s->null_crossings == 0 && hit.t > camera_ray_reach(params, s->ray)) return no_hit(INFINITY);
#endif
    return hit;
}

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
#if FILM_AOVS
    s.aov = aov_start();
#endif
#if SCENE_HAS_FLUORESCENCE
    s.fluoresced = 0;
#endif
    IF_POLARIZED(s.pol = polarized_start(ray.direction));
    return s;
}

/* One free flight of s through its medium toward the surface at hit_t, the same for camera paths, light paths
 * and BDPT subpaths, so that the three draw their numbers alike: medium_sample_flight's lane then distance, the
 * flight's weight taken into s->throughput. The caller has checked that s is in a medium. */
inline FreeFlight path_free_flight(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                                   __global const Medium *medium, float hit_t)
{
    float u_lane = sample_1d(sampler);
    float u_distance = sample_1d(sampler);
    FreeFlight flight;
#if SCENE_HAS_GRID_MEDIA
    if (medium->grid >= 0) {
        flight = grid_sample_flight(medium, scene->spectra, w, s->ray.origin, s->ray.direction, hit_t,
                                    s->secondary_terminated, s->throughput, u_lane, u_distance);
    } else
#endif
    flight = medium_sample_flight(medium, scene->spectra, w, hit_t, s->secondary_terminated, u_lane, u_distance);
    s->throughput *= flight.weight;
    return flight;
}

/* A query of the path's from its current vertex (opacity_query): the segment and the boundaries crossed within it
 * tell its queries apart even where no draw lies between them (a material-less boundary crossed outside media). */
inline uint path_query(const Sampler *sampler, const PathState *s, uint kind)
{
    return opacity_query(sampler, ((uint)s->segments << 16) ^ (uint)s->null_crossings, kind);
}

inline int max_segments(__global const RenderParams *params)
{
    return params->max_depth < 0 ? UNBOUNDED_DEPTH : params->max_depth;
}

/* 1 when the material shading a vertex frames its BSDF along dp/du (Material.tangent_frame): only then is dp/du
 * formed, so no other material's vertex does more work. */
inline int vertex_follows_tangent(const Scene *scene, int material)
{
#if SCENE_HAS_TANGENT_FRAMES
    return material != TRIANGLE_NO_MATERIAL && scene->materials[material].tangent_frame;
#else
    return 0;
#endif
}

/* A triangle's dp/du (object space for an instance's), 0 where its texture coordinates are degenerate, so that
 * material_frame falls back to the normal's own basis. */
inline float3 triangle_dpdu(const Scene *scene, int triangle)
{
    float3 dpdu = (float3)(0.0f), dpdv = (float3)(0.0f);
    return triangle_dp_duv(scene, triangle, &dpdu, &dpdv) ? dpdu : (float3)(0.0f);
}

/* Where a path's ray met a surface. */
typedef struct {
    TriangleInfo info;  /* the triangle's, but `material`: the BSDF that shades this point, a mix resolved into
                           one of its materials (material_mix.cl) */
    float3 p;
    float3 n;   /* geometric normal (the winding's front): sides, ray offsets, media, emission */
    float3 ns;  /* shading normal, the BSDF's frame: n itself on a flat triangle (shading_normal.cl), turned by a
                   normal or bump map (surface_detail.cl) */
    float3 ns_base;  /* the shading normal before a normal or bump map turned it: their shadowing term's reference */
    float3 dpdu;     /* the surface's dp/du where its material's frame follows it (Material.tangent_frame), else 0 */
    float tangent_w; /* ±1: dpdu's handedness, a file tangent's w where dpdu is one, else 1 (SurfaceContext) */
    float3 wo;  /* back along the ray */
    float2 uv;  /* texture coordinates (only in scenes with material textures) */
    int triangle;  /* the hit's triangle slot and barycentrics of v1, v2 (an analytic shape's: its uv), where mesh */
    float2 b12;    /* attributes are read (texture_mesh_attribute.cl) */
    float footprint;  /* texture footprint in uv units (scene.cl's camera_footprint; 0 unless SCENE_NEEDS_FOOTPRINT) */
} PathVertex;

#if SCENE_HAS_SDF_GRIDS
#include "shape_sdf_grid_vertex.cl"
#endif

#if SCENE_HAS_SHAPES
/* path_vertex at a hit of an analytic shape, placed by itself or by an instance (hit_shape_surface): its exact
 * normal shades (no interpolation to correct), and its dp/du, dp/dv frame the surface detail and the footprint. */
inline PathVertex shape_vertex(const Scene *scene, Hit hit, Ray ray)
{
    PathVertex v;
    v.info = scene->triangle_info[hit.triangle];
    v.triangle = hit.triangle;
    v.b12 = hit.b12;
    ShapeSurface g = hit_shape_surface(scene, hit);
    v.p = g.p;
    v.n = g.n;
    v.ns = g.n;
    v.ns_base = v.ns;
    v.wo = -ray.direction;
    v.uv = hit.b12;
#if SCENE_HAS_SDF_GRIDS
    if (hit_shape(scene, hit.triangle)->type == SHAPE_SDFGRID) sdf_grid_vertex_shading(scene, hit, &v);
#endif
#if SCENE_HAS_CURVES
    if (hit_shape(scene, hit.triangle)->type == SHAPE_CURVE)
        v.uv = curve_texture_uv(hit_shape(scene, hit.triangle), hit.b12, g.n, g.dpdu, v.wo);
#endif
    v.footprint = 0.0f;
    if (SCENE_NEEDS_FOOTPRINT) {
        v.footprint = footprint_from_tangents(scene->params, v.p, v.n, g.dpdu, g.dpdv, (float2)(1.0f, 0.0f),
                                              (float2)(0.0f, 1.0f));
    }
    if (SCENE_HAS_MIX) v.info.material = mix_resolve(scene, v.info.material, v.p, v.wo, v.uv, v.footprint, hit.triangle, hit.b12);
    v.dpdu = vertex_follows_tangent(scene, v.info.material) ? g.dpdu : (float3)(0.0f);
    v.tangent_w = 1.0f;
    if (SCENE_HAS_SURFACE_NORMALS && v.info.material != TRIANGLE_NO_MATERIAL) {
        __global const Material *m = &scene->materials[v.info.material];
        if (m->normal_map != NO_TEXTURE || m->bump_map != NO_TEXTURE) {
            int parametrised = all(isfinite(g.dpdu)) && length(g.dpdu) > 0.0f && length(g.dpdv) > 0.0f;
            v.ns = detailed_normal_at(scene, m, parametrised, g.dpdu, g.dpdv, v.uv, v.footprint, v.n, v.ns, v.wo,
                                      (float3)(0.0f), 0.0f);
        }
    }
    return v;
}
#endif

#if SCENE_HAS_INSTANCES
/* path_vertex at a hit of an instanced object's triangle: the object-space triangle read as for the scene's own,
 * its point and tangents taken to world space by the instance's map, its normals by the inverse transpose. */
inline PathVertex instance_vertex(const Scene *scene, Hit hit, Ray ray)
{
    __global const Instance *instance = &scene->instances[hit.instance];
    PathVertex v;
    v.info = scene->triangle_info[hit.triangle];
    v.triangle = hit.triangle;
    v.b12 = hit.b12;
    v.p = affine_point(instance->to_world, triangle_point(scene->triangle_vertices, hit.triangle, hit.b12));
    v.n = instance_normal(instance, triangle_normal(scene->triangle_vertices, hit.triangle));
    v.wo = -ray.direction;
    v.ns = v.info.normals < 0 ? v.n : instance_shading_normal(scene, instance, v.info.normals, hit.b12, v.n, v.wo);
    v.ns_base = v.ns;
    v.uv = (float2)(0.0f);
    v.footprint = 0.0f;
    if (SCENE_HAS_TEXTURES) {
        v.uv = triangle_uv(scene->triangle_uvs, hit.triangle, hit.b12);
        if (SCENE_NEEDS_FOOTPRINT) {
            __global const float4 *c = scene->triangle_vertices + 3 * hit.triangle;
            __global const float2 *t = scene->triangle_uvs + 3 * hit.triangle;
            float3 e1 = affine_vector(instance->to_world, c[1].xyz - c[0].xyz);
            float3 e2 = affine_vector(instance->to_world, c[2].xyz - c[0].xyz);
            v.footprint = footprint_from_tangents(scene->params, v.p, v.n, e1, e2, t[1] - t[0], t[2] - t[0]);
        }
    }
    if (SCENE_HAS_MIX) v.info.material = mix_resolve(scene, v.info.material, v.p, v.wo, v.uv, v.footprint, hit.triangle, hit.b12);
    float3 file_t = (float3)(0.0f);
    float file_w = 0.0f;
#if SCENE_HAS_FILE_TANGENTS
    file_w = instance_file_tangent(scene, instance, v.info.normals, hit.b12, &file_t);
#endif
    v.dpdu = (float3)(0.0f);
    v.tangent_w = 1.0f;
    if (vertex_follows_tangent(scene, v.info.material)) {
        v.dpdu = file_w != 0.0f ? file_t : affine_vector(instance->to_world, triangle_dpdu(scene, hit.triangle));
        if (file_w != 0.0f) v.tangent_w = file_w;
    }
    if (SCENE_HAS_SURFACE_NORMALS && v.info.material != TRIANGLE_NO_MATERIAL) {
        __global const Material *m = &scene->materials[v.info.material];
        if (m->normal_map != NO_TEXTURE || m->bump_map != NO_TEXTURE) {
            float3 dpdu = (float3)(0.0f), dpdv = (float3)(0.0f);
            int parametrised = triangle_dp_duv(scene, hit.triangle, &dpdu, &dpdv);
            dpdu = affine_vector(instance->to_world, dpdu);
            dpdv = affine_vector(instance->to_world, dpdv);
            v.ns = detailed_normal_at(scene, m, parametrised, dpdu, dpdv, v.uv, v.footprint, v.n, v.ns, v.wo, file_t,
                                      file_w);
        }
    }
    return v;
}
#endif

inline PathVertex path_vertex(const Scene *scene, Hit hit, Ray ray)
{
#if SCENE_HAS_SHAPES
    if (hit_is_shape(scene, hit.triangle)) return shape_vertex(scene, hit, ray);
#endif
#if SCENE_HAS_INSTANCES
    if (hit.instance >= 0) return instance_vertex(scene, hit, ray);
#endif
    PathVertex v;
    v.info = scene->triangle_info[hit.triangle];
    v.triangle = hit.triangle;
    v.b12 = hit.b12;
    v.p = triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
    v.n = triangle_normal(scene->triangle_vertices, hit.triangle);
    v.wo = -ray.direction;
    v.ns = v.info.normals < 0 ? v.n : shading_normal(scene, v.info.normals, hit.b12, v.n, v.wo);
    v.uv = (float2)(0.0f);
    v.footprint = 0.0f;
    if (SCENE_HAS_TEXTURES) {
        v.uv = triangle_uv(scene->triangle_uvs, hit.triangle, hit.b12);
        if (SCENE_NEEDS_FOOTPRINT) v.footprint = camera_footprint(scene, hit.triangle, v.p, v.n);
    }
    if (SCENE_HAS_MIX) v.info.material = mix_resolve(scene, v.info.material, v.p, v.wo, v.uv, v.footprint, hit.triangle, hit.b12);
    v.ns_base = v.ns;
    float3 file_t = (float3)(0.0f);
    float file_w = 0.0f;
#if SCENE_HAS_FILE_TANGENTS
    file_w = file_tangent(scene, v.info.normals, hit.b12, &file_t);
#endif
    v.dpdu = vertex_follows_tangent(scene, v.info.material) ? triangle_dpdu(scene, hit.triangle) : (float3)(0.0f);
    v.tangent_w = 1.0f;
    if (file_w != 0.0f && vertex_follows_tangent(scene, v.info.material)) {
        v.dpdu = file_t;
        v.tangent_w = file_w;
    }
    if (SCENE_HAS_SURFACE_NORMALS && v.info.material != TRIANGLE_NO_MATERIAL) {
        v.ns = detailed_normal(scene, &scene->materials[v.info.material], hit.triangle, v.uv, v.footprint, v.n,
                               v.ns, v.wo, file_t, file_w);
    }
    return v;
}

/* Radiance the vertex's area light (v.info.light >= 0) sends back along the ray. */
inline float4 vertex_emission(const Scene *scene, const SampledWavelengths *w, const PathVertex *v, Hit hit)
{
    TextureBuffers textures = {scene->textures, (__global const float *)scene->texels, scene->spectra};
    return area_light_emitted(&scene->lights[v->info.light], &textures, w, v->n, v->wo, hit_uv(scene, hit));
}

#if FILM_AOVS
/* The film XYZ of the emission the camera ray meets, integrated over the grid (aov.cl's emission AOV): the area
 * light at v, or the environment in direction d when v is 0. Only for camera rays, so its cost (GRID_SAMPLES
 * evaluations) is paid once per sample that sees an emitter. Both integrators record it. */
inline float4 expected_camera_emission(const Scene *scene, __global const float4 *cmf, const PathVertex *v, Hit hit,
                                       float3 d)
{
    float4 xyz = (float4)(0.0f);
    for (int i = 0; i < GRID_SAMPLES; i += 4) {
        float4 lambda;
        float4 weight = aov_grid_weights(i, &lambda);
        SampledWavelengths g = wavelengths_on_grid(lambda, (float4)(1.0f));
        float4 emitted;
        if (v) {
            emitted = vertex_emission(scene, &g, v, hit);
        } else {
            __global const Light *env = &scene->lights[scene->params->environment_light];
            emitted = environment_radiance(env, scene->spectra, scene->texels, &g, d);
        }
        xyz += aov_grid_xyz(cmf, i, weight, emitted);
    }
    return xyz;
}

inline void record_camera_emission(const Scene *scene, const SampledWavelengths *w, PathState *s, float4 emitted,
                                   float weight, const PathVertex *v, Hit hit)
{
    if (s->segments != 1 || scene->film_cmf == 0) return;
    int expectable = aov_emission_expectable(s->throughput, w);
    float4 expected = expectable ? expected_camera_emission(scene, scene->film_cmf, v, hit, s->ray.direction)
                                 : (float4)(0.0f);
    aov_at_camera_emission(&s->aov, scene->film_cmf, s->throughput, emitted, weight, expected, expectable, w);
}
#endif

/* At a material-less (index-matched) medium boundary the ray goes on unchanged into or out of the shape's
 * interior: no vertex, and the segment it is goes on too. Returns 0 when the path has crossed too many (a ray
 * caught on a boundary by rounding). */
inline int cross_null_boundary(PathState *s, const PathVertex *v)
{
    if (++s->null_crossings > MAX_NULL_CROSSINGS) return 0;
    s->medium = medium_beyond(v->info.interior, v->n, s->ray.direction, s->medium);
    s->ray.origin = offset_ray_origin(v->p, v->n, s->ray.direction);
    return 1;
}

/* What a path records of the surface it has just reached, before anything else is done there: the AOVs' first
 * surface, and hidden area lights (hide_emitters), which the camera's own rays cross as a boundary without material,
 * showing what lies behind (they still light every other vertex). Returns 1 when the path crossed such a light;
 * the segment's caller then returns *live. */
inline int record_surface_reached(PathState *s, const PathVertex *v, float t, __global const RenderParams *params,
                                  int *live)
{
#if SCENE_HIDES_AREA_EMITTERS
    if (v->info.light >= 0 && s->segments == 1 && (params->hide_emitters & HIDE_AREA_EMITTERS)) {
#if FILM_AOVS
        aov_at_surface(&s->aov, t, v->p, v->ns, 0); /* seen through: its distance counts toward the depth */
#endif
        *live = cross_null_boundary(s, v);
        return 1;
    }
#endif
#if FILM_AOVS
    aov_at_surface(&s->aov, t, v->p, v->ns, v->info.material != TRIANGLE_NO_MATERIAL);
#endif
    return 0;
}

#if SCENE_POLARIZED
/* dp/du of the area light `light` at the point its sample ls reached from p: a triangle's own, an analytic shape's
 * where the ray toward the point meets it. The Stokes basis of a polarised light follows it (polarized_path.cl). */
inline float3 light_sample_dpdu(const Scene *scene, __global const Light *light, float3 p, const LightSample *ls)
{
#if SCENE_HAS_SHAPES
    if (!light_is_triangle(light)) {
        __global const AnalyticShape *shape = &scene->shapes[light->triangle];
        float2 uv = (float2)(0.5f);
        intersect_shape(shape, p, ls->wi, 1.001f * ls->distance + 1.0e-4f, &uv);
        return shape_surface(shape, uv).dpdu;
    }
#endif
    return triangle_dpdu(scene, light->triangle);
}

/* Next-event estimation's `gathered` (throughput applied) at v, whose light sample `replay` draws again: through the
 * event's Mueller matrix where it polarises (a rough conductor or dielectric, pplastic: microfacet_polarized.cl),
 * the light's own Stokes vector where it is polarised, else depolarised. Returns the S0 to add to the radiance. */
inline float4 polarized_direct_vertex(const Scene *scene, const SampledWavelengths *w, Sampler *replay,
                                      PathState *s, const PathVertex *v, __global const Material *material,
                                      const SurfaceContext *sc, float4 gathered)
{
    __global const Light *light;
    LightSample ls;
    Mueller e;
    float3 x;
    if (any(gathered != (float4)(0.0f)) && sample_one_light(scene, w, replay, v->p, &light, &ls)
        && glossy_polarization(material, sc, w, v->ns, v->wo, ls.wi, &e, &x)) {
        float4 in[4] = {(float4)(1.0f), (float4)(0.0f), (float4)(0.0f), (float4)(0.0f)};
        if (LIGHT_ON_SURFACE(light) && light->direction.w > 0.0f)
            polarized_light_stokes(light, light_sample_dpdu(scene, light, v->p, &ls), ls.wi, x, in);
        float4 out[4];
        for (int i = 0; i < 4; ++i)
            out[i] = e.m[4 * i] * in[0] + e.m[4 * i + 1] * in[1] + e.m[4 * i + 2] * in[2] + e.m[4 * i + 3] * in[3];
        return gathered * polarized_gather_event(&s->pol, out, x, v->wo, gathered);
    }
    polarized_gather(&s->pol, gathered);
    return gathered;
}
#endif

/* What a path does at a surface before choosing where to go: a dispersive surface keeps only the hero wavelength
 * for everything that follows, direct light included (its BSDF is evaluated at the hero's index of refraction);
 * then next-event estimation, MIS-weighted when use_mis, unless every lobe is a delta lobe. */
inline void light_vertex(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                         const PathVertex *v, __global const Material *material, int use_mis, float4 *radiance,
                         uint *rays_traced)
{
    if (material_disperses(material, w)) terminate_secondary(&s->throughput, &s->secondary_terminated);
    if (material_has_non_delta_lobe(material)) {
        SurfaceContext sc = shading_context(scene, v->uv, v->p, v->footprint, v->ns_base, v->dpdu, v->tangent_w, 0);
        SURFACE_AT_HIT(sc, *v);
#if SCENE_POLARIZED
        Sampler replay = *sampler;  /* draws the estimate's light sample again, for its direction */
#endif
        float4 direct = estimate_direct_light(scene, w, sampler, v->p, v->n, v->ns, v->wo, material, &sc,
                                              v->info.interior, s->medium, use_mis,
                                              path_query(sampler, s, QUERY_SHADOW), rays_traced);
#if SCENE_POLARIZED
        *radiance += polarized_direct_vertex(scene, w, &replay, s, v, material, &sc, s->throughput * direct);
#else
        PATH_GATHER(s, radiance, direct);
#endif
    }
}

/* A surface vertex, as both integrators meet it: its direct light (light_vertex), then a direction from its
 * material's BSDF drawn with the next 1D and 2D numbers. Returns 0 when the BSDF gives no direction, or one on
 * different sides of the shading and the geometric normal (shading_normal.cl). */
inline int light_and_sample_vertex(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                                   const PathVertex *v, int use_mis, float4 *radiance, uint *rays_traced,
                                   BSDFSample *bs)
{
    __global const Material *material = &scene->materials[v->info.material];
    light_vertex(scene, w, sampler, s, v, material, use_mis, radiance, rays_traced);
    float uc = sample_1d(sampler);
    float2 u = sample_2d(sampler);
    SurfaceContext sc = shading_context(scene, v->uv, v->p, v->footprint, v->ns_base, v->dpdu, v->tangent_w, 0);
    SURFACE_AT_HIT(sc, *v);
    return material_sample(material, &sc, w, v->ns, v->wo, uc, u, bs)
        && shading_side_agrees(v->n, v->ns, bs->wi);
}

#if SCENE_POLARIZED
/* The path scatters at v by bs: the event's Mueller matrix joins the path's (polarized_path.cl). */
inline void polarized_scatter_vertex(const Scene *scene, const SampledWavelengths *w, PathState *s,
                                     const PathVertex *v, const BSDFSample *bs)
{
    SurfaceContext sc = shading_context(scene, v->uv, v->p, v->footprint, v->ns_base, v->dpdu, v->tangent_w, 0);
    SURFACE_AT_HIT(sc, *v);
    polarized_scatter(&s->pol, &s->throughput, &scene->materials[v->info.material], &sc, w, v->ns, v->wo, bs);
}

/* The path meets the area light `light` at v (hit): the Stokes basis of a polarised light follows the surface's own
 * dp/du, whatever its material's frame; returns what scales its S0 (polarized_gather_emitter). */
inline float4 polarized_emitter_vertex(const Scene *scene, PathState *s, __global const Light *light,
                                       const PathVertex *v, Hit hit, float4 contribution)
{
    float3 dpdu = (float3)(0.0f);
    if (light->direction.w > 0.0f) {
#if SCENE_HAS_SHAPES
        if (hit_is_shape(scene, hit.triangle)) dpdu = hit_shape_surface(scene, hit).dpdu;
        else
#endif
            dpdu = triangle_dpdu(scene, hit.triangle);
    }
    return polarized_gather_emitter(&s->pol, light, dpdu, v->wo, contribution);
}
#endif

/* The path leaves the vertex along a BSDF sample: its weight and radiance compression join the throughput, and
 * the next ray starts off the surface in the medium on that side. */
inline void follow_bsdf_sample(PathState *s, const PathVertex *v, const BSDFSample *bs)
{
    s->throughput *= bs->weight;
    s->radiance_scale *= bs->radiance_scale;
    s->previous_pdf = bs->pdf;
    s->previous_delta = bs->is_delta;
    s->medium = medium_beyond(v->info.interior, v->n, bs->wi, s->medium);
    s->previous_point = v->p;
    s->ray.origin = offset_ray_origin(v->p, v->n, bs->wi);
    s->ray.direction = bs->wi;
}

#endif
