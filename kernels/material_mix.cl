/* The mix material (host: spectrace.materials.mix): two materials, of which the second shades a surface point with
 * probability `amount` and the first otherwise, so that what a pixel averages is (1 − amount) f₁ + amount f₂. As in
 * pbrt-v4's MixMaterial::ChooseMaterial (the choice of the second where a hash u ∈ [0, 1) of the point and the
 * direction it is seen from falls below the amount), the choice is made once where a path meets the surface,
 * before anything is evaluated there: the vertex then carries an ordinary material, and its light, its BSDF sample,
 * its MIS weights and the connections BDPT makes to it all see the same one. The hash is of the intersection, not
 * a sampler draw, so no sampler dimension moves (every other surface keeps its bits) and a render splits into passes
 * and tiles with the same bits. Mixes nest: the choice repeats, each level hashed with its own row, down to a BSDF.
 *
 * The mix's row (kernels/types.h): eta_offset and k_offset hold its two materials' row indices (first, second),
 * alpha the amount, roughness_texture a grey texture of it (NO_TEXTURE: alpha everywhere). */
#ifndef SPECTRACE_MATERIAL_MIX_CL
#define SPECTRACE_MATERIAL_MIX_CL

#include "scene.cl"
#include "hash.cl"

/* Mixes within mixes at most (spectrace.materials.mix.MAX_DEPTH, which the host enforces). */
#define MIX_MAX_DEPTH 8

/* A hash of the point, the direction and the mix's row, uniform in [0, 1) (24 bits). */
inline float mix_hash(float3 p, float3 wo, int row)
{
    uint h = hash_u32(as_uint(p.x) ^ (uint)row * 0x9e3779b9U);
    h = hash_u32(h ^ as_uint(p.y));
    h = hash_u32(h ^ as_uint(p.z));
    h = hash_u32(h ^ as_uint(wo.x));
    h = hash_u32(h ^ as_uint(wo.y));
    h = hash_u32(h ^ as_uint(wo.z));
    return (float)(h >> 8) * 0x1.0p-24f;
}

/* The row of the BSDF that shades point p seen from wo (uv, footprint: its texture lookup) where the surface's
 * material is row `material`: `material` itself unless it is a mix. Contract: a mix's materials are rows of the
 * scene; mixes nest at most MIX_MAX_DEPTH deep (a deeper one would leave a mix row, which shades black). */
inline int mix_resolve(const Scene *scene, int material, float3 p, float3 wo, float2 uv, float footprint, int triangle,
                       float2 b12)
{
    for (int depth = 0; depth < MIX_MAX_DEPTH && material != TRIANGLE_NO_MATERIAL; ++depth) {
        __global const Material *m = &scene->materials[material];
        if (m->type != MATERIAL_MIX) break;
        float amount = m->alpha;
        if (SCENE_HAS_TEXTURES && m->roughness_texture != NO_TEXTURE) {
            SurfaceContext sc = surface_context(scene, uv, footprint);
#if SCENE_HAS_MESH_ATTRIBUTES
            sc.buffers.triangle = triangle;
            sc.buffers.b12 = b12;
#endif
            amount = texture_numbers_at(&sc.buffers, m->roughness_texture, uv, p, footprint).x;
        }
        material = mix_hash(p, wo, material) < amount ? m->k_offset : m->eta_offset;
    }
    return material;
}

#endif
