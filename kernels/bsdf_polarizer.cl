/* Linear polariser: a sheet that passes light straight through, transmittance k1 = T(λ) for the field along its
 * axis and k2 = e T(λ) across it (e its extinction, 0 for an ideal polariser), the axis at `angle` radians from
 * the surface's dp/du (the material's frame follows dp/du: Material.tangent_frame) toward the bitangent.
 * Seen obliquely, a dichroic sheet absorbs the field along its absorbing axis a (in the sheet, normal to its
 * transmission axis) and passes the field normal to both a and the beam, along k × a (J. Korger et al., "The
 * polarization properties of a tilted polarizer", Opt. Express 21, 27032, 2013; docs/polarization.md), which is
 * not the projection of the transmission axis onto the beam's normal plane. Mitsuba 3's `polarizer` takes k × a
 * for its theta = 0 and turns that axis by theta about the beam (its "rotation around the optical axis"): the row's
 * about_ray flag selects that reading of `angle`, which the importer sets; both agree at normal incidence
 * (polarizer_axis, material_polarized.cl). Unpolarised light keeps (k1 + k2)/2 of its power, which is all
 * the unpolarised transport sees: f = (k1 + k2)/2 δ(ωi + ωo) / |cos θi|, a delta lobe. With SCENE_POLARIZED the
 * path applies its Mueller matrix (E. Collett, "Field Guide to Polarization", linear diattenuator; mueller.cl,
 * material_polarized.cl).
 * Row: ior_coefficients_b.x the axis angle (radians), .y the extinction e; transmittance_offset T(λ)
 * (MATERIAL_NO_SPECTRUM: 1). */
#ifndef SPECTRACE_BSDF_POLARIZER_CL
#define SPECTRACE_BSDF_POLARIZER_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 k1;    /* transmittance along the axis */
    float4 k2;    /* across it */
    float angle;  /* of the axis from the frame's tangent, radians */
    int about_ray; /* the angle turns the axis about the beam (Mitsuba 3), not in the sheet */
} PolarizerParams;

inline int polarizer_flags(__global const Material *m)
{
    return BSDF_DELTA | BSDF_TRANSMISSION;
}

inline PolarizerParams polarizer_params(__global const Material *m, const SurfaceContext *sc,
                                        const SampledWavelengths *w)
{
    PolarizerParams p;
    p.k1 = m->transmittance_offset == MATERIAL_NO_SPECTRUM ? (float4)(1.0f)
                                                           : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    p.k2 = m->ior_coefficients_b.y * p.k1;
    p.angle = m->ior_coefficients_b.x;
    p.about_ray = m->ior_coefficients_b.z != 0.0f;
    return p;
}

inline float4 polarizer_eval(const PolarizerParams *p, float3 wo, float3 wi)
{
    return (float4)(0.0f);
}

inline float polarizer_pdf(const PolarizerParams *p, float3 wo, float3 wi)
{
    return 0.0f;
}

inline int polarizer_sample(const PolarizerParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    return delta_sample(-wo, 0.5f * (p->k1 + p->k2), 1.0f, s);
}

#endif
