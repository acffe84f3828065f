/* Texture mappings: the (u, v) a 2D texture (image, spectral, checkerboard, dots) is looked up at, from the surface
 * point rather than the surface's own texture coordinates, as pbrt-v4's TextureMapping2D (Pharr, Jakob & Humphreys,
 * 4th ed., 10.2 "Texture Coordinate Generation"): `spherical` (θ/π, φ/2π of the point's direction from the texture
 * space's origin, θ from +z, φ counter-clockwise from +x in [0, 2π)), `cylindrical` ((π + atan2(y, x))/2π, z) and
 * `planar` (p · v1, p · v2, the point taken as a vector from the texture space's origin).
 *
 * Contract: a mapped texture's row (Texture) has `mapping` = TEXTURE_MAPPING_* and `mapping_offset` pointing at 12
 * floats of the texel buffer (host/spectrace/textures/mapping.py writes them): the 3 × 4 matrix (rows) taking the
 * world-space point into texture space; for `planar` its first two rows are already v1ᵀ and v2ᵀ times that matrix,
 * so that s and t are the first two coordinates. The result is in spectrace's texture-coordinate convention, v down
 * the image: (s, 1 − t), as a mesh whose file stored (s, t) would carry, so that uv_scale and uv_offset and the
 * image's rows apply as they do to a mesh's coordinates. Unitless. */
#ifndef SPECTRACE_TEXTURE_MAPPING_CL
#define SPECTRACE_TEXTURE_MAPPING_CL

#define TEXTURE_MAPPING_UV 0
#define TEXTURE_MAPPING_SPHERICAL 1
#define TEXTURE_MAPPING_CYLINDRICAL 2
#define TEXTURE_MAPPING_PLANAR 3

/* The texture coordinates texture t is looked up at: the surface's uv, or those its mapping gives at the
 * world-space point p. */
inline float2 texture_uv(const TextureBuffers *b, __global const Texture *t, float2 uv, float3 p)
{
    if (t->mapping == TEXTURE_MAPPING_UV) return uv;
    __global const float *m = b->texels + t->mapping_offset;
    float4 ph = (float4)(p, 1.0f);
    float3 q = (float3)(dot(vload4(0, m), ph), dot(vload4(1, m), ph), dot(vload4(2, m), ph));
    float2 st;
    if (t->mapping == TEXTURE_MAPPING_PLANAR) {
        st = q.xy;
    } else if (t->mapping == TEXTURE_MAPPING_CYLINDRICAL) {
        st = (float2)((M_PI_F + atan2(q.y, q.x)) * (0.5f * M_1_PI_F), q.z);
    } else {
        float r = length(q);
        float cos_theta = r > 0.0f ? clamp(q.z / r, -1.0f, 1.0f) : 1.0f;
        float phi = atan2(q.y, q.x);
        if (phi < 0.0f) phi += 2.0f * M_PI_F;
        st = (float2)(acos(cos_theta) * M_1_PI_F, phi * (0.5f * M_1_PI_F));
    }
    return (float2)(st.x, 1.0f - st.y);
}

#endif
