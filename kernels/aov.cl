/* Arbitrary output variables (AOVs) of the camera paths: what a path records about its first surface on the way,
 * and what a finished pixel sample adds to the AOV film. Renders that ask for no AOV build with FILM_AOVS 0 and
 * carry none of this code (kernels/render_pass.cl, path_tracer.cl and whitted.cl test the define).
 *
 * Definitions (Mitsuba 3's `aov` integrator for depth, position and normal; Open Image Denoise's documentation,
 * "Denoising filters: RT", for the albedo):
 *   depth    the camera ray's parameter t at its first surface, the distance from the ray's origin (the eye, or the
 *            near-clip plane when the camera has one) along the unit direction; material-less medium boundaries
 *            on the way add their t; 0 for a ray that meets nothing.
 *   position the world-space point of that surface (scene units); normal its world-space shading normal (not turned
 *            toward the viewer). A camera ray that scatters in a medium first records the scattering point and
 *            a zero normal.
 *   albedo   the directional albedo at the first surface with a non-delta lobe, reached through the path's own
 *            specular chain: the path's throughput there (without refraction's radiance compression) times the
 *            weight f·cos/pdf of the BSDF sample the path draws at that surface, an unbiased one-sample estimate
 *            of ∫ f cos dω (exact for a Lambertian surface, whose sample weight is its reflectance). A sample
 *            whose BSDF draw fails, a chain that leaves the scene, and a path that ends before such a surface
 *            record 0; a path that scatters in a medium before it records its throughput at the scattering point.
 *   emission the emission the camera ray itself meets (an area light's surface, or the environment where it meets
 *            nothing; through material-less boundaries, not through specular chains), two ways: the film's
 *            four-wavelength estimate of it, exactly the part of the sample's colour it makes, and its expected
 *            value over the wavelengths, the film XYZ of the emitted spectrum (the trapezoid rule on the grid,
 *            as the film's tables are integrated). The expected value carries none of the colour noise of four
 *            sampled wavelengths, which the directly seen emitters of a short render are full of; the denoiser
 *            takes the sampled part out of the image and adds back the expected part of a longer pass of camera
 *            rays alone (max_depth 1; spectrace.denoising), or the image's own, a conditional expectation
 *            (Rao-Blackwellisation) of that part of the estimator. A sample whose camera
 *            throughput differs between its wavelengths (a medium on the way) or whose wavelengths are one
 *            (sensors) records the sampled value for both.
 * The film keeps per pixel three float4 sums over the samples in sample order (split-invariant like the film):
 *   [0] albedo's film-XYZ estimate (the film's estimator applied to the albedo spectrum) and ΣY² of the image,
 *   [1] normal, unused, [2] position and depth, [3] the emission's sampled film XYZ, unused, [4] its expected film
 *   XYZ, unused. The host divides by the samples done. */
#ifndef SPECTRACE_AOV_CL
#define SPECTRACE_AOV_CL

#ifndef FILM_AOVS
#define FILM_AOVS 0
#endif

#if FILM_AOVS

#include "film.cl"

/* FILM_STOKES (a polarised render's Stokes images, polarized_path.cl): four more sums, the film XYZ of S0..S3. */
#ifndef FILM_STOKES
#define FILM_STOKES 0
#endif
#define AOV_STOKES 5
#define AOV_FLOAT4S_PER_PIXEL (FILM_STOKES ? 9 : 5)

typedef struct {
    float4 albedo;         /* albedo estimate at the four wavelengths (dimensionless) */
    float4 normal;         /* xyz: world shading normal of the first surface */
    float4 position;       /* xyz: first surface point (scene units); w: depth t (scene units) */
    float4 emission_sampled;   /* xyz: film XYZ estimate of the emission the camera ray meets (radiance units) */
    float4 emission_expected;  /* xyz: its expected value over the wavelengths (radiance units) */
    float travelled;       /* scene units of camera ray crossed through material-less boundaries so far */
    int surface_recorded;  /* normal, position and depth are final */
    int albedo_recorded;   /* albedo is final */
} AovRecord;

inline AovRecord aov_start(void)
{
    AovRecord a;
    a.albedo = (float4)(0.0f);
    a.normal = (float4)(0.0f);
    a.position = (float4)(0.0f);
    a.emission_sampled = (float4)(0.0f);
    a.emission_expected = (float4)(0.0f);
    a.travelled = 0.0f;
    a.surface_recorded = 0;
    a.albedo_recorded = 0;
    return a;
}

/* The camera path's ray met a surface at parameter t (point p, shading normal ns); has_material is 0 for a
 * material-less medium boundary, which the ray crosses without a vertex. */
inline void aov_at_surface(AovRecord *a, float t, float3 p, float3 ns, int has_material)
{
    if (a->surface_recorded) return;
    if (!has_material) {
        a->travelled += t;
        return;
    }
    a->normal = (float4)(ns, 0.0f);
    a->position = (float4)(p, a->travelled + t);
    a->surface_recorded = 1;
}

/* The camera path scattered in a medium at p, distance t along its ray, with throughput `weight` (radiance
 * compression removed): the medium's albedo estimate. */
inline void aov_at_medium_scatter(AovRecord *a, float t, float3 p, float4 weight)
{
    if (!a->surface_recorded) {
        a->position = (float4)(p, a->travelled + t);
        a->surface_recorded = 1;
    }
    if (!a->albedo_recorded) {
        a->albedo = weight;
        a->albedo_recorded = 1;
    }
}

/* At a surface vertex, after the path drew its BSDF sample (sampled: the draw gave a usable direction, whose
 * f·cos/pdf is bsdf_weight). throughput: the path's throughput at the vertex without radiance compression. A
 * vertex with only delta lobes continues the chain (the throughput carries its weight to the next vertex). */
inline void aov_at_bsdf_sample(AovRecord *a, int non_delta, int sampled, float4 throughput, float4 bsdf_weight)
{
    if (a->albedo_recorded) return;
    if (non_delta || !sampled) {
        a->albedo = sampled ? throughput * bsdf_weight : (float4)(0.0f);
        a->albedo_recorded = 1;
    }
}

/* Trapezoid weights of grid nodes i .. i+3 (0 beyond the grid) and their wavelengths (nm), for the expected
 * emission's sum over the grid. */
inline float4 aov_grid_weights(int i, float4 *lambda)
{
    const float step = (GRID_MAX_NM - GRID_MIN_NM) / (float)(GRID_SAMPLES - 1);
    float4 index = (float4)((float)i, (float)(i + 1), (float)(i + 2), (float)(i + 3));
    *lambda = fmin(GRID_MIN_NM + step * index, (float4)(GRID_MAX_NM));
    float4 weight = select((float4)(step), (float4)(0.0f), index > (float4)(GRID_SAMPLES - 1));
    if (i == 0) weight.x *= 0.5f;
    int last = GRID_SAMPLES - 1 - i;
    if (last >= 0 && last < 4) weight = select(weight, 0.5f * weight, (int4)(0, 1, 2, 3) == (int4)(last));
    return weight;
}

inline float4 aov_grid_xyz(__global const float4 *cmf, int i, float4 weight, float4 emitted)
{
    float4 e = weight * emitted;
    float4 xyz = e.x * cmf[i] + (e.y != 0.0f ? e.y * cmf[min(i + 1, GRID_SAMPLES - 1)] : (float4)(0.0f))
               + (e.z != 0.0f ? e.z * cmf[min(i + 2, GRID_SAMPLES - 1)] : (float4)(0.0f))
               + (e.w != 0.0f ? e.w * cmf[min(i + 3, GRID_SAMPLES - 1)] : (float4)(0.0f));
    return (float4)(xyz.x, xyz.y, xyz.z, 0.0f);
}

/* Whether the camera ray's emission can be given its expected value: the path's throughput is one number for
 * every wavelength, and the wavelengths differ (not a sensor's). */
inline int aov_emission_expectable(float4 throughput, const SampledWavelengths *w)
{
    return all(throughput == (float4)(throughput.x)) && wavelengths_differ(w);
}

/* The camera ray met emission `emitted` at wavelengths w with path throughput `throughput` and MIS weight
 * `weight` (what the path adds to its radiance); expected_xyz is the film XYZ of the emitted spectrum (the film's
 * table `cmf`), when aov_emission_expectable said it can be had (otherwise ignored). */
inline void aov_at_camera_emission(AovRecord *a, __global const float4 *cmf, float4 throughput, float4 emitted,
                                   float weight, float4 expected_xyz, int expectable, const SampledWavelengths *w)
{
    float4 sampled = spectrum_to_xyz_estimate(throughput * emitted * weight, cmf, w);
    a->emission_sampled += sampled;
    a->emission_expected += expectable ? throughput.x * weight * expected_xyz : sampled;
}

/* Adds a finished sample's AOVs to the pixel's running sums `sums` (AOV_FLOAT4S_PER_PIXEL float4s held by the
 * caller). The image's Y² counts only when the sample's XYZ is finite, as add_pixel_sample adds it; a non-finite
 * albedo estimate adds 0. */
inline void add_aov_sample(float4 *sums, const AovRecord *a, float4 radiance, float filter_weight,
                           __global const float4 *cmf, const SampledWavelengths *w)
{
    float4 xyz = spectrum_to_xyz_estimate(radiance, cmf, w);
    float y2 = (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z)) ? xyz.y * xyz.y : 0.0f;
    float4 albedo = spectrum_to_xyz_estimate(a->albedo, cmf, w);
    if (!(isfinite(albedo.x) && isfinite(albedo.y) && isfinite(albedo.z))) albedo = (float4)(0.0f);
    sums[0] += (float4)(albedo.x, albedo.y, albedo.z, y2);
    sums[1] += a->normal;
    sums[2] += a->position;
    float4 sampled = filter_weight * a->emission_sampled;
    float4 expected = filter_weight * a->emission_expected;
    if (isfinite(xyz.x) && isfinite(xyz.y) && isfinite(xyz.z) && isfinite(sampled.x) && isfinite(sampled.y)
        && isfinite(sampled.z) && isfinite(expected.x) && isfinite(expected.y) && isfinite(expected.z)) {
        sums[3] += sampled;
        sums[4] += expected;
    }
}

#endif
#endif
