/* Perfect specular reflection with a reflectance spectrum R(λ): f = R δ(ωi − reflect(ωo)) / |cos θi|, a delta
 * lobe (eval and pdf are zero for every direction a sampler of another lobe or a light could propose). */
#ifndef SPECTRACE_BSDF_MIRROR_CL
#define SPECTRACE_BSDF_MIRROR_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 reflectance;
} MirrorParams;

inline int mirror_flags(__global const Material *m)
{
    return BSDF_DELTA;
}

inline MirrorParams mirror_params(__global const Material *m, const SurfaceContext *sc,
                                  const SampledWavelengths *w)
{
    MirrorParams p;
    p.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    return p;
}

inline float4 mirror_eval(const MirrorParams *p, float3 wo, float3 wi)
{
    return (float4)(0.0f);
}

inline float mirror_pdf(const MirrorParams *p, float3 wo, float3 wi)
{
    return 0.0f;
}

inline int mirror_sample(const MirrorParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    return delta_sample(reflect_local(wo), p->reflectance, 1.0f, s);
}

#endif
