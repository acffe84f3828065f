/* Fluorescent (bispectral) surfaces in the path and light tracers (host: spectrace.materials.fluorescent, which states the
 * model): a dye of excitation a(λ) (fraction of photons absorbed, dimensionless), normalised emission e(λ) (1/nm) and
 * quantum yield Q over a non-fluorescent base, whose bispectral BSDF is
 *     f(λi → λo) = f_base(λo) δ(λi − λo) + a(λi) Q e(λo) (λi / λo) / π.
 *
 * A camera path carries radiance backward, so where it meets the dye its wavelength λo is the one the dye emits
 * toward the camera, and what it must gather is the light arriving at every excitation wavelength λi. As Mojzík,
 * Fichet and Wilkie 2018 ("Handling Fluorescence in a Uni-directional Spectral Path Tracer", Computer Graphics
 * Forum 37(4), EGSR) do in a hero-wavelength tracer, the vertex chooses between the elastic part (the base BSDF, every
 * wavelength going on as it was) and the re-emission, by a probability P drawn from the hero λo alone; the
 * re-emission keeps only the hero wavelength (terminate_secondary, as dispersion does: each wavelength would change
 * to its own λi) and switches it to λi drawn from a density ∝ a(λi)·λi, the path then going on from a white
 * Lambertian lobe at λi, its next-event estimation and every emission it meets read at λi. The estimator's weights:
 *     elastic:     1 / (1 − P)                                        on every lane, then the base's BSDF
 *     re-emission: Q e(λo) a(λi) (λi / λo) / (p(λi) P)               on the hero (x4), then the white lobe
 * unbiased as long as P < 1 (secondary lanes reach their elastic part only through it) and P > 0 where e(λo) > 0.
 * P = F / (1 + F) with F = Q e(λo) ∫a dλ, the expected re-emitted photons toward λo per photon of a flat
 * illuminant, against the base's at most 1. The film keeps the wavelengths the camera path started with: the
 * radiance found at λi, weighted as above, is L(λo).
 *
 * The fluorescent row (kernels/types.h, spectrace.materials.fluorescent): eta_offset the base's row, k_offset the
 * white lobe's, reflectance_offset a(λ), transmittance_offset e(λ), coat_table_offset the CDF of a(λ)·λ at the grid's
 * GRID_SAMPLES wavelengths (1 nm cells), coat_internal_reflectance ∫a dλ (nm), alpha Q (0: the base alone; with
 * roughness_texture, a grey texture of Q per point, alpha its largest value), ior_model a non-separable matrix's
 * block (fluorescence_matrix.cl, which then replaces the dye's spectra) or MATERIAL_NO_SPECTRUM.
 * The path tracer and the light tracer include this file; SCENE_HAS_FLUORESCENCE (scene_features.h) leaves it out
 * of every scene without the material, whose kernels and bits stay as they were. */
#ifndef SPECTRACE_FLUORESCENCE_CL
#define SPECTRACE_FLUORESCENCE_CL

#include "path_state.cl"

#if SCENE_HAS_FLUORESCENCE

#include "fluorescence_matrix.cl"

/* The wavelengths path s carries: its own after a fluorescent re-emission, those it started with (w) before. */
inline const SampledWavelengths *path_wavelengths(const PathState *s, const SampledWavelengths *w)
{
    return s->fluoresced ? &s->fluorescent_wavelengths : w;
}

/* The grid cell a uniform u ∈ [0, 1) falls in by the CDF `cdf` (GRID_SAMPLES values from 0 to 1), and a wavelength
 * uniform within it (nm); *pdf its density (1/nm, the cell's mass over its 1 nm). A cell that u can reach has a
 * mass above 0: cdf[lo] ≤ u < cdf[lo + 1]. */
inline float sample_grid_cell_wavelength(__global const float *cdf, float u, float *pdf)
{
    int lo = 0, hi = GRID_SAMPLES - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    float mass = cdf[lo + 1] - cdf[lo];
    *pdf = mass;
    float t = mass > 0.0f ? (u - cdf[lo]) / mass : 0.5f;
    return GRID_MIN_NM + (float)lo + clamp(t, 0.0f, 1.0f);
}

/* The row that shades a fluorescent material's vertex without a change of wavelength: its base, a mix of them
 * resolved at the vertex. */
inline int fluorescent_base(const Scene *scene, __global const Material *m, const PathVertex *v)
{
    int base = m->eta_offset;
    if (SCENE_HAS_MIX) base = mix_resolve(scene, base, v->p, v->wo, v->uv, v->footprint);
    return base;
}

/* The quantum yield at the vertex: the row's, or its texture's value there. */
inline float fluorescent_yield(const Scene *scene, __global const Material *m, const PathVertex *v)
{
    float quantum_yield = m->alpha;
    if (SCENE_HAS_TEXTURES && m->roughness_texture != NO_TEXTURE) {
        SurfaceContext sc = surface_context(scene, v->uv, v->footprint);
        quantum_yield = texture_numbers_at(&sc.buffers, m->roughness_texture, v->uv, v->p, v->footprint).x;
    }
    return quantum_yield;
}

/* At a vertex of a fluorescent material: v->info.material becomes what shades it (the base, a mix of them
 * resolved, or the white re-emission lobe), s->throughput takes the choice's weight, and a re-emission switches the
 * path's wavelength (path_wavelengths). w: the path's wavelengths at the vertex. Any other vertex is left alone
 * and draws nothing, as does a yield of 0 (the base, with its bits). */
inline void fluorescent_vertex(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                               PathVertex *v)
{
    __global const Material *m = &scene->materials[v->info.material];
    if (m->type != MATERIAL_FLUORESCENT) return;
    int base = fluorescent_base(scene, m, v);
    if (!(m->alpha > 0.0f)) {
        v->info.material = base;
        return;
    }
    float quantum_yield = fluorescent_yield(scene, m, v);
#if SCENE_HAS_FLUORESCENCE_MATRIX
    if (m->ior_model != MATERIAL_NO_SPECTRUM) {  /* a non-separable matrix (fluorescence_matrix.cl) */
        fluorescent_matrix_vertex(scene, m, base, quantum_yield, w, sampler, s, v);
        return;
    }
#endif
    float u_choice = sample_1d(sampler);
    float u_lambda = sample_1d(sampler);
    __global const float *table = scene->spectra;
    float lambda_out = w->lambda.x;
    float emitted = quantum_yield * table_lerp(table, m->transmittance_offset + w->grid_index.x, w->grid_frac.x);
    float expected = emitted * m->coat_internal_reflectance;
    float p_fluoresce = expected / (1.0f + expected);
    if (!(u_choice < p_fluoresce)) {
        s->throughput /= 1.0f - p_fluoresce;
        v->info.material = base;
        return;
    }
    float pdf;
    float lambda_in = sample_grid_cell_wavelength(table + m->coat_table_offset, u_lambda, &pdf);
    SampledWavelengths in = wavelengths_on_grid((float4)(lambda_in), (float4)(pdf));
    float absorbed = table_lerp(table, m->reflectance_offset + in.grid_index.x, in.grid_frac.x);
    terminate_secondary(&s->throughput, &s->secondary_terminated);
    s->throughput *= emitted * absorbed * (lambda_in / lambda_out) / (pdf * p_fluoresce);
    s->fluorescent_wavelengths = in;
    s->fluoresced = 1;
    v->info.material = m->k_offset;
}

/* The same vertex met by a light path (light_tracer.cl), which carries light forward: its hero wavelength is the
 * absorbed λi, and a re-emission draws λo from e(λ) (its CDF a row after it) and goes on at λo, weighted by
 *     Q a(λi) e(λo) (λi / λo) / (p(λo) P),  P = F / (1 + F),  F = Q a(λi)
 * on the hero alone (x4), the elastic part by 1 / (1 − P) on every lane. *w becomes λo in every lane with the
 * density the hero was drawn with: the camera sees λo, and the film divides by the density of the path's own
 * draw (film.cl). *scatter, the light path's scattering weights for Russian roulette, takes the same factor. */
inline void fluorescent_light_vertex(const Scene *scene, SampledWavelengths *w, Sampler *sampler, PathState *s,
                                     PathVertex *v, float4 *scatter)
{
    __global const Material *m = &scene->materials[v->info.material];
    if (m->type != MATERIAL_FLUORESCENT) return;
    int base = fluorescent_base(scene, m, v);
    if (!(m->alpha > 0.0f)) {
        v->info.material = base;
        return;
    }
    float quantum_yield = fluorescent_yield(scene, m, v);
#if SCENE_HAS_FLUORESCENCE_MATRIX
    if (m->ior_model != MATERIAL_NO_SPECTRUM) {
        fluorescent_matrix_light_vertex(scene, m, base, quantum_yield, w, sampler, s, v, scatter);
        return;
    }
#endif
    float u_choice = sample_1d(sampler);
    float u_lambda = sample_1d(sampler);
    __global const float *table = scene->spectra;
    float lambda_in = w->lambda.x;
    float absorbed = quantum_yield * table_lerp(table, m->reflectance_offset + w->grid_index.x, w->grid_frac.x);
    float p_fluoresce = absorbed / (1.0f + absorbed);
    if (!(u_choice < p_fluoresce)) {
        float elastic = 1.0f / (1.0f - p_fluoresce);
        s->throughput *= elastic;
        *scatter *= elastic;
        v->info.material = base;
        return;
    }
    float pdf;
    float lambda_out = sample_grid_cell_wavelength(table + m->transmittance_offset + GRID_SAMPLES, u_lambda, &pdf);
    SampledWavelengths out = wavelengths_on_grid((float4)(lambda_out), (float4)(w->pdf.x));
    float emitted = table_lerp(table, m->transmittance_offset + out.grid_index.x, out.grid_frac.x);
    float weight = absorbed * emitted * (lambda_in / lambda_out) / (pdf * p_fluoresce);
    terminate_secondary(&s->throughput, &s->secondary_terminated);
    s->throughput *= weight;
    *scatter *= weight;
    *w = out;
    v->info.material = m->k_offset;
}

#endif

#endif
