/* Coated conductor: a dielectric coat over a metal with an absorbing or scattering slab between, pbrt-v4's
 * CoatedConductorBxDF (a LayeredBxDF, "Physically Based Rendering", 4th ed., sec. 14.3), evaluated, sampled and
 * given a density by layered.cl's stochastic random walk. Row: `ior` the coat's index (over the outside), `alpha`
 * its GGX α; eta_offset, k_offset the conductor's η and k relative to the outside, divided here by the coat's index
 * (pbrt-v4 divides alike); transmittance_offset the slab's albedo (MATERIAL_NO_SPECTRUM: 0, a slab that only
 * absorbs); ior_coefficients_b = (thickness, g, the conductor's α, ·), ior_coefficients_c = (max_depth, samples);
 * roughness_texture, reflectance_texture the coat's and the conductor's α textures (NO_TEXTURE: the numbers; a
 * texture leaves its largest α in the row, from which the flags come).
 * A smooth coat has a delta lobe (its reflection, and walks through smooth layers only); the rest has a density. */
#ifndef SPECTRACE_BSDF_COATEDCONDUCTOR_CL
#define SPECTRACE_BSDF_COATEDCONDUCTOR_CL

#include "layered.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    LayeredParams layers;
} CoatedconductorParams;

inline int coatedconductor_flags(__global const Material *m)
{
    int coat = layered_coat_flags(m);
    int scatters = m->transmittance_offset != MATERIAL_NO_SPECTRUM;
    if (coat == BSDF_DELTA && ggx_is_smooth(m->ior_coefficients_b.z) && !scatters) return BSDF_DELTA;
    return coat | BSDF_NON_DELTA;
}

inline CoatedconductorParams coatedconductor_params(__global const Material *m, const SurfaceContext *sc,
                                                    const SampledWavelengths *w)
{
    CoatedconductorParams c;
    c.layers = layered_row_params(m, sc, w);
    c.layers.base = LAYERED_CONDUCTOR;
    c.layers.base_alpha = surface_scalar(sc, m->reflectance_texture, m->ior_coefficients_b.z, w);
    c.layers.base_eta = spectrum_at(sc->buffers.spectra, m->eta_offset, w) / m->ior;
    c.layers.base_k = spectrum_at(sc->buffers.spectra, m->k_offset, w) / m->ior;
    return c;
}

inline float4 coatedconductor_eval(const CoatedconductorParams *p, float3 wo, float3 wi)
{
    return layered_eval(&p->layers, wo, wi);
}

inline float coatedconductor_pdf(const CoatedconductorParams *p, float3 wo, float3 wi)
{
    return layered_pdf(&p->layers, wo, wi);
}

inline int coatedconductor_sample(const CoatedconductorParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    return layered_sample(&p->layers, wo, uc, u, s);
}

#endif
