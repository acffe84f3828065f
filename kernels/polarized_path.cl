/* What a camera path carries for polarised transport (SCENE_POLARIZED), as Mitsuba 3's polarised variants trace it
 * from the sensor: the Mueller matrix of the path so far, mapping the Stokes vector of light arriving along the
 * current ray to the one the camera receives, with the basis that light's Stokes vector is expressed in (mueller.cl
 * conventions); each scattering event multiplies its Mueller matrix in on the right, after a rotation from the
 * event's basis into the path's (Mitsuba 3, "Polarization" developer guide). What a path gathers of unpolarised light
 * is the matrix's first column times the scalar radiance it gathers anyway; an area light may emit a given Stokes
 * state, which the path meets through the whole matrix (polarized_gather_emitter).
 *
 * The path's scalar throughput stays the matrix's (0, 0) entry, the response to unpolarised light (Mitsuba 3's
 * Russian roulette and every unpolarised quantity read the same entry): `p` holds the matrix divided by it, so
 * that everything that scales the throughput (media, Russian roulette, dispersion) needs no hook here. The S0 the
 * path gathers is its radiance as without polarisation; S1..S3 are kept here, in the camera's basis: x = d × up
 * for a camera ray along d (the image's right), y = k × x (the image's up; k = −d, the way light travels).
 *
 * Camera polariser (RenderParams.lens.w = 1): a linear polariser in front of the lens, its axis lens.z radians from
 * the camera's right toward its up; the film records ½ (S0 + cos 2φ S1 + sin 2φ S2) (Collett, linear polariser). */
#ifndef SPECTRACE_POLARIZED_PATH_CL
#define SPECTRACE_POLARIZED_PATH_CL

#include "material_polarized.cl"
#include "microfacet_polarized.cl"

typedef struct {
    Mueller p;        /* the path's Mueller matrix divided by its (0, 0) entry, the scalar throughput */
    float4 stokes[3]; /* S1, S2, S3 gathered (per wavelength, radiance units), camera basis */
    float3 basis;     /* x axis of the basis of light arriving along the path's ray */
} PolarizedPath;

inline PolarizedPath polarized_start(float3 d)
{
    PolarizedPath q;
    q.p = mueller_identity();
    for (int i = 0; i < 3; ++i) q.stokes[i] = (float4)(0.0f);
    q.basis = stokes_basis_from(-d, (float3)(1.0f, 0.0f, 0.0f));
    return q;
}

/* A camera ray along d: the camera's basis, x = d × up normalised (the image's right on the view axis), as Mitsuba 3
 * turns a sensor's Stokes vectors to its up vector, so that every pixel's basis is the same function of its ray. */
inline void polarized_camera(PolarizedPath *q, __global const RenderParams *params, float3 d)
{
    q->basis = stokes_basis_from(-d, cross(d, params->camera_up.xyz));
}

/* The path gathers `radiance` of unpolarised light (its throughput already applied). */
inline void polarized_gather(PolarizedPath *q, float4 radiance)
{
    for (int i = 0; i < 3; ++i) q->stokes[i] += q->p.m[4 * (i + 1)] * radiance;
}

/* The path meets an area light whose light leaves along wo, the light's u tangent dpdu there: `contribution` is
 * what it gathers of unpolarised light of the same radiance (throughput applied). A polarised light (Light.direction.w
 * > 0) emits S0 (1, s1, s2, s3) with (s1, s2, s3) = Light.direction.xyz in the basis x = dpdu's part normal to wo (a
 * picture's right), y = wo × x (its up, seen from the front). Gathers S1..S3 and returns what scales the radiance's
 * S0: the path's first row times the normalised Stokes vector, exactly 1 for an unpolarised light. */
inline float4 polarized_gather_emitter(PolarizedPath *q, __global const Light *light, float3 dpdu, float3 wo,
                                       float4 contribution)
{
    if (!(light->direction.w > 0.0f)) {
        polarized_gather(q, contribution);
        return (float4)(1.0f);
    }
    float2 turn = stokes_basis_turn(wo, stokes_basis_from(wo, dpdu), q->basis);
    float3 e = light->direction.xyz;
    float3 s = (float3)(turn.x * e.x + turn.y * e.y, -turn.y * e.x + turn.x * e.y, e.z);
    float4 row[4];
    for (int i = 0; i < 4; ++i) row[i] = q->p.m[4 * i] + s.x * q->p.m[4 * i + 1] + s.y * q->p.m[4 * i + 2] + s.z * q->p.m[4 * i + 3];
    for (int i = 0; i < 3; ++i) q->stokes[i] += row[i + 1] * contribution;
    return row[0];
}

/* Next-event estimation at a vertex seen from wo whose event toward the sampled light polarises: the Stokes vector
 * `out` leaving the event toward wo (in the basis x, per unit of the light's S0: the event's matrix divided by its
 * (0, 0) entry times the light's normalised Stokes vector) turns into the path's basis and meets the path's matrix.
 * Gathers S1..S3 of `contribution` (the unpolarised estimate, throughput applied) and returns what scales its S0,
 * the path's first row times that Stokes vector. */
inline float4 polarized_gather_event(PolarizedPath *q, const float4 *out, float3 x, float3 wo, float4 contribution)
{
    float2 turn = stokes_basis_turn(wo, x, q->basis);
    float4 s1 = turn.x * out[1] + turn.y * out[2], s2 = -turn.y * out[1] + turn.x * out[2];
    float4 row[4];
    for (int i = 0; i < 4; ++i)
        row[i] = q->p.m[4 * i] * out[0] + s1 * q->p.m[4 * i + 1] + s2 * q->p.m[4 * i + 2] + out[3] * q->p.m[4 * i + 3];
    for (int i = 0; i < 3; ++i) q->stokes[i] += row[i + 1] * contribution;
    return row[0];
}

/* The normalised Stokes vector (1, s1, s2, s3) of an area light's light (polarized_gather_emitter's convention:
 * Light.direction.xyz in the basis of the surface's dp/du made normal to the way it leaves) arriving along −wi,
 * re-expressed in the basis with x axis x (normal to wi). */
inline void polarized_light_stokes(__global const Light *light, float3 dpdu, float3 wi, float3 x, float4 *stokes)
{
    float3 leaving = -wi;
    float2 turn = stokes_basis_turn(leaving, stokes_basis_from(leaving, dpdu), x);
    float3 e = light->direction.xyz;
    stokes[0] = (float4)(1.0f);
    stokes[1] = (float4)(turn.x * e.x + turn.y * e.y);
    stokes[2] = (float4)(-turn.y * e.x + turn.x * e.y);
    stokes[3] = (float4)(e.z);
}

/* A depolarising event; the path goes on along `d`. */
inline void polarized_depolarize(PolarizedPath *q, float3 d)
{
    mueller_then_depolarize(&q->p);
    q->basis = stokes_basis_from(-d, q->basis);
}

/* The path scatters at a surface by bs (material m, shading normal n, seen from wo): the event's Mueller matrix
 * joins the path's, and *throughput takes the change of the (0, 0) entry (0 where crossed polarisers pass
 * nothing); the BSDF's sample weight is the caller's to apply, as without polarisation. */
inline void polarized_scatter(PolarizedPath *q, float4 *throughput, __global const Material *m,
                              const SurfaceContext *sc, const SampledWavelengths *w, float3 n, float3 wo,
                              const BSDFSample *bs)
{
    float3 x_out, x_in;
    if (bs->is_delta) {
        AlignedElement e;
        if (!material_polarization(m, sc, w, n, wo, bs, &e, &x_out, &x_in)) {
            polarized_depolarize(q, bs->wi);
            return;
        }
        mueller_then_rotate(&q->p, stokes_basis_turn(wo, x_out, q->basis));
        mueller_then_element(&q->p, &e);
    } else {
        Mueller e;
        if (!glossy_polarization(m, sc, w, n, wo, bs->wi, &e, &x_out)) {
            polarized_depolarize(q, bs->wi);
            return;
        }
        mueller_then_rotate(&q->p, stokes_basis_turn(wo, x_out, q->basis));
        mueller_then_matrix(&q->p, &e);
        x_in = x_out;
    }
    float4 f = fmax(q->p.m[0], 0.0f);
    *throughput *= f;
    mueller_scale(&q->p, f);
    q->basis = x_in;
}

/* What the film records of a finished sample whose S0 is `radiance` (pixel filter weight applied; S1..S3 get
 * `weight`): through the camera polariser when there is one. */
inline float4 polarized_film_radiance(const PolarizedPath *q, __global const RenderParams *params, float4 radiance,
                                      float weight)
{
    if (!(params->lens.w > 0.0f)) return radiance;
    float c = cos(2.0f * params->lens.z), s = sin(2.0f * params->lens.z);
    return 0.5f * (radiance + weight * (c * q->stokes[0] + s * q->stokes[1]));
}

#if FILM_STOKES
/* Adds the sample's Stokes images' film XYZ (S0 `radiance`, S1..S3 the path's times `weight`) to the AOV sums
 * from AOV_STOKES on (aov.cl); a non-finite one adds nothing. */
inline void add_stokes_sample(float4 *sums, const PolarizedPath *q, float4 radiance, float weight,
                              __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 xyz[4];
    xyz[0] = spectrum_to_xyz_estimate(radiance, cmf, w);
    for (int i = 0; i < 3; ++i) xyz[i + 1] = spectrum_to_xyz_estimate(weight * q->stokes[i], cmf, w);
    for (int i = 0; i < 4; ++i)
        if (!(isfinite(xyz[i].x) && isfinite(xyz[i].y) && isfinite(xyz[i].z))) return;
    for (int i = 0; i < 4; ++i) sums[AOV_STOKES + i] += xyz[i];
}
#endif

#endif
