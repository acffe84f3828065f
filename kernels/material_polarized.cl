/* The Mueller matrix of a sampled delta event, for polarised transport (SCENE_POLARIZED): the materials whose events
 * polarise (smooth dielectrics and conductors by the Fresnel equations, a smooth plastic's coat, the mirror as a
 * perfect conductor, polarisers, retarders) give theirs as an aligned element (mueller.cl) with the bases of the two beams; every
 * other event depolarises, as Mitsuba 3's BSDFs without a polarised model do (their value becomes the depolariser
 * diag(f, 0, 0, 0)). The element is returned divided by its (0, 0) entry, the event's response to unpolarised
 * light, which the BSDF's own sample weight already carries (its sampling is the unpolarised one, as in Mitsuba).
 * Non-delta events are microfacet_polarized.cl's (rough conductors and dielectrics, pplastic); every other one
 * depolarises, a rough plastic's coat included (as Mitsuba 3's roughplastic). */
#ifndef SPECTRACE_MATERIAL_POLARIZED_CL
#define SPECTRACE_MATERIAL_POLARIZED_CL

#include "material.cl"
#include "fresnel_polarized.cl"

/* (1, b, c, d) of every lane as one aligned element. */
inline AlignedElement aligned_uniform(float4 shape)
{
    return aligned_from_shapes(shape, shape, shape, shape);
}

/* An aligned element divided by its (0, 0) entry (lanes where that is 0 keep the depolariser). */
inline AlignedElement aligned_normalised(AlignedElement e)
{
    float4 inverse = select((float4)(0.0f), 1.0f / e.a, e.a > (float4)(0.0f));
    e.b *= inverse;
    e.c *= inverse;
    e.d *= inverse;
    e.a = (float4)(1.0f);
    return e;
}

/* The unit normal of the plane of incidence of a reflection or refraction at a surface of normal n seen from wo
 * (the s direction of both beams), or the frame's tangent at normal incidence, where every direction is one. */
inline float3 plane_of_incidence_normal(const ShadingFrame *frame, float3 wo)
{
    float3 s = cross(frame->normal, wo);
    float l = length(s);
    return l > 1.0e-6f ? s / l : frame->tangent;
}

#ifdef MATERIAL_POLARIZER
/* The transmission axis, a unit vector normal to the beam along k (either sense), of the sheet in `frame`. k is
 * turned to the frame's normal side so that the angle's sense is the sheet's from either side; at normal incidence
 * both readings give cos(angle) tangent + sin(angle) bitangent. */
inline float3 polarizer_axis(const PolarizerParams *p, const ShadingFrame *frame, float3 k)
{
    float3 kn = dot(k, frame->normal) < 0.0f ? -k : k;
    float c = cos(p->angle), s = sin(p->angle);
    if (p->about_ray) {
        float3 a0 = stokes_basis_from(kn, frame->bitangent);
        return c * cross(a0, kn) + s * a0;
    }
    float3 a = stokes_basis_from(kn, c * frame->bitangent - s * frame->tangent);
    return cross(a, kn);
}
#endif

/* The event of `bs` (drawn at a surface of shading normal n, seen from wo) as an aligned element in the bases with x
 * axes *x_out (the beam leaving along wo) and *x_in (the beam arriving along −bs->wi), world space. Returns 0 when
 * the event depolarises. */
inline int material_polarization(__global const Material *m, const SurfaceContext *sc, const SampledWavelengths *w,
                                 float3 n, float3 wo, const BSDFSample *bs, AlignedElement *e, float3 *x_out,
                                 float3 *x_in)
{
    if (!bs->is_delta) return 0;
    ShadingFrame frame = material_frame(m, sc, n, wo);
    float3 lo = to_local(&frame, wo), li = to_local(&frame, bs->wi);
#ifdef MATERIAL_POLARIZER
    if (MATERIAL_IS(m, MATERIAL_POLARIZER)) {
        PolarizerParams p = polarizer_params(m, sc, w);
        *x_out = *x_in = polarizer_axis(&p, &frame, wo);
        *e = aligned_normalised(linear_polarizer_element(p.k1, p.k2));
        return 1;
    }
#endif
#ifdef MATERIAL_RETARDER
    if (MATERIAL_IS(m, MATERIAL_RETARDER)) {
        RetarderParams p = retarder_params(m, sc, w);
        float3 axis = cos(p.angle) * frame.tangent + sin(p.angle) * frame.bitangent;
        *x_out = *x_in = stokes_basis_from(wo, axis);
        *e = aligned_normalised(linear_retarder_element(p.retardance, p.transmittance));
        return 1;
    }
#endif
    *x_out = *x_in = plane_of_incidence_normal(&frame, wo);
    if (MATERIAL_IS(m, MATERIAL_DIELECTRIC)) {
        DielectricParams p = dielectric_params(m, sc, w);
        /* The light comes from wi's side: its index ratio and cosine there (the normalised shape of a refraction
         * is the same both ways). */
        float eta = dielectric_eta_from(li.z, p.eta);
        float4 shape = lo.z * li.z > 0.0f ? fresnel_reflection_shape(fabs(li.z), (float2)(eta, 0.0f))
                                          : fresnel_transmission_shape(fabs(li.z), eta);
        *e = aligned_uniform(shape);
        return 1;
    }
    if (MATERIAL_IS(m, MATERIAL_CONDUCTOR)) {
        ConductorParams p = conductor_params(m, sc, w);
        float c = fabs(lo.z);
        *e = aligned_from_shapes(fresnel_reflection_shape(c, (float2)(p.eta.x, p.k.x)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.y, p.k.y)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.z, p.k.z)),
                                 fresnel_reflection_shape(c, (float2)(p.eta.w, p.k.w)));
        return 1;
    }
    if (MATERIAL_IS(m, MATERIAL_PLASTIC)) {
        /* The smooth coat's reflection (the only delta event); its base's diffuse light depolarises, as in
         * Mitsuba 3's polarised plastic. */
        *e = aligned_uniform(fresnel_reflection_shape(fabs(lo.z), (float2)(m->ior, 0.0f)));
        return 1;
    }
    if (MATERIAL_IS(m, MATERIAL_MIRROR)) {
        /* A perfect conductor: r_s = −1, r_p = 1. */
        *e = aligned_uniform((float4)(1.0f, 0.0f, -1.0f, 0.0f));
        return 1;
    }
    return 0;
}

#endif
