/* The direction a texture gives an anisotropic lobe, per point: glTF 2.0's KHR_materials_anisotropy, whose
 * anisotropyTexture holds in red and green the direction d = 2 (r, g) − 1 in the tangent frame (x along the
 * tangent, y along the signed bitangent), turned by anisotropyRotation: rotations about one axis add, so the frame
 * material_frame has already turned by the material's rotation is turned further by d's angle,
 *   x' = d̂.x x + d̂.y w y,   y' = n × x',
 * w the tangent's handedness (a file tangent's w, 1 otherwise), as material_frame's own rotation turns toward the
 * signed bitangent. A texel with d = 0 leaves the frame as it is. Units: none (directions). Contract: the frame is
 * orthonormal with y = n × x; only principled rows hold a direction texture, in Material.k_offset (host:
 * spectrace.materials.principled, anisotropic_direction). */
#ifndef SPECTRACE_ANISOTROPY_DIRECTION_CL
#define SPECTRACE_ANISOTROPY_DIRECTION_CL

#include "frame.cl"
#include "texture.cl"

#if SCENE_HAS_DIRECTION_TEXTURES
inline void turn_by_direction_texture(__global const Material *m, const SurfaceContext *sc, ShadingFrame *frame)
{
    if (m->type != MATERIAL_PRINCIPLED || m->k_offset == NO_TEXTURE) return;
    float2 d = 2.0f * texture_numbers(&sc->buffers, m->k_offset, sc->uv, sc->footprint).xy - 1.0f;
    float length_d = length(d);
    if (!(length_d > 0.0f)) return;
    d /= length_d;
    float w = 1.0f;
#if SCENE_HAS_FILE_TANGENTS
    w = sc->tangent_w;
#endif
    float3 x = d.x * frame->tangent + (d.y * w) * frame->bitangent;
    frame->bitangent = cross(frame->normal, x);
    frame->tangent = x;
}
#endif

#endif
