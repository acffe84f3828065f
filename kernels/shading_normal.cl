/* Smooth shading: the normal a BSDF's frame takes at a hit of a triangle with vertex normals, interpolated from its
 * corners, and the rule for directions on which the shading and the geometric normal disagree.
 *
 * The geometric normal keeps every decision about sides: which side of the surface a direction is on, where a
 * ray leaves from (offset_ray_origin), which medium it enters (medium_beyond), which side an area light emits
 * to, whether a one-sided material is seen from its back. The host winds each triangle with vertex normals toward
 * them (TriangleMesh.corners), so its geometric normal faces the side its normals do, the front as Mitsuba 3's
 * shading frame decides it. Only the BSDF's frame (material_frame, material.cl) turns with the shading normal,
 * cosines included; light subpaths (light_tracer.cl, bdpt.cl) add the correction that importance transport needs
 * for shading normals (Veach 1997, thesis §5.3).
 *
 * Where the two normals disagree, a direction would count as reflected for one and transmitted for the other, and
 * light leaks through the surface. Two rules keep them consistent, the same in next-event estimation and in BSDF
 * sampling (so MIS weighs the same set of directions), in both integrators and both kernel shapes:
 * 1. at the vertex: when the viewer is on different sides of the two normals (a grazing view near a silhouette)
 *    the vertex shades with the geometric normal, since every BSDF expects wo above its frame and a dielectric
 *    reads its interior's side from it;
 * 2. for the other direction: light arriving or leaving along wi counts only when wi is on the same side of both
 *    normals. This is Mitsuba's choice (its path tracers discard such samples, "strict normals"); pbrt-v4 instead
 *    evaluates its BxDFs in the shading frame alone and lets them through, which can brighten or leak. The rule
 *    loses only the thin wedge between the two tangent planes, which shrinks with finer tessellation.
 * Flat triangles (TriangleInfo.normals < 0) read nothing more and skip both tests, so they render as before. */
#ifndef SPECTRACE_SHADING_NORMAL_CL
#define SPECTRACE_SHADING_NORMAL_CL

#include "scene.cl"

/* The shading normal at barycentrics b12 of a triangle whose corner normals start at entry 3·normals, seen from wo:
 * the interpolated normal turned to the winding's front (which says inside from outside, as for the geometric
 * one; the host winds the triangle so, and this turns only where corner normals cross the triangle's plane), or
 * the geometric normal n_geometric by rule 1 above, or when the interpolation vanishes (opposite corner normals). */
inline float3 shading_normal(const Scene *scene, int normals, float2 b12, float3 n_geometric, float3 wo)
{
    __global const float4 *corner = scene->triangle_normals + 3 * normals;
    float3 n = (1.0f - b12.x - b12.y) * corner[0].xyz + b12.x * corner[1].xyz + b12.y * corner[2].xyz;
    float length_n = length(n);
    if (!(length_n > 0.0f)) return n_geometric;
    n /= length_n;
    if (dot(n, n_geometric) < 0.0f) n = -n;
    return dot(n, wo) * dot(n_geometric, wo) > 0.0f ? n : n_geometric;
}

#if SCENE_HAS_INSTANCES
/* shading_normal at a hit of an instanced object's triangle: the corners' object-space normals interpolated, then
 * taken to world space by the instance's inverse transpose (as the host turns the normals of a transformed mesh). */
inline float3 instance_shading_normal(const Scene *scene, __global const Instance *instance, int normals, float2 b12,
                                      float3 n_geometric, float3 wo)
{
    __global const float4 *corner = scene->triangle_normals + 3 * normals;
    float3 n = (1.0f - b12.x - b12.y) * corner[0].xyz + b12.x * corner[1].xyz + b12.y * corner[2].xyz;
    n = instance_normal_direction(instance, n);
    float length_n = length(n);
    if (!(length_n > 0.0f)) return n_geometric;
    n /= length_n;
    if (dot(n, n_geometric) < 0.0f) n = -n;
    return dot(n, wo) * dot(n_geometric, wo) > 0.0f ? n : n_geometric;
}
#endif

/* Rule 2 above: 0 when wi is on different sides of the shading and the geometric normal. A vertex that shades with
 * its geometric normal passes without a test. */
inline int shading_side_agrees(float3 n_geometric, float3 n_shading, float3 wi)
{
    return all(n_shading == n_geometric) || dot(wi, n_geometric) * dot(wi, n_shading) > 0.0f;
}

#endif
