/* Mesh attributes as textures: Mitsuba 3's `mesh_attribute` (its Mesh::eval_attribute): a value stored per vertex,
 * blended across the hit triangle by the hit's barycentrics, or per face, constant across it; times the texture's
 * scale. A colour (three channels) is stored as each vertex's sigmoid coefficients (Jakob & Hanika 2019,
 * rgb_spectrum.cl) and the corners' spectra are blended, as texture.cl blends a bitmap's texels, so a blend of
 * reflectances in [0, 1] stays in [0, 1]; one channel is a number, the same at every wavelength.
 *
 * Contract (host: host/spectrace/engine/mesh_attribute_rows.py): a TEXTURE_MESH_ATTRIBUTE row's data_offset is where
 * one int per triangle slot (TriangleInfo's numbering, as float bits in the texel buffer) gives the float offset of
 * that triangle's record in the texel buffer, or -1 where its mesh does not wear the texture (the value is then 0).
 * A record holds `width` corners (3: a vertex attribute, at the triangle's corners v0, v1, v2; 1: a face attribute)
 * of `channels` floats each: sigmoid coefficients for λ in nm (TEXEL_SIGMOID) or one number (TEXEL_SCALAR).
 * `factor` is the scale. The hit (its slot and the barycentrics of v1, v2) is the lookup's TextureBuffers' own. */
#ifndef SPECTRACE_TEXTURE_MESH_ATTRIBUTE_CL
#define SPECTRACE_TEXTURE_MESH_ATTRIBUTE_CL

inline float4 mesh_attribute_corner(__global const Texture *t, __global const float *values,
                                    const SampledWavelengths *w)
{
    if (t->texel_format == TEXEL_SIGMOID) return sigmoid_polynomial(vload3(0, values), w->lambda);
    return (float4)(values[0]);
}

inline float4 mesh_attribute_spectrum(const TextureBuffers *b, __global const Texture *t, const SampledWavelengths *w)
{
    if (b->triangle < 0) return (float4)(0.0f);
    int record = as_int(b->texels[t->data_offset + b->triangle]);
    if (record < 0) return (float4)(0.0f);
    __global const float *corner = b->texels + record;
    if (t->width == 1) return t->factor * mesh_attribute_corner(t, corner, w);
    float4 c0 = mesh_attribute_corner(t, corner, w);
    float4 c1 = mesh_attribute_corner(t, corner + t->channels, w);
    float4 c2 = mesh_attribute_corner(t, corner + 2 * t->channels, w);
    float4 value = (1.0f - b->b12.x - b->b12.y) * c0 + b->b12.x * c1 + b->b12.y * c2;
    return t->factor * value;
}

#endif
