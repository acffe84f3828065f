/* Tangents a mesh file supplies (glTF 2.0's TANGENT, 3.7.2.1: xyz along +u, w = ±1 the handedness, the bitangent
 * cross(normal, xyz) · w), interpolated across a smooth triangle. Where a triangle has them they frame its normal
 * map and its anisotropic lobes instead of its dp/du (surface_detail.cl, material.cl), so a model whose tangents
 * disagree with its texture layout (mirrored geometry with unmirrored texture coordinates) shades as its author
 * baked it. Layout (host: spectrace.engine.vertex_tangents): a triangle whose corner normals are slot k of
 * triangle_normals holds its handedness in the first corner's w (0: no file tangents) and its corner tangents
 * (x, y, z, w) in slot k + 1. Units: none (directions); object space for an instanced object's triangles. */
#ifndef SPECTRACE_VERTEX_TANGENTS_CL
#define SPECTRACE_VERTEX_TANGENTS_CL

#include "scene.cl"

#if SCENE_HAS_FILE_TANGENTS
/* The handedness w (±1) of the file tangents of the triangle whose normals are slot `normals`, with their
 * interpolation at barycentrics b12 in *tangent (not normalised, not yet orthogonal to the shading normal); 0, and
 * *tangent untouched, where the triangle has none (flat, or a mesh without tangents). */
inline float file_tangent(const Scene *scene, int normals, float2 b12, float3 *tangent)
{
    if (normals < 0) return 0.0f;
    __global const float4 *corner = scene->triangle_normals + 3 * normals;
    float w = corner[0].w;
    if (w == 0.0f) return 0.0f;
    __global const float4 *t = corner + 3;
    *tangent = (1.0f - b12.x - b12.y) * t[0].xyz + b12.x * t[1].xyz + b12.y * t[2].xyz;
    return w;
}

#if SCENE_HAS_INSTANCES
/* file_tangent of an instanced object's triangle, in world space: the tangent moves with the surface (the
 * instance's linear part) and a mirroring instance reverses the handedness. */
inline float instance_file_tangent(const Scene *scene, __global const Instance *instance, int normals, float2 b12,
                                   float3 *tangent)
{
    float3 t;
    float w = file_tangent(scene, normals, b12, &t);
    if (w == 0.0f) return 0.0f;
    *tangent = affine_vector(instance->to_world, t);
    __global const float4 *m = instance->to_world;
    float det = dot(m[0].xyz, cross(m[1].xyz, m[2].xyz));
    return det < 0.0f ? -w : w;
}
#endif
#endif

#endif
