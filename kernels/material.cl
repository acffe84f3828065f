/* Material dispatch: the integrators see every BSDF through the functions below, in world space. Each BSDF lives
 * in its own bsdf_<name>.cl and works in the local shading frame (frame.cl) with the same four functions:
 * <name>_params (its inputs at the path's wavelengths), <name>_eval (f·|cos θi|), <name>_pdf and <name>_sample.
 * Adding a BSDF: that file, its MATERIAL_* value in types.h, and one case in each switch here (plus
 * material_frame if it does not reflect on both faces). docs/materials.md describes each model. */
#ifndef SPECTRACE_MATERIAL_CL
#define SPECTRACE_MATERIAL_CL

#include "types.h"
#include "frame.cl"
#include "spectrum.cl"
#include "bsdf_sample.cl"
#include "bsdf_diffuse.cl"
#include "bsdf_mirror.cl"
#include "bsdf_conductor.cl"
#include "bsdf_plastic.cl"
#include "bsdf_retroreflector.cl"
#include "bsdf_dielectric.cl"

/* n faces wo for two-sided reflectors. */
inline float3 facing(float3 n, float3 wo)
{
    return dot(n, wo) >= 0.0f ? n : -n;
}

/* The local frame of material m at a surface of normal n seen from wo. Every reflector reflects on both faces,
 * so its frame's normal is turned toward wo (local wo.z ≥ 0). A dielectric keeps the geometric normal: which side
 * is the interior (so the sign of the refraction) comes from the winding, so closed meshes need outward normals. */
inline ShadingFrame material_frame(__global const Material *m, float3 n, float3 wo)
{
    return shading_frame(MATERIAL_IS(m, MATERIAL_DIELECTRIC) ? n : facing(n, wo));
}

/* f(wo, wi)·|cos θi| per wavelength, local directions. */
inline float4 material_eval_local(__global const Material *m, __global const float *spectra,
                                  const SampledWavelengths *w, float3 wo, float3 wi)
{
    switch (m->type) {
#if SCENE_USES_MATERIAL(MATERIAL_MIRROR)
    case MATERIAL_MIRROR: { MirrorParams p = mirror_params(m, spectra, w); return mirror_eval(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_CONDUCTOR)
    case MATERIAL_CONDUCTOR: { ConductorParams p = conductor_params(m, spectra, w); return conductor_eval(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_PLASTIC)
    case MATERIAL_PLASTIC: { PlasticParams p = plastic_params(m, spectra, w); return plastic_eval(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_RETROREFLECTOR)
    case MATERIAL_RETROREFLECTOR: {
        RetroreflectorParams p = retroreflector_params(m, spectra, w);
        return retroreflector_eval(&p, wo, wi);
    }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_DIELECTRIC)
    case MATERIAL_DIELECTRIC: { DielectricParams p = dielectric_params(m, spectra, w); return dielectric_eval(&p, wo, wi); }
#endif
    default: { DiffuseParams p = diffuse_params(m, spectra, w); return diffuse_eval(&p, wo, wi); }
    }
}

/* Solid-angle pdf with which material_sample_local proposes wi (delta lobes contribute nothing). */
inline float material_pdf_local(__global const Material *m, __global const float *spectra,
                                const SampledWavelengths *w, float3 wo, float3 wi)
{
    switch (m->type) {
#if SCENE_USES_MATERIAL(MATERIAL_MIRROR)
    case MATERIAL_MIRROR: { MirrorParams p = mirror_params(m, spectra, w); return mirror_pdf(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_CONDUCTOR)
    case MATERIAL_CONDUCTOR: { ConductorParams p = conductor_params(m, spectra, w); return conductor_pdf(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_PLASTIC)
    case MATERIAL_PLASTIC: { PlasticParams p = plastic_params(m, spectra, w); return plastic_pdf(&p, wo, wi); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_RETROREFLECTOR)
    case MATERIAL_RETROREFLECTOR: {
        RetroreflectorParams p = retroreflector_params(m, spectra, w);
        return retroreflector_pdf(&p, wo, wi);
    }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_DIELECTRIC)
    case MATERIAL_DIELECTRIC: { DielectricParams p = dielectric_params(m, spectra, w); return dielectric_pdf(&p, wo, wi); }
#endif
    default: { DiffuseParams p = diffuse_params(m, spectra, w); return diffuse_pdf(&p, wo, wi); }
    }
}

/* uc picks a lobe, u samples within it. Returns 0 when no direction was produced. */
inline int material_sample_local(__global const Material *m, __global const float *spectra,
                                 const SampledWavelengths *w, float3 wo, float uc, float2 u, BSDFSample *s)
{
    switch (m->type) {
#if SCENE_USES_MATERIAL(MATERIAL_MIRROR)
    case MATERIAL_MIRROR: { MirrorParams p = mirror_params(m, spectra, w); return mirror_sample(&p, wo, s); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_CONDUCTOR)
    case MATERIAL_CONDUCTOR: {
        ConductorParams p = conductor_params(m, spectra, w);
        return conductor_sample(&p, wo, u, s);
    }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_PLASTIC)
    case MATERIAL_PLASTIC: { PlasticParams p = plastic_params(m, spectra, w); return plastic_sample(&p, wo, uc, u, s); }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_RETROREFLECTOR)
    case MATERIAL_RETROREFLECTOR: {
        RetroreflectorParams p = retroreflector_params(m, spectra, w);
        return retroreflector_sample(&p, wo, u, s);
    }
#endif
#if SCENE_USES_MATERIAL(MATERIAL_DIELECTRIC)
    case MATERIAL_DIELECTRIC: {
        DielectricParams p = dielectric_params(m, spectra, w);
        if (!dielectric_sample(&p, wo, uc, u, s)) return 0;
        s->terminate_secondary = dielectric_disperses(m, w);
        return 1;
    }
#endif
    default: { DiffuseParams p = diffuse_params(m, spectra, w); return diffuse_sample(&p, wo, u, s); }
    }
}

/* 0 when every lobe is a delta lobe: next-event estimation cannot contribute there and is skipped. */
inline int material_has_non_delta_lobe(__global const Material *m)
{
    if (MATERIAL_IS(m, MATERIAL_MIRROR)) return 0;
    if (MATERIAL_IS(m, MATERIAL_CONDUCTOR) || MATERIAL_IS(m, MATERIAL_RETROREFLECTOR)
        || MATERIAL_IS(m, MATERIAL_DIELECTRIC)) {
        return !ggx_is_smooth(m->alpha);
    }
    return 1;
}

/* 1 when the event steers each wavelength its own way: the integrators then keep only the hero wavelength, before
 * next-event estimation as well as before following the sampled direction. */
inline int material_disperses(__global const Material *m, const SampledWavelengths *w)
{
    return MATERIAL_IS(m, MATERIAL_DIELECTRIC) && dielectric_disperses(m, w);
}

inline float4 material_eval(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                            float3 n, float3 wo, float3 wi)
{
    ShadingFrame frame = material_frame(m, n, wo);
    return material_eval_local(m, spectra, w, to_local(&frame, wo), to_local(&frame, wi));
}

inline float material_pdf(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                          float3 n, float3 wo, float3 wi)
{
    ShadingFrame frame = material_frame(m, n, wo);
    return material_pdf_local(m, spectra, w, to_local(&frame, wo), to_local(&frame, wi));
}

inline int material_sample(__global const Material *m, __global const float *spectra, const SampledWavelengths *w,
                           float3 n, float3 wo, float uc, float2 u, BSDFSample *s)
{
    ShadingFrame frame = material_frame(m, n, wo);
    if (!material_sample_local(m, spectra, w, to_local(&frame, wo), uc, u, s)) return 0;
    s->wi = to_world(&frame, s->wi);
    return 1;
}

#endif
