/* Linear retarder (a wave plate): a sheet that passes light straight through, transmittance T(λ), delaying the
 * field across its fast axis by the retardance δ (radians; π/2 a quarter-wave plate, π a half-wave plate), the
 * fast axis at `angle` radians from the surface's dp/du (Material.tangent_frame) toward the bitangent, as Mitsuba
 * 3's `retarder` measures its `theta`. Unpolarised light keeps T of its power, which is all the unpolarised
 * transport sees: f = T δ(ωi + ωo) / |cos θi|, a delta lobe. With SCENE_POLARIZED the path applies its Mueller
 * matrix (E. Collett, "Field Guide to Polarization", linear retarder; mueller.cl, material_polarized.cl).
 * Row: ior_coefficients_b.x the fast axis' angle, .y the retardance (radians); transmittance_offset T(λ)
 * (MATERIAL_NO_SPECTRUM: 1). */
#ifndef SPECTRACE_BSDF_RETARDER_CL
#define SPECTRACE_BSDF_RETARDER_CL

#include "bsdf_sample.cl"
#include "frame.cl"
#include "spectrum.cl"
#include "texture.cl"

typedef struct {
    float4 transmittance;
    float angle;       /* of the fast axis from the frame's tangent, radians */
    float retardance;  /* radians */
} RetarderParams;

inline int retarder_flags(__global const Material *m)
{
    return BSDF_DELTA | BSDF_TRANSMISSION;
}

inline RetarderParams retarder_params(__global const Material *m, const SurfaceContext *sc,
                                      const SampledWavelengths *w)
{
    RetarderParams p;
    p.transmittance = m->transmittance_offset == MATERIAL_NO_SPECTRUM
                          ? (float4)(1.0f)
                          : spectrum_at(sc->buffers.spectra, m->transmittance_offset, w);
    p.angle = m->ior_coefficients_b.x;
    p.retardance = m->ior_coefficients_b.y;
    return p;
}

inline float4 retarder_eval(const RetarderParams *p, float3 wo, float3 wi)
{
    return (float4)(0.0f);
}

inline float retarder_pdf(const RetarderParams *p, float3 wo, float3 wi)
{
    return 0.0f;
}

inline int retarder_sample(const RetarderParams *p, float3 wo, float uc, float2 u, BSDFSample *s)
{
    return delta_sample(-wo, p->transmittance, 1.0f, s);
}

#endif
