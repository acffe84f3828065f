/* The Mueller matrices of non-delta events, for polarised transport (SCENE_POLARIZED): a rough conductor's or rough
 * dielectric's microfacet event, and pplastic's two lobes.
 *
 * Sources: B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces" (EGSR 2007): a pair of
 * directions (ωo, ωi) is linked by the one microfacet normal h that reflects (h ∝ ωo + ωi) or refracts
 * (h ∝ ωo + e ωi, e the index ratio seen from ωo) one into the other, and the event is the smooth interface's on
 * that microfacet; Mitsuba 3's documentation, developer guide "Polarization" and its rough conductor: the Fresnel
 * term becomes the Fresnel Mueller matrix at h, in the plane of incidence spanned by the two directions and h;
 * S.-H. Baek et al., "Simultaneous Acquisition of Polarimetric SVBRDF and Normals" (SIGGRAPH Asia 2018), and
 * Mitsuba 3's pplastic for pplastic's two lobes.
 *
 * Contract: the unpolarised BSDF (bsdf_conductor.cl, bsdf_dielectric.cl) is unchanged and gives the event's (0, 0)
 * entry, D G F / (4 cos θo) and its refraction twin; D, G and the Jacobians are scalars common to every entry, so
 * the Mueller matrix is that entry times the smooth Fresnel shape (1, b, c, d) at h (fresnel_polarized.cl), in the
 * basis x = the unit normal of the plane of incidence, y = k × x, for both beams (mueller.cl's conventions). The
 * shape is a function of (ωo, ωi) alone, so BSDF sampling, next-event estimation and MIS hits on emitters all see
 * the same matrix. Units: dimensionless. */
#ifndef SPECTRACE_MICROFACET_POLARIZED_CL
#define SPECTRACE_MICROFACET_POLARIZED_CL

#include "material.cl"
#include "fresnel_polarized.cl"

/* The normal of the plane of incidence through h and wo (world space), or any direction normal to wo when h is
 * along wo (normal incidence on the microfacet, where every plane is one). */
inline float3 microfacet_plane_normal(float3 h, float3 wo, float3 fallback)
{
    float3 s = cross(h, wo);
    float l = length(s);
    return l > 1.0e-6f ? s / l : stokes_basis_from(wo, fallback);
}

/* The event of a rough conductor or dielectric m between wo (toward the viewer) and wi (toward the light), at a
 * surface of shading normal n, as an aligned element with the x axis *x of both beams. Returns 0 for any other
 * material, a smooth one (its delta events are material_polarization's) or a pair no microfacet links. */
inline int microfacet_polarization(__global const Material *m, const SurfaceContext *sc,
                                   const SampledWavelengths *w, float3 n, float3 wo, float3 wi, AlignedElement *e,
                                   float3 *x)
{
    int conductor = MATERIAL_IS(m, MATERIAL_CONDUCTOR);
    if (!conductor && !MATERIAL_IS(m, MATERIAL_DIELECTRIC)) return 0;
    ShadingFrame frame = material_frame(m, sc, n, wo);
    float3 lo = to_local(&frame, wo), li = to_local(&frame, wi);
    if (conductor) {
        ConductorParams p = conductor_params(m, sc, w);
        if (conductor_is_smooth(&p) || !(lo.z > 0.0f && li.z > 0.0f)) return 0;
        float3 h = normalize(lo + li);
        float c = fabs(dot(lo, h));
        *e = aligned_from_shapes(fresnel_reflection_shape(c, (float2)(p.eta.x, p.k.x)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.y, p.k.y)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.z, p.k.z)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.w, p.k.w)));
        *x = microfacet_plane_normal(to_world(&frame, h), wo, frame.tangent);
        return 1;
    }
    DielectricParams p = dielectric_params(m, sc, w);
    if (ggx_is_smooth(p.alpha) || lo.z == 0.0f || li.z == 0.0f) return 0;
    int reflection = lo.z * li.z > 0.0f;
    float3 h = reflection ? lo + li : lo + dielectric_eta_from(lo.z, p.eta) * li;
    float l = length(h);
    if (!(l > 0.0f)) return 0;
    h /= l;
    /* The light comes from wi's side: its index ratio and its cosine on the microfacet (the normalised shape of a
     * refraction is the same both ways). */
    float eta = dielectric_eta_from(li.z, p.eta);
    float c = fabs(dot(li, h));
    float4 shape = reflection ? fresnel_reflection_shape(c, (float2)(eta, 0.0f)) : fresnel_transmission_shape(c, eta);
    *e = aligned_from_shapes(shape, shape, shape, shape);
    *x = microfacet_plane_normal(to_world(&frame, h), wo, frame.tangent);
    return 1;
}

#ifdef MATERIAL_PPLASTIC
/* pplastic's event between wo and wi (bsdf_pplastic.cl): its specular lobe's value times the Fresnel reflection
 * matrix on the microfacet (in the basis x of h's plane, both beams), plus its diffuse lobe's value times the two
 * refractions' matrices about a depolarising base, T_out D T_in with D = diag(1, 0, 0, 0): the rank-one product of
 * the exit's first column (1, t_o, 0, 0) in the basis of wo's plane of incidence and the entry's first row
 * (1, t_i, 0, 0) in the basis of wi's (t the refraction's normalised shape, fresnel_transmission_shape, the same
 * both ways), each turned into x (Baek et al. 2018; Mitsuba 3's pplastic). Divided by its (0, 0) entry, the
 * unpolarised BSDF's value. */
inline int pplastic_polarization(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                                 float3 n, float3 wo, float3 wi, Mueller *e, float3 *x)
{
    ShadingFrame frame = material_frame(m, sc, n, wo);
    float3 lo = to_local(&frame, wo), li = to_local(&frame, wi);
    if (!(lo.z > 0.0f && li.z > 0.0f)) return 0;
    PplasticParams p = pplastic_params(m, sc, w);
    float4 specular = pplastic_specular_eval(&p, lo, li), diffuse = pplastic_diffuse_eval(&p, lo, li);
    float4 total = specular + diffuse;
    float4 inverse = select((float4)(0.0f), 1.0f / total, total > (float4)(0.0f));
    specular *= inverse;
    diffuse *= inverse;
    float3 h = normalize(lo + li);
    float4 shape = fresnel_reflection_shape(fabs(dot(lo, h)), (float2)(p.eta, 0.0f));
    *x = microfacet_plane_normal(to_world(&frame, h), wo, frame.tangent);
    /* The diffuse lobe's column, its exit's, re-expressed from wo's plane of incidence in x; its row, its entry's,
     * acting on a Stokes vector in wi's plane of incidence, re-expressed for one in x. */
    float t_out = fresnel_transmission_shape(lo.z, p.eta).y, t_in = fresnel_transmission_shape(li.z, p.eta).y;
    float2 turn_out = stokes_basis_turn(wo, microfacet_plane_normal(frame.normal, wo, frame.tangent), *x);
    float2 turn_in = stokes_basis_turn(-wi, *x, microfacet_plane_normal(frame.normal, wi, frame.tangent));
    float column[4] = {1.0f, turn_out.x * t_out, -turn_out.y * t_out, 0.0f};
    float row[4] = {1.0f, turn_in.x * t_in, turn_in.y * t_in, 0.0f};
    float aligned[16] = {1.0f, shape.y, 0.0f, 0.0f, shape.y, 1.0f, 0.0f, 0.0f,
                         0.0f, 0.0f, shape.z, shape.w, 0.0f, 0.0f, -shape.w, shape.z};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) e->m[4 * i + j] = specular * aligned[4 * i + j] + diffuse * (column[i] * row[j]);
    return any(total > (float4)(0.0f));
}
#endif

/* The event of a non-delta lobe between wo and wi, divided by its (0, 0) entry, in the basis with x axis *x for
 * both beams: rough conductors and dielectrics, pplastic. Returns 0 where it depolarises. */
inline int glossy_polarization(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                               float3 n, float3 wo, float3 wi, Mueller *e, float3 *x)
{
    AlignedElement a;
    if (microfacet_polarization(m, sc, w, n, wo, wi, &a, x)) {
        *e = mueller_from_aligned(&a);
        return 1;
    }
#ifdef MATERIAL_PPLASTIC
    if (MATERIAL_IS(m, MATERIAL_PPLASTIC)) return pplastic_polarization(m, sc, w, n, wo, wi, e, x);
#endif
    return 0;
}

#endif
