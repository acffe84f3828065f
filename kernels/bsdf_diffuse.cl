/* Lambertian reflection f = R(λ)/π, in the local shading frame (material.cl flips the normal toward the
 * outgoing direction, so both faces reflect and meshes work whatever their winding; Mitsuba 3 needs a `twosided`
 * wrapper for this). Every bsdf_*.cl file has the same shape: flags (bsdf_sample.cl) and params from the
 * Material, then eval (f·cos θi), pdf (solid angle) and sample(params, wo, uc, u, sample), uc choosing a lobe and u
 * a direction in it, all on local directions with wo.z ≥ 0; material.cl's MATERIAL_LIST (generated
 * from the host's registry of materials) names each file's prefix. */
#ifndef SPECTRACE_BSDF_DIFFUSE_CL
#define SPECTRACE_BSDF_DIFFUSE_CL

#include "bsdf_sample.cl"
#include "sampling.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 reflectance;
} DiffuseParams;

inline int diffuse_flags(__global const Material *m)
{
    return BSDF_NON_DELTA;
}

inline DiffuseParams diffuse_params(__global const Material *m, const SurfaceContext *sc,
                                    const SampledWavelengths *w)
{
    DiffuseParams p;
    p.reflectance = surface_spectrum(sc, m->reflectance_texture, m->reflectance_offset, w);
    return p;
}

inline float4 diffuse_eval(const DiffuseParams *p, float3 wo, float3 wi)
{
    return wi.z > 0.0f ? p->reflectance * (INV_PI * wi.z) : (float4)(0.0f);
}

inline float diffuse_pdf(const DiffuseParams *p, float3 wo, float3 wi)
{
    return wi.z > 0.0f ? wi.z * INV_PI : 0.0f;
}

/* Cosine-weighted: the weight f cos / pdf of a Lambertian surface is its reflectance. */
inline int diffuse_sample(const DiffuseParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    s->wi = sample_cosine_hemisphere(u);
    s->pdf = s->wi.z * INV_PI;
    s->weight = p->reflectance;
    s->is_delta = 0;
    s->radiance_scale = 1.0f;
    return s->pdf > 0.0f;
}

#endif
