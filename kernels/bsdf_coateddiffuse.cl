/* Coated diffuse: a dielectric coat over a Lambertian base with an absorbing or scattering slab between, pbrt-v4's
 * CoatedDiffuseBxDF (a LayeredBxDF, "Physically Based Rendering", 4th ed., sec. 14.3), evaluated, sampled and given
 * a density by layered.cl's stochastic random walk. Row: reflectance_offset (or reflectance_texture) the base's
 * albedo; `ior`, `alpha`, transmittance_offset and ior_coefficients_b.xy, ior_coefficients_c.xy as
 * bsdf_coatedconductor.cl's. A smooth coat has a delta lobe (its reflection); the base gives the rest a density. */
#ifndef SPECTRACE_BSDF_COATEDDIFFUSE_CL
#define SPECTRACE_BSDF_COATEDDIFFUSE_CL

#include "layered.cl"
#include "texture.cl"

typedef struct {
    LayeredParams layers;
} CoateddiffuseParams;

inline int coateddiffuse_flags(__global const Material *m)
{
    return layered_coat_flags(m) | BSDF_NON_DELTA;
}

inline CoateddiffuseParams coateddiffuse_params(__global const Material *m, const SurfaceContext *sc,
                                                const SampledWavelengths *w)
{
    CoateddiffuseParams c;
    c.layers = layered_row_params(m, sc, w);
    c.layers.base = LAYERED_DIFFUSE;
    c.layers.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    return c;
}

inline float4 coateddiffuse_eval(const CoateddiffuseParams *p, float3 wo, float3 wi)
{
    return layered_eval(&p->layers, wo, wi);
}

inline float coateddiffuse_pdf(const CoateddiffuseParams *p, float3 wo, float3 wi)
{
    return layered_pdf(&p->layers, wo, wi);
}

inline int coateddiffuse_sample(const CoateddiffuseParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    return layered_sample(&p->layers, wo, uc, u, s);
}

#endif
