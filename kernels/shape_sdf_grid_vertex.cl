/* A path vertex on an SDF grid (shape_sdf_grid.cl): its shading normal, the grid's own ("smooth" or "analytic"),
 * taken to world space as the geometric normal is (the shape's M⁻ᵀ, then an instance's), and no texture
 * coordinates (Mitsuba 3's sdfgrid has none: textures read uv = (0, 0)). Requires PathVertex (path_state.cl). */
#ifndef SPECTRACE_SHAPE_SDF_GRID_VERTEX_CL
#define SPECTRACE_SHAPE_SDF_GRID_VERTEX_CL

inline void sdf_grid_vertex_shading(const Scene *scene, Hit hit, PathVertex *v)
{
    __global const AnalyticShape *s = hit_shape(scene, hit.triangle);
    float3 ns = shape_normal_to_world(s, sdf_grid_shading_local(s, hit.b12));
#if SCENE_HAS_INSTANCES
    if (hit.instance >= 0) ns = instance_normal_direction(&scene->instances[hit.instance], ns);
#endif
    float length_ns = length(ns);
    if (length_ns > 0.0f) {
        v->ns = ns / length_ns;
        v->ns_base = v->ns;
    }
    v->uv = (float2)(0.0f);
}

#endif
