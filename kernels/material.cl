/* Material dispatch: the integrators see every BSDF through the functions below, in world space. Each BSDF lives
 * in its own bsdf_<name>.cl and works in the local shading frame (frame.cl) with the same five functions:
 * <name>_flags (what its lobes are, bsdf_sample.cl), <name>_params (its inputs at the path's wavelengths, looked
 * up in the spectrum table or, for textured parameters, the textures at the surface point: texture.cl's
 * SurfaceContext),
 * <name>_eval (f·|cos θi|), <name>_pdf and <name>_sample. The list of BSDFs is not kept here: the host writes
 * material_list.h from its registry (spectrace.materials.MATERIALS) for every build it hands them to
 * (spectrace.plugins.generated_sources), with each bsdf_<name>.cl included and MATERIAL_LIST, and defines each
 * MATERIAL_<NAME> code. Adding a BSDF: that file and its host module
 * (docs/materials.md, "Adding a BSDF"); nothing here changes. docs/materials.md describes each model. */
#ifndef SPECTRACE_MATERIAL_CL
#define SPECTRACE_MATERIAL_CL

#include "types.h"
#include "frame.cl"
#include "spectrum.cl"
#include "texture.cl"
#include "bsdf_sample.cl"
#ifndef MATERIAL_TYPE_COUNT
#error "built without the materials' generated sources (spectrace.plugins.generated_sources)"
#endif
#include "material_list.h"
#include "anisotropy_direction.cl"

/* MATERIAL_LIST(X) (material_list.h) holds X(code, name, Params) for every BSDF: its Material.type code, the prefix
 * of its functions and its params struct. Each dispatch below is this list expanded, one test per type; a type the
 * scene lacks tests as a constant 0 (MATERIAL_IS, scene_features.h), so its code is not compiled in, and a scene of
 * one type dispatches without a test. */
#define MATERIAL_FLAGS_CASE(type, name, Params) \
    if (MATERIAL_IS(m, type)) return name##_flags(m);
#define MATERIAL_EVAL_CASE(type, name, Params)          \
    if (MATERIAL_IS(m, type)) {                         \
        Params p = name##_params(m, sc, w);            \
        return name##_eval(&p, wo, wi);                 \
    }
#define MATERIAL_PDF_CASE(type, name, Params)           \
    if (MATERIAL_IS(m, type)) {                         \
        Params p = name##_params(m, sc, w);            \
        return name##_pdf(&p, wo, wi);                  \
    }
#define MATERIAL_SAMPLE_CASE(type, name, Params)        \
    if (MATERIAL_IS(m, type)) {                         \
        Params p = name##_params(m, sc, w);            \
        return name##_sample(&p, wo, uc, u, s);         \
    }

/* BSDF_* flags of material m (0 for a type code no BSDF has). */
inline int material_flags(__global const Material *m)
{
    MATERIAL_LIST(MATERIAL_FLAGS_CASE)
    return 0;
}

/* n faces wo for two-sided reflectors. */
inline float3 facing(float3 n, float3 wo)
{
    return dot(n, wo) >= 0.0f ? n : -n;
}

/* The local frame of material m at a surface of (shading) normal n seen from wo. A reflector's frame's normal is
 * turned toward wo (local wo.z ≥ 0): it reflects on both faces, unless one-sided (material_back_is_black). A
 * transmitting one keeps n on the winding's front: which side is the interior (so the sign of the refraction) comes from the winding, so closed meshes need
 * outward normals. A material with Material.tangent_frame (an anisotropic lobe) takes its x axis along the
 * surface's dp/du (sc->dpdu), Mitsuba 3's convention, so the highlight follows the texture coordinates; every other
 * frame's tangent is arbitrary, the BSDF being isotropic about the normal. Every integrator's eval, pdf and
 * sampling come through here, so all see the same frame. */
inline ShadingFrame material_frame(__global const Material *m, const SurfaceContext *sc, float3 n, float3 wo)
{
    float3 normal = (material_flags(m) & BSDF_TRANSMISSION) ? n : facing(n, wo);
#if SCENE_HAS_TANGENT_FRAMES
    if (m->tangent_frame) {
        ShadingFrame frame = shading_frame_along(normal, sc->dpdu);
        /* Turned about the normal by the material's rotation: x = cos θ x + sin θ w y, y = n × x, w the
         * tangent's handedness (glTF's KHR_materials_anisotropy turns toward the signed bitangent). */
        if (m->tangent_rotation != 0.0f) {
            float c, s = sincos(m->tangent_rotation, &c);
#if SCENE_HAS_FILE_TANGENTS
            s *= sc->tangent_w;
#endif
            float3 x = c * frame.tangent + s * frame.bitangent;
            frame.bitangent = cross(frame.normal, x);
            frame.tangent = x;
        }
#if SCENE_HAS_DIRECTION_TEXTURES
        turn_by_direction_texture(m, sc, &frame);
#endif
        return frame;
    }
#endif
    return shading_frame(normal);
}

/* f(wo, wi)·|cos θi| per wavelength, local directions. */
inline float4 material_eval_local(__global const Material *m, const SurfaceContext *sc,
                                  const SampledWavelengths *w, float3 wo, float3 wi)
{
    MATERIAL_LIST(MATERIAL_EVAL_CASE)
    return (float4)(0.0f);
}

/* Solid-angle pdf with which material_sample_local proposes wi (delta lobes contribute nothing). */
inline float material_pdf_local(__global const Material *m, const SurfaceContext *sc,
                                const SampledWavelengths *w, float3 wo, float3 wi)
{
    MATERIAL_LIST(MATERIAL_PDF_CASE)
    return 0.0f;
}

/* uc picks a lobe, u samples within it. Returns 0 when no direction was produced. */
inline int material_sample_local(__global const Material *m, const SurfaceContext *sc,
                                 const SampledWavelengths *w, float3 wo, float uc, float2 u, BSDFSample *s)
{
    MATERIAL_LIST(MATERIAL_SAMPLE_CASE)
    return 0;
}

/* 0 when every lobe is a delta lobe: next-event estimation cannot contribute there and is skipped. */
inline int material_has_non_delta_lobe(__global const Material *m)
{
    return (material_flags(m) & BSDF_NON_DELTA) != 0;
}

/* 1 when the event steers each of the path's wavelengths its own way: the integrators then keep only the hero
 * wavelength (terminate_secondary, wavelengths.cl), before next-event estimation as well as before following the
 * sampled direction. Sensors put one wavelength in all four lanes: those go on together. */
inline int material_disperses(__global const Material *m, const SampledWavelengths *w)
{
    return (material_flags(m) & BSDF_DISPERSIVE) && wavelengths_differ(w);
}

/* 1 when m reflects on one face only and wo sees the other, where it is black (Mitsuba 3's BSDFs outside `twosided`
 * test cos θ > 0 in the shading frame alike). n is turned to the winding's front (shading_normal.cl), which the
 * host has made the side the vertex normals point to, so its side is the front. A reflecting BSDF passes light only between directions on wo's side, so testing wo alone blacks
 * the back whichever of the pair is wo: radiance (wo toward the viewer) and importance (wo toward the light) alike. */
inline int material_back_is_black(__global const Material *m, float3 n, float3 wo)
{
#if SCENE_HAS_ONE_SIDED
    return m->one_sided && !(material_flags(m) & BSDF_TRANSMISSION) && !(dot(n, wo) > 0.0f);
#else
    return 0;
#endif
}

/* tan² of the angle between unit vectors whose cosine is c (either side: the square of c). */
inline float tan2_from_cos(float c)
{
    float c2 = c * c;
    return fmax(1.0f - c2, 0.0f) / c2;
}

/* The factor a normal- or bump-mapped material m with Material.shadowing scales its BSDF's value by, for light
 * arriving along wl (the light's side, whichever way the transport runs) at a point whose shading normal n was
 * turned from sc->base_normal: Conty Estevez, Pearce & Kulla 2019 ("A Microfacet-Based Shadowing Function to Solve
 * the Bump Terminator Problem", Ray Tracing Gems ch. 12), G = 2 / (1 + √(1 + α² tan² θl)), α² = min(1, tan²θn / 8),
 * θn the turn and θl wl's angle from the base normal, as Mitsuba 3's normalmap and bumpmap apply it. 1 without
 * the term. Its value is a function of squares of cosines, so the side either normal faces does not matter. */
inline float material_shadowing(__global const Material *m, const SurfaceContext *sc, float3 n, float3 wl)
{
#if SCENE_HAS_SURFACE_NORMALS
    if (!m->shadowing || !(dot(sc->base_normal, sc->base_normal) > 0.0f)) return 1.0f;
    float alpha2 = fmin(0.125f * tan2_from_cos(dot(n, sc->base_normal)), 1.0f);
    float g = 2.0f / (1.0f + sqrt(1.0f + alpha2 * tan2_from_cos(dot(wl, sc->base_normal))));
    return isfinite(g) ? g : 0.0f;
#else
    return 1.0f;
#endif
}

/* wi is the light's side: radiance's own arguments, which every caller passes (an importance walk swaps them). */
inline float4 material_eval(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                            float3 n, float3 wo, float3 wi)
{
    if (material_back_is_black(m, n, wo)) return (float4)(0.0f);
    ShadingFrame frame = material_frame(m, sc, n, wo);
    return material_eval_local(m, sc, w, to_local(&frame, wo), to_local(&frame, wi)) *
           material_shadowing(m, sc, n, wi);
}

inline float material_pdf(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                          float3 n, float3 wo, float3 wi)
{
    if (material_back_is_black(m, n, wo)) return 0.0f;
    ShadingFrame frame = material_frame(m, sc, n, wo);
    return material_pdf_local(m, sc, w, to_local(&frame, wo), to_local(&frame, wi));
}

inline int material_sample(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                           float3 n, float3 wo, float uc, float2 u, BSDFSample *s)
{
    if (material_back_is_black(m, n, wo)) return 0;
    ShadingFrame frame = material_frame(m, sc, n, wo);
    if (!material_sample_local(m, sc, w, to_local(&frame, wo), uc, u, s)) return 0;
    s->wi = to_world(&frame, s->wi);
    /* The pdf stays the nested BSDF's, as in Mitsuba: the term is part of the value, so of the weight. */
    s->weight *= material_shadowing(m, sc, n, sc->adjoint ? wo : s->wi);
    return 1;
}

#endif
