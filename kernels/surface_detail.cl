/* Normal and bump maps: the shading normal a material's surface detail turns (docs/textures.md, "Surface detail";
 * host: spectrace.materials.surface). Both work in the triangle's tangent frame: dp/du and dp/dv from its corners'
 * positions and texture coordinates, made orthogonal to the (smooth) shading normal. The turned normal takes the
 * smooth one's place in the BSDF's frame, and the rules of shading_normal.cl hold for it as for the smooth one (a
 * viewer on different sides of it and the geometric normal shades with the geometric normal; directions on
 * different sides are dropped in next-event estimation and BSDF sampling alike). */
#ifndef SPECTRACE_SURFACE_DETAIL_CL
#define SPECTRACE_SURFACE_DETAIL_CL

#include "scene.cl"
#include "frame.cl"
#include "vertex_tangents.cl"

/* dp/du and dp/dv of a triangle: p = v0 + a e1 + b e2 and uv = t0 + a d1 + b d2 solved for (a, b). 0 when its
 * texture coordinates do not span the plane (a degenerate parametrisation). */
inline int triangle_dp_duv(const Scene *scene, int triangle, float3 *dpdu, float3 *dpdv)
{
    __global const float4 *v = scene->triangle_vertices + 3 * triangle;
    __global const float2 *t = scene->triangle_uvs + 3 * triangle;
    float3 e1 = v[1].xyz - v[0].xyz, e2 = v[2].xyz - v[0].xyz;
    float2 d1 = t[1] - t[0], d2 = t[2] - t[0];
    float det = d1.x * d2.y - d1.y * d2.x;
    if (det == 0.0f) return 0;
    *dpdu = (d2.y * e1 - d1.y * e2) / det;
    *dpdv = (d1.x * e2 - d2.x * e1) / det;
    return all(isfinite(*dpdu)) && all(isfinite(*dpdv));
}

/* The part of d in the plane normal to n. */
inline float3 in_plane(float3 n, float3 d)
{
    return d - n * dot(n, d);
}

#if SCENE_HAS_NORMAL_MAP_HANDEDNESS
/* w of glTF 2.0's bitangent = cross(normal, tangent.xyz) · w (3.7.2.1), for material m whose normal map asks for it:
 * −1 where the texture layout is mirrored, i.e. where n × dp/du points down the image, along +dp/dv (spectrace's
 * v runs down the image, as glTF's does), so that the map's +y (green) points up the image on both halves of a
 * mirrored layout, as MikkTSpace's sign makes it in Blender; 1 otherwise, and for every other material. */
inline float normal_map_handedness(__global const Material *m, float3 bitangent, float3 dpdv)
{
    return (m->normal_map_handedness && dot(bitangent, dpdv) > 0.0f) ? -1.0f : 1.0f;
}
#endif

/* ∂h/∂u and ∂h/∂v of bump map `index` at uv: a bitmap's is the exact gradient of its lookup (image_texture_gradient:
 * the bilinear interpolant's, 0 for nearest), as Mitsuba 3's bumpmap takes it. A checkerboard's heights are flat
 * but for their edges, whose relief a derivative would miss: forward differences over half the footprint (about a
 * pixel's width, pbrt-v4's BumpMap step) or, where the footprint is 0, pbrt-v4's fixed 5e-4, show them. */
inline float2 bump_gradient(const TextureBuffers *b, int index, float2 uv, float footprint)
{
    __global const Texture *t = &b->textures[index];
    if (t->type != TEXTURE_CHECKERBOARD) {
        SampledWavelengths w = fixed_wavelengths((float4)(560.0f));
        return image_texture_gradient(t, b, uv, footprint, &w);
    }
    float step = footprint > 0.0f ? 0.5f * footprint : 5.0e-4f;
    float h = texture_numbers(b, index, uv, footprint).x;
    float h_u = texture_numbers(b, index, uv + (float2)(step, 0.0f), footprint).x;
    float h_v = texture_numbers(b, index, uv + (float2)(0.0f, step), footprint).x;
    return (float2)(h_u - h, h_v - h) / step;
}

/* The shading normal of material m at a point with tangents dpdu, dpdv (when `parametrised`), texture coordinates
 * uv and footprint, turned from ns by its normal map or bump map; ns itself when it has neither or the turn cannot
 * be formed. `file_w` ≠ 0: the normal map's frame is the file's tangent `file_t` with bitangent
 * cross(ns, tangent) · file_w (vertex_tangents.cl); 0: dp/du's. */
inline float3 detailed_normal_at(const Scene *scene, __global const Material *m, int parametrised, float3 dpdu,
                                 float3 dpdv, float2 uv, float footprint, float3 n_geometric, float3 ns, float3 wo,
                                 float3 file_t, float file_w)
{
    SurfaceContext sc = surface_context(scene, uv, footprint);
    float3 n;
    if (m->normal_map != NO_TEXTURE) {
        /* x along +u, y = z × x, z = ns (Mitsuba 3's normalmap frame); any frame about ns where uv is degenerate. */
        float3 mapped = 2.0f * texture_numbers(&sc.buffers, m->normal_map, uv, footprint).xyz - 1.0f;
        ShadingFrame frame = shading_frame(ns);
        float3 s = parametrised ? in_plane(ns, dpdu) : (float3)(0.0f);
#if SCENE_HAS_FILE_TANGENTS
        if (file_w != 0.0f) s = in_plane(ns, file_t);  /* Gram-Schmidt against the shading normal */
#endif
        float length_s = length(s);
        if (length_s > 0.0f) {
            frame.tangent = s / length_s;
            frame.bitangent = cross(ns, frame.tangent);
#if SCENE_HAS_FILE_TANGENTS
            if (file_w != 0.0f) {
                frame.bitangent *= file_w;
            } else
#endif
            {
#if SCENE_HAS_NORMAL_MAP_HANDEDNESS
                frame.bitangent *= normal_map_handedness(m, frame.bitangent, dpdv);
#endif
            }
        }
        n = to_world(&frame, mapped);
    } else {
        /* Blinn 1978: the surface displaced by h·bump_scale along ns has tangents dp/du + (∂h/∂u)·bump_scale·ns
         * and dp/dv + (∂h/∂v)·bump_scale·ns (their parts along ns replaced, as Mitsuba 3's bumpmap does). */
        if (!parametrised) return ns;
        float2 slope = m->bump_scale * bump_gradient(&sc.buffers, m->bump_map, uv, footprint);
        float3 tu = in_plane(ns, dpdu) + ns * slope.x;
        float3 tv = in_plane(ns, dpdv) + ns * slope.y;
        n = cross(tu, tv);
        /* The cross product's sign follows the uv layout's handedness; the surface's front is ns's side. */
        if (dot(n, ns) < 0.0f) n = -n;
    }
    float length_n = length(n);
    if (!(length_n > 0.0f) || !isfinite(length_n)) return ns;
    n /= length_n;
    return dot(n, wo) * dot(n_geometric, wo) > 0.0f ? n : n_geometric;
}

/* detailed_normal_at a hit of `triangle`, in its tangent frame (the file's where file_w ≠ 0). */
inline float3 detailed_normal(const Scene *scene, __global const Material *m, int triangle, float2 uv,
                              float footprint, float3 n_geometric, float3 ns, float3 wo, float3 file_t, float file_w)
{
    if (m->normal_map == NO_TEXTURE && m->bump_map == NO_TEXTURE) return ns;
    float3 dpdu, dpdv;
    int parametrised = triangle_dp_duv(scene, triangle, &dpdu, &dpdv);
    return detailed_normal_at(scene, m, parametrised, dpdu, dpdv, uv, footprint, n_geometric, ns, wo, file_t, file_w);
}

#endif
