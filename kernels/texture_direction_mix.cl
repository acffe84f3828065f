/* pbrt-v4's `directionmix` texture (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., sec. 10.3.3,
 * DirectionMixTexture): two textures blended by how the surface faces a direction,
 *     value = a · tex1 + (1 − a) · tex2,  a = |n · dir|,
 * so tex1 shows where the surface faces along ±dir and tex2 where it lies edge-on to it. Dimensionless weights; the
 * result has the units of its operands.
 *
 * Contract (host: host/spectrace/textures/directionmix.py): a TEXTURE_DIRECTIONMIX row's side_spectrum /
 * side_texture are tex1 and tex2 (spectra or non-composite textures, as a mix's), and uv_transform.xyz the unit
 * world-space dir. n is the lookup's TextureBuffers.normal: the vertex's unit geometric normal (SURFACE_AT_HIT), as
 * pbrt-v4 evaluates textures with its interaction's n (TextureEvalContext), not the shading normal that vertex
 * normals interpolate or a normal or bump map turns; 0 where a lookup has no surface at hand (then a = 0: tex2). */
#ifndef SPECTRACE_TEXTURE_DIRECTION_MIX_CL
#define SPECTRACE_TEXTURE_DIRECTION_MIX_CL

inline float4 direction_mix_spectrum(const TextureBuffers *b, __global const Texture *t, float2 uv, float3 p,
                                     float footprint, const SampledWavelengths *w)
{
    float a = fmin(fabs(dot(b->normal, t->uv_transform.xyz)), 1.0f);
    float4 first = texture_side(b, t, 0, uv, p, footprint, w);
    float4 second = texture_side(b, t, 1, uv, p, footprint, w);
    return a * first + (1.0f - a) * second;
}

#endif
