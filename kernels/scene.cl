/* The scene as the integrators see it: the device buffers of one render, bundled. */
#ifndef SPECTRACE_SCENE_CL
#define SPECTRACE_SCENE_CL

#include "types.h"
#include "bvh.cl"
#include "camera.cl"
#include "lights.cl"
#include "medium.cl"
#include "texture.cl"
#include "hash.cl"

typedef struct {
    __global const RenderParams *params;
    __global const BVHNode *nodes;
    __global const float4 *triangle_vertices;
    __global const float2 *triangle_uvs;
    __global const float4 *triangle_normals;  /* shading normals of the smooth triangles' corners (TriangleInfo) */
    __global const TriangleInfo *triangle_info;
    __global const Material *materials;
    __global const Light *lights;
    __global const float *light_cdf;
    __global const float *spectra;
    __global const float4 *texels;  /* images of environment maps and textured emitters (a dummy texel if none) */
    __global const float *map_cdf;
    __global const Medium *media;
    __global const Texture *textures;  /* material and emission textures, whose texels share `texels` (a dummy row
                                          if none) */
    __global const AnalyticShape *shapes;  /* analytic spheres, disks and cylinders (a dummy row if none), in the
                                              leaf order of shape_nodes */
    __global const BVHNode *shape_nodes;   /* binary BVH over their boxes (a root no ray enters if none) */
    __global const Instance *instances;    /* placed copies of instanced objects (a dummy row if none), in the leaf
                                              order of the top-level BVH */
    __global const float4 *instance_nodes; /* the top-level binary BVH over the instances' world boxes (BVHNode,
                                              two float4 each), then each object's own BVH (Instance.nodes) */
#if FILM_AOVS
    __global const float4 *film_cmf;       /* the film's table (film.cl) for the emission AOV (aov.cl), set by the
                                              render passes; 0 (the initializer leaves it so) in other kernels */
#endif
} Scene;

/* The kinds of visibility query, told apart in a cut-out's choice (surface_met) so that a shadow ray and the path's
 * own ray from one vertex choose independently. */
#define QUERY_PATH 0x2c1b3c6dU    /* camera, BSDF- and phase-sampled rays: scene_intersect */
#define QUERY_SHADOW 0x297a2d39U  /* shadow rays of next-event estimation: scene_occluded, scene_transmittance */

/* The parameters every scene kernel starts with: the render's parameters, then the scene's buffers in the order
 * spectrace.core.contract.SCENE_KERNEL_BUFFERS names them (the host sets them from that list). A kernel
 * declared with them makes its Scene with `Scene scene = SCENE_FROM_KERNEL_PARAMS;`. */
#define SCENE_KERNEL_PARAMS                                                                                        \
    __global const RenderParams *params, __global const BVHNode *nodes, __global const float4 *triangle_vertices, \
        __global const float2 *triangle_uvs, __global const float4 *triangle_normals,                             \
        __global const TriangleInfo *triangle_info, __global const Material *materials,                           \
        __global const Light *lights, __global const float *light_cdf, __global const float *spectra,             \
        __global const float4 *texels, __global const float *map_cdf, __global const Medium *media,                \
        __global const Texture *textures, __global const AnalyticShape *shapes, __global const BVHNode *shape_nodes, \
        __global const Instance *instances, __global const float4 *instance_nodes
#define SCENE_FROM_KERNEL_PARAMS                                                                                   \
    {params, nodes, triangle_vertices, triangle_uvs, triangle_normals, triangle_info, materials, lights,           \
     light_cdf, spectra, texels, map_cdf, media, textures, shapes, shape_nodes, instances, instance_nodes}

inline LightBuffers light_buffers(const Scene *scene)
{
    LightBuffers b = {scene->triangle_vertices, scene->triangle_uvs, scene->spectra, scene->texels, scene->map_cdf,
                      {scene->textures, (__global const float *)scene->texels, scene->spectra}, scene->shapes};
    return b;
}

/* The lookups of a surface point's material parameters at texture coordinates uv with a footprint (texture.cl). */
inline SurfaceContext surface_context(const Scene *scene, float2 uv, float footprint)
{
    SurfaceContext sc;
    sc.buffers.textures = scene->textures;
    sc.buffers.texels = (__global const float *)scene->texels;
    sc.buffers.spectra = scene->spectra;
    sc.uv = uv;
    sc.p = (float3)(0.0f);
    sc.footprint = footprint;
    sc.base_normal = (float3)(0.0f);
    sc.dpdu = (float3)(0.0f);
    sc.tangent_w = 1.0f;
    sc.adjoint = 0;
#if SCENE_HAS_MESH_ATTRIBUTES
    sc.buffers.triangle = -1;
#endif
    SURFACE_NORMAL(sc, (float3)(0.0f));
#if SCENE_HAS_MITSUBA_CURVE_UV
    sc.fibre_h_from_geometry = 0;
#endif
    return sc;
}

/* surface_context at the world-space surface point p whose shading normal before its surface detail was base_normal and whose
 * dp/du is dpdu (0 where its material does not ask for it) of handedness tangent_w, for the transport `adjoint` (SurfaceContext): what
 * material_eval and material_sample take, for the shadowing term and an anisotropic frame. */
inline SurfaceContext shading_context(const Scene *scene, float2 uv, float3 p, float footprint, float3 base_normal,
                                      float3 dpdu, float tangent_w, int adjoint)
{
    SurfaceContext sc = surface_context(scene, uv, footprint);
    sc.p = p;
    sc.base_normal = base_normal;
    sc.dpdu = dpdu;
    sc.tangent_w = tangent_w;
    sc.adjoint = adjoint;
    return sc;
}

/* The texture footprint at point p of a triangle (normal n): how far uv moves between neighbouring pixels, estimated
 * from the camera as pbrt-v4 does for every intersection (Pharr, Jakob & Humphreys, 4th ed., 10.1.3,
 * Camera::Approximate_dp_dxy): the camera's rays one pixel to the right and down of p's (camera_neighbour_rays), met
 * with the tangent plane at p, give dp/dx and dp/dy; the triangle's positions and uvs map them to du/dx ... dv/dy;
 * the footprint is 2 max(|du/dx|, |dv/dx|, |du/dy|, |dv/dy|) (a filter spans a pixel on either side). After
 * reflections this is the camera's view of p, not the path's: an approximation that blurs no less than a primary
 * hit would. 0 (the finest level) where it cannot be formed: behind the camera, or a degenerate triangle.
 * footprint_from_tangents takes any surface on which moving by e1 and e2 moves uv by d1 and d2 (a triangle's edges,
 * or an analytic shape's dp/du and dp/dv with d1 = (1, 0), d2 = (0, 1)). */
inline float footprint_from_tangents(__global const RenderParams *camera, float3 p, float3 n, float3 e1, float3 e2,
                                     float2 d1, float2 d2)
{
    float3 ox, dx, oy, dy;
    if (!camera_neighbour_rays(camera, p, &ox, &dx, &oy, &dy)) return 0.0f;
    float3 dpdx = ox + dx * (dot(n, p - ox) / dot(n, dx)) - p;
    float3 dpdy = oy + dy * (dot(n, p - oy) / dot(n, dy)) - p;
    /* p = v0 + a e1 + b e2 and uv = t0 + a d1 + b d2: an offset in the plane has (a, b) from the Gram system. */
    float g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2);
    float det = g11 * g22 - g12 * g12;
    if (!(det > 0.0f)) return 0.0f;
    float ax = (g22 * dot(e1, dpdx) - g12 * dot(e2, dpdx)) / det, bx = (g11 * dot(e2, dpdx) - g12 * dot(e1, dpdx)) / det;
    float ay = (g22 * dot(e1, dpdy) - g12 * dot(e2, dpdy)) / det, by = (g11 * dot(e2, dpdy) - g12 * dot(e1, dpdy)) / det;
    float2 duv_dx = ax * d1 + bx * d2, duv_dy = ay * d1 + by * d2;
    float width = 2.0f * fmax(fmax(fabs(duv_dx.x), fabs(duv_dx.y)), fmax(fabs(duv_dy.x), fabs(duv_dy.y)));
    return isfinite(width) ? width : 0.0f;
}

inline float camera_footprint(const Scene *scene, int triangle, float3 p, float3 n)
{
    __global const float4 *v = scene->triangle_vertices + 3 * triangle;
    __global const float2 *t = scene->triangle_uvs + 3 * triangle;
    float3 e1 = v[1].xyz - v[0].xyz, e2 = v[2].xyz - v[0].xyz;
    float2 d1 = t[1] - t[0], d2 = t[2] - t[0];
    return footprint_from_tangents(scene->params, p, n, e1, e2, d1, d2);
}

/* Analytic shapes (shapes.cl) have a BVH of their own beside the triangles': a hit of shape k is slot
 * triangle_count + k of the TriangleInfo array, with the shape's texture coordinates in b12. A scene without them
 * builds with SCENE_HAS_SHAPES 0 and traces exactly as before they existed. */
inline int hit_is_shape(const Scene *scene, int slot)
{
#if !SCENE_HAS_SHAPES
    return 0;
#elif SCENE_HAS_INSTANCES
    /* Instanced objects' analytic shapes follow the scene's own, and their triangles follow all the shapes' slots. */
    return slot >= scene->params->triangle_count &&
           slot < scene->params->triangle_count + scene->params->shape_count + scene->params->instanced_shape_count;
#else
    return slot >= scene->params->triangle_count;
#endif
}

/* Whether the scene has nothing to hit. */
inline int scene_is_empty(const Scene *scene)
{
    int empty = scene->params->triangle_count == 0;
#if SCENE_HAS_SHAPES
    empty = empty && scene->params->shape_count == 0;
#endif
#if SCENE_HAS_INSTANCES
    empty = empty && scene->params->instance_count == 0;
#endif
    return empty;
}

#if SCENE_HAS_SHAPES
inline __global const AnalyticShape *hit_shape(const Scene *scene, int slot)
{
    return &scene->shapes[slot - scene->params->triangle_count];
}

#if SCENE_HAS_MITSUBA_CURVE_UV
/* Whether hit slot `slot` is a curve with Mitsuba 3's texture coordinates (shape_curve.cl; SURFACE_AT_HIT). */
inline int curve_slot_has_mitsuba_uv(const Scene *scene, int slot)
{
    return hit_is_shape(scene, slot) && hit_shape(scene, slot)->type == SHAPE_CURVE && !hit_shape(scene, slot)->pbrt_uv;
}
#endif

/* The closest analytic shape the ray meets before t_max (any of them when any_hit): bvh.cl's binary traversal
 * (trace_bvh_binary) over the shapes' own BVH, whose leaves are runs of shapes. */
inline Hit intersect_shapes(const Scene *scene, Ray ray, float t_max, int any_hit)
{
    Hit hit = no_hit(t_max);
    /* The empty BVH's inverted root box still admits rays (the slab test orders each axis' bounds). */
    if (scene->params->shape_count == 0) return hit;
    __global const BVHNode *nodes = scene->shape_nodes;
    float3 inv_direction = slab_inverse_direction(ray.direction);
    BinaryWalk walk;
    if (!binary_walk_start(&walk, nodes, ray.origin, inv_direction, t_max)) return hit;
    while (binary_walk_to_leaf(&walk, nodes, ray.origin, inv_direction, hit.t)) {
        __global const BVHNode *node = &nodes[walk.index];
        for (int k = node->left_first; k < node->left_first + node->count; ++k) {
            float2 uv;
            float t = intersect_shape(&scene->shapes[k], ray.origin, ray.direction, hit.t, &uv);
            if (t < hit.t) {
                hit.t = t;
                hit.triangle = scene->params->triangle_count + k;
                hit.b12 = uv;
                if (any_hit) return hit;
            }
        }
        if (!binary_walk_pop(&walk, hit.t)) break;
    }
    return hit;
}
#endif

/* Instances (two-level BVH, as in Wald et al. 2003 and pbrt-v4's and Mitsuba 3's instancing): an object's triangles
 * are stored once, at TriangleInfo slots after the analytic shapes' (their vertices, uvs and normals at the same
 * slots of the triangle arrays, which hold unused entries for the shapes), under a 4-wide BVH of their own built in
 * object space. A binary top-level BVH over the instances' world boxes leads to Instance rows; a ray reaching one is
 * taken into object space (direction not renormalised, so t stays the world distance) and traced through the
 * object's BVH. The object's analytic shapes (a short list, AnalyticShape rows in object space after the scene's
 * own, slots triangle_count + row) are met by the same object-space ray, its direction made unit for
 * intersect_shape and its distances scaled back to world units: the ray is transformed, never the shape, so any
 * affine placement (non-uniform scale, shear, mirror) gives the exact quadric (pbrt-v4 and Mitsuba 3 do the same).
 * The hit keeps the object's slot, so materials, media and cut-outs need nothing new, and the Instance, whose map
 * takes points and tangents to world space and normals by its inverse transpose. A scene without instances builds
 * with SCENE_HAS_INSTANCES 0 and traces exactly as before they existed. */
#if SCENE_HAS_INSTANCES
inline float3 affine_point(__global const float4 *rows, float3 p)
{
    return (float3)(dot(rows[0].xyz, p) + rows[0].w, dot(rows[1].xyz, p) + rows[1].w, dot(rows[2].xyz, p) + rows[2].w);
}

inline float3 affine_vector(__global const float4 *rows, float3 v)
{
    return (float3)(dot(rows[0].xyz, v), dot(rows[1].xyz, v), dot(rows[2].xyz, v));
}

/* M⁻ᵀ n of an object-space normal n (not normalised): the columns of to_object's linear part weighted by n. */
inline float3 instance_normal_direction(__global const Instance *instance, float3 n)
{
    return n.x * instance->to_object[0].xyz + n.y * instance->to_object[1].xyz + n.z * instance->to_object[2].xyz;
}

inline float3 instance_normal(__global const Instance *instance, float3 n)
{
    return normalize(instance_normal_direction(instance, n));
}

#if SCENE_HAS_SHAPES
/* The closest of an instance's analytic shapes that the object-space ray `in_object` (direction M⁻¹ d for a unit
 * world direction d) meets before world distance hit.t, replacing `hit` (t in world units) when one is closer; any
 * of them when any_hit. Requires instance->shape_count > 0. */
inline Hit intersect_instance_shapes(const Scene *scene, __global const Instance *instance, Ray in_object, Hit hit,
                                     int any_hit)
{
    float object_per_world = length(in_object.direction);  /* object-space length of one world unit along the ray */
    if (!(object_per_world > 0.0f)) return hit;
    float3 direction = in_object.direction / object_per_world;
    float t_object = hit.t * object_per_world;
    for (int k = instance->first_shape; k < instance->first_shape + instance->shape_count; ++k) {
        float2 uv;
        float t = intersect_shape(&scene->shapes[k], in_object.origin, direction, t_object, &uv);
        if (t < t_object) {
            t_object = t;
            hit.t = t / object_per_world;
            hit.triangle = scene->params->triangle_count + k;
            hit.b12 = uv;
            if (any_hit) return hit;
        }
    }
    return hit;
}
#endif

/* The closest instanced triangle or analytic shape the ray meets before t_max (any of them when any_hit): the binary
 * traversal of intersect_shapes over the top-level BVH, whose leaves are runs of instances, each traced in its
 * object's BVH and then its object's shapes. */
inline Hit intersect_instances(const Scene *scene, Ray ray, float t_max, int any_hit)
{
    Hit hit = no_hit(t_max);
    if (scene->params->instance_count == 0) return hit;
    __global const BVHNode *nodes = (__global const BVHNode *)scene->instance_nodes;
    float3 inv_direction = slab_inverse_direction(ray.direction);
    BinaryWalk walk;
    if (!binary_walk_start(&walk, nodes, ray.origin, inv_direction, t_max)) return hit;
    while (binary_walk_to_leaf(&walk, nodes, ray.origin, inv_direction, hit.t)) {
        __global const BVHNode *node = &nodes[walk.index];
        for (int k = node->left_first; k < node->left_first + node->count; ++k) {
            __global const Instance *instance = &scene->instances[k];
            Ray in_object;
            in_object.origin = affine_point(instance->to_object, ray.origin);
            in_object.direction = affine_vector(instance->to_object, ray.direction);
#if SCENE_HAS_SHAPES
            Hit h = no_hit(hit.t);
            if (instance->nodes >= 0) {
                h = trace_bvh((__global const BVHNode *)(scene->instance_nodes + instance->nodes),
                              scene->triangle_vertices, in_object, hit.t, any_hit);
            }
            if (instance->shape_count > 0 && !(any_hit && h.triangle >= 0)) {
                h = intersect_instance_shapes(scene, instance, in_object, h, any_hit);
            }
#else
            Hit h = trace_bvh((__global const BVHNode *)(scene->instance_nodes + instance->nodes),
                              scene->triangle_vertices, in_object, hit.t, any_hit);
#endif
            if (h.triangle >= 0) {
                hit = h;
                hit.instance = k;
                if (any_hit) return hit;
            }
        }
        if (!binary_walk_pop(&walk, hit.t)) break;
    }
    return hit;
}
#endif

/* The closest surface before t_max among the scene's own triangles and analytic shapes (any one when any_hit). */
inline Hit trace_scene_own(const Scene *scene, Ray ray, float t_max, int any_hit)
{
#if SCENE_HAS_SHAPES
    Hit shape_hit = intersect_shapes(scene, ray, t_max, any_hit);
    if ((any_hit && shape_hit.triangle >= 0) || scene->params->triangle_count == 0) return shape_hit;
    Hit hit = trace_bvh(scene->nodes, scene->triangle_vertices, ray, shape_hit.t, any_hit);
    return hit.triangle >= 0 ? hit : shape_hit;
#else
    return trace_bvh(scene->nodes, scene->triangle_vertices, ray, t_max, any_hit);
#endif
}

/* The closest surface before t_max, triangle, analytic shape or instanced triangle (any one when any_hit). */
inline Hit trace_scene(const Scene *scene, Ray ray, float t_max, int any_hit)
{
#if SCENE_HAS_INSTANCES
    Hit hit = trace_scene_own(scene, ray, t_max, any_hit);
    if (any_hit && hit.triangle >= 0) return hit;
    Hit instance_hit = intersect_instances(scene, ray, hit.t, any_hit);
    return instance_hit.triangle >= 0 ? instance_hit : hit;
#else
    return trace_scene_own(scene, ray, t_max, any_hit);
#endif
}

#if SCENE_HAS_SHAPES
/* The world-space surface at a hit of an analytic shape (hit_is_shape): an instanced object's shape is rebuilt in
 * object space and taken to world space by its instance's map (points and tangents by M, the normal by M⁻ᵀ, which
 * keeps its side). */
inline ShapeSurface hit_shape_surface(const Scene *scene, Hit hit)
{
    ShapeSurface g = shape_surface(hit_shape(scene, hit.triangle), hit.b12);
#if SCENE_HAS_INSTANCES
    if (hit.instance >= 0) {
        __global const Instance *instance = &scene->instances[hit.instance];
        __global const float4 *m = instance->to_world;
        g.p = affine_point(m, g.p);
        g.dpdu = affine_vector(m, g.dpdu);
        g.dpdv = affine_vector(m, g.dpdv);
        float3 n = instance_normal_direction(instance, g.n);
        float length_n = length(n);
        g.n = n / length_n;
        g.area_stretch *= fabs(dot(m[0].xyz, cross(m[1].xyz, m[2].xyz))) * length_n;
    }
#endif
    return g;
}
#endif

/* The geometric normal and point of a hit, for either kind of surface. */
inline float3 hit_normal(const Scene *scene, Hit hit)
{
#if SCENE_HAS_SHAPES
    if (hit_is_shape(scene, hit.triangle)) return hit_shape_surface(scene, hit).n;
#endif
#if SCENE_HAS_INSTANCES
    if (hit.instance >= 0) {
        return instance_normal(&scene->instances[hit.instance], triangle_normal(scene->triangle_vertices, hit.triangle));
    }
#endif
    return triangle_normal(scene->triangle_vertices, hit.triangle);
}

inline float3 hit_point(const Scene *scene, Hit hit)
{
#if SCENE_HAS_SHAPES
    if (hit_is_shape(scene, hit.triangle)) return hit_shape_surface(scene, hit).p;
#endif
#if SCENE_HAS_INSTANCES
    if (hit.instance >= 0) {
        return affine_point(scene->instances[hit.instance].to_world,
                            triangle_point(scene->triangle_vertices, hit.triangle, hit.b12));
    }
#endif
    return triangle_point(scene->triangle_vertices, hit.triangle, hit.b12);
}

/* Texture coordinates of a hit. */
inline float2 hit_uv(const Scene *scene, Hit hit)
{
#if SCENE_HAS_SDF_GRIDS
    /* An SDF grid's b12 holds its hit point: it has no texture coordinates (shape_sdf_grid.cl). */
    if (hit_is_shape(scene, hit.triangle) && hit_shape(scene, hit.triangle)->type == SHAPE_SDFGRID) return 0.0f;
#endif
#if SCENE_HAS_CURVES
    if (hit_is_shape(scene, hit.triangle) && hit_shape(scene, hit.triangle)->type == SHAPE_CURVE)
        return curve_axis_uv(hit_shape(scene, hit.triangle), hit.b12);
#endif
    if (hit_is_shape(scene, hit.triangle)) return hit.b12;
    return triangle_uv(scene->triangle_uvs, hit.triangle, hit.b12);
}

#if SCENE_HAS_OPACITY
/* Cut-outs (docs/textures.md, "Opacity"): a ray meets a surface of opacity α with probability α and otherwise goes
 * on as if it were not there, in every query (camera and BSDF rays, shadow rays, sensors). The choice is a hash of
 * the query's identity (`query`: the sample, how far along its path, the kind of query; the callers' opacity_query),
 * the triangle and the surfaces already crossed by the query; not a sampler draw, so the sampler's dimensions stay
 * what they were, and not the ray's bits, so kernels that round a ray differently in its last bit (the wavefront
 * and the megakernel, a scene's own kernels and the general ones) still choose alike. */
#define MAX_OPACITY_CROSSINGS 64

/* The opacity at barycentrics b12 of a triangle (1 for a material-less medium boundary), read at the finest level. */
inline float surface_opacity(const Scene *scene, int triangle, float2 b12)
{
    int material = scene->triangle_info[triangle].material;
    if (material == TRIANGLE_NO_MATERIAL) return 1.0f;
    __global const Material *m = &scene->materials[material];
    if (SCENE_HAS_TEXTURES && m->opacity_texture != NO_TEXTURE) {
        Hit at;
        at.triangle = triangle;
        at.b12 = b12;
#if SCENE_HAS_INSTANCES
        at.instance = -1;  /* hit_uv reads only the slot */
#endif
        SurfaceContext sc = surface_context(scene, hit_uv(scene, at), 0.0f);
        SURFACE_HIT_DETAIL(sc, at);  /* an opacity is no directionmix: no normal */
        return texture_numbers(&sc.buffers, m->opacity_texture, sc.uv, 0.0f).x;
    }
    return m->opacity;
}

/* Whether query `query` meets the surface of `hit`, its `crossing`th surface (from 0). */
inline int surface_met(const Scene *scene, uint query, int crossing, Hit hit)
{
    float opacity = surface_opacity(scene, hit.triangle, hit.b12);
    if (opacity >= 1.0f) return 1;
    if (!(opacity > 0.0f)) return 0;
    uint h = hash_u32(hash_u32(query ^ hash_u32((uint)hit.triangle)) ^ (uint)crossing);
    return (float)(h >> 8) * 0x1.0p-24f < opacity;
}

/* The ray `ray` (first traced as `query`) started again just past the surface of `hit`. */
inline Ray ray_past(const Scene *scene, Ray ray, Hit hit)
{
    ray.origin = offset_ray_origin(hit_point(scene, hit), hit_normal(scene, hit), ray.direction);
    return ray;
}
#endif

/* The closest surface along the ray (none in a scene without triangles) that the ray meets (a cut-out surface it
 * passes through is skipped; the hit's distance is still from the ray's origin). `query` names the query for the
 * cut-outs' choices (surface_met). */
inline Hit scene_intersect(const Scene *scene, Ray ray, uint query, uint *rays_traced)
{
    *rays_traced += 1;
    if (scene_is_empty(scene)) return no_hit(INFINITY);
    Hit hit = trace_scene(scene, ray, INFINITY, 0);
#if SCENE_HAS_OPACITY
    Ray past = ray;
    for (int crossing = 0;
         hit.triangle >= 0 && crossing < MAX_OPACITY_CROSSINGS && !surface_met(scene, query, crossing, hit);
         ++crossing) {
        past = ray_past(scene, past, hit);
        float t_past = dot(past.origin - ray.origin, ray.direction);
        *rays_traced += 1;
        hit = trace_scene(scene, past, INFINITY, 0);
        hit.t += t_past;
    }
#endif
    return hit;
}

/* Whether anything blocks the segment from `from` (already offset off its surface) to `to`; `to` may be at
 * infinity (distant and environment lights), then `direction` is used. `query` as for scene_intersect. */
inline int scene_occluded(const Scene *scene, float3 from, float3 to, float3 direction, int to_infinity,
                          uint query, uint *rays_traced)
{
    if (scene_is_empty(scene)) return 0;
    *rays_traced += 1;
    Ray shadow;
    shadow.origin = from;
    float t_max = INFINITY;
    if (to_infinity) {
        shadow.direction = direction;
    } else {
        float3 d = to - from;
        float length_d = length(d);
        if (!(length_d > 0.0f)) return 0;
        shadow.direction = d / length_d;
        t_max = length_d * 0.9999f;  /* stop just short of the light's own surface */
    }
#if SCENE_HAS_OPACITY
    /* Closest hits in turn, since an any-hit answer could be a cut-out surface behind one that blocks. */
    Ray past = shadow;
    float t_left = t_max;
    for (int crossing = 0; crossing <= MAX_OPACITY_CROSSINGS; ++crossing) {
        Hit hit = trace_scene(scene, past, t_left, 0);
        if (hit.triangle < 0) return 0;
        if (crossing == MAX_OPACITY_CROSSINGS || surface_met(scene, query, crossing, hit)) return 1;
        past = ray_past(scene, past, hit);
        t_left = t_max - dot(past.origin - shadow.origin, shadow.direction);
        if (!(t_left > 0.0f)) return 0;
        *rays_traced += 1;
    }
    return 1;
#else
    return trace_scene(scene, shadow, t_max, 1).triangle >= 0;
#endif
}

/* The fraction of light per wavelength that crosses the same segment as scene_occluded, for a segment that starts
 * in `medium` (-1: none; the path's medium on the side the segment leaves): 0 when a surface blocks it, else
 * exp(−Σ σt·length) over the media it travels through, passing material-less (index-matched) boundaries, so
 * shadow rays see what a path would (Beer–Lambert). Each boundary changes the medium as it changes a path's
 * (medium_beyond). `query` as for scene_intersect. */
inline float4 scene_transmittance(const Scene *scene, const SampledWavelengths *w, int medium, float3 from, float3 to,
                                  float3 direction, int to_infinity, uint query, uint *rays_traced)
{
    if (!SCENE_HAS_MEDIA || (scene->params->medium_count == 0 && !scene->params->null_surfaces)) {
        return scene_occluded(scene, from, to, direction, to_infinity, query, rays_traced) ? (float4)(0.0f)
                                                                                            : (float4)(1.0f);
    }
    Ray segment;
    segment.origin = from;
    float t_end = INFINITY;  /* along the whole segment, from `from` */
    if (to_infinity) {
        segment.direction = direction;
    } else {
        float3 d = to - from;
        float length_d = length(d);
        if (!(length_d > 0.0f)) return (float4)(1.0f);
        segment.direction = d / length_d;
        t_end = length_d * 0.9999f;  /* stop just short of the light's own surface */
    }
    float4 optical_depth = (float4)(0.0f);
    int medium_ahead = medium;
    float t_origin = 0.0f;
#if SCENE_HAS_OPACITY
    float carried = 0.0f;  /* the stretch since the last medium boundary before segment.origin (cut-outs passed) */
#define STRETCH(t) ((t) + carried)
#else
#define STRETCH(t) (t)
#endif
#if SCENE_HAS_GRID_MEDIA
    float4 ratio = (float4)(1.0f);  /* the grid media's tracked transmittance (medium_grid.cl) */
#endif
    for (int crossing = 0; crossing <= MAX_NULL_CROSSINGS; ++crossing) {
        Hit hit;
        hit.triangle = -1;
        if (!scene_is_empty(scene)) {
            *rays_traced += 1;
            hit = trace_scene(scene, segment, fmax(t_end - t_origin, 0.0f), 0);
        }
        if (hit.triangle < 0) {
#if SCENE_HAS_GRID_MEDIA
            /* As below, times the grid media's factor (exactly 1 where the segment crossed none). */
            if (medium_ahead < 0) return exp(-optical_depth) * ratio;
            if (isinf(t_end)) return (float4)(0.0f);
            if (scene->media[medium_ahead].grid >= 0) {
                return exp(-optical_depth) * ratio
                     * grid_stretch(scene->media, scene->spectra, w, medium_ahead, segment.origin,
                                    segment.direction, STRETCH(0.0f), t_end - t_origin, query, crossing);
            }
            float4 sigma_t_ahead = medium_sigma_t(&scene->media[medium_ahead], scene->spectra, w);
            return exp(-(optical_depth + sigma_t_ahead * STRETCH(fmax(t_end - t_origin, 0.0f)))) * ratio;
#else
            if (medium_ahead < 0) return exp(-optical_depth);
            if (isinf(t_end)) return (float4)(0.0f);  /* a leak out of a closed medium: light cannot get through */
            float4 sigma_t = medium_sigma_t(&scene->media[medium_ahead], scene->spectra, w);
            return exp(-(optical_depth + sigma_t * STRETCH(fmax(t_end - t_origin, 0.0f))));
#endif
        }
        TriangleInfo info = scene->triangle_info[hit.triangle];
#if SCENE_HAS_OPACITY
        if (info.material != TRIANGLE_NO_MATERIAL) {
            if (surface_met(scene, query, crossing, hit)) return (float4)(0.0f);
            segment = ray_past(scene, segment, hit);
            float t_past = dot(segment.origin - from, segment.direction);
            carried += t_past - t_origin;
            t_origin = t_past;
            continue;
        }
#else
        if (info.material != TRIANGLE_NO_MATERIAL) return (float4)(0.0f);
#endif
        float3 n = hit_normal(scene, hit);
#if SCENE_HAS_GRID_MEDIA
        if (medium_ahead >= 0 && scene->media[medium_ahead].grid >= 0) {
            ratio *= grid_stretch(scene->media, scene->spectra, w, medium_ahead, segment.origin, segment.direction,
                                  STRETCH(0.0f), hit.t, query, crossing);
        } else
#endif
        if (medium_ahead >= 0) {
            optical_depth += medium_sigma_t(&scene->media[medium_ahead], scene->spectra, w) * STRETCH(hit.t);
        }
#if SCENE_HAS_OPACITY
        carried = 0.0f;
#endif
        medium_ahead = medium_beyond(info.interior, n, segment.direction, medium_ahead);
        float3 p = hit_point(scene, hit);
        segment.origin = offset_ray_origin(p, n, segment.direction);
        t_origin = dot(segment.origin - from, segment.direction);
    }
    return (float4)(0.0f);
#undef STRETCH
}

/* The medium around a point (-1: none), for paths that start away from the camera (light paths): a probe ray from
 * the point goes on past every surface without an interior until it meets a medium boundary, which it leaves (the
 * point is inside that medium) or enters (outside every medium). One level, as media do not nest (medium.cl). */
inline int scene_medium_at(const Scene *scene, float3 point)
{
    if (!SCENE_HAS_MEDIA || scene->params->medium_count == 0 || scene_is_empty(scene)) return -1;
    Ray probe;
    probe.origin = point;
    probe.direction = normalize((float3)(0.267f, 0.535f, 0.802f));  /* any direction: boundaries are closed */
    for (int crossing = 0; crossing <= MAX_NULL_CROSSINGS; ++crossing) {
        Hit hit = trace_scene(scene, probe, INFINITY, 0);
        if (hit.triangle < 0) return -1;
        int interior = scene->triangle_info[hit.triangle].interior;
        float3 n = hit_normal(scene, hit);
        if (interior >= 0) return dot(n, probe.direction) > 0.0f ? interior : -1;
        probe.origin = offset_ray_origin(hit_point(scene, hit), n, probe.direction);
    }
    return -1;
}

#endif
