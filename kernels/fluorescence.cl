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
    if (SCENE_HAS_MIX) base = mix_resolve(scene, base, v->p, v->wo, v->uv, v->footprint, v->triangle, v->b12);
    return base;
}

/* The quantum yield at the vertex: the row's, or its texture's value there. */
inline float fluorescent_yield(const Scene *scene, __global const Material *m, const PathVertex *v)
{
    float quantum_yield = m->alpha;
    if (SCENE_HAS_TEXTURES && m->roughness_texture != NO_TEXTURE) {
        SurfaceContext sc = surface_context(scene, v->uv, v->footprint);
        SURFACE_AT_HIT(sc, *v);
        quantum_yield = texture_numbers_at(&sc.buffers, m->roughness_texture, v->uv, v->p, v->footprint).x;
    }
    return quantum_yield;
}

/* What a dye's choice at a vertex is made from, at the hero wavelength of the side that meets it (light_side: a light
 * path's λi; otherwise a camera path's λo): the odds F of the re-emission against the base, whose probabilities are
 * P = F / (1 + F) and 1 − P = 1 / (1 + F), and what the draw of the other wavelength reads again. */
typedef struct {
    float odds;      /* F: camera side Q e(λo) ∫a dλ, light side Q a(λi) (a matrix: its column's or row's total) */
    float spectral;  /* a separable dye's Q e(λo) (camera side) or Q a(λi) (light side) */
    int line;        /* a matrix's column (camera side) or row (light side) below the hero wavelength */
    float t;         /* and the hero wavelength's fraction toward the next */
} DyeOdds;

/* The odds at dye m (its yield factor quantum_yield at the vertex) at w's hero wavelength. */
inline DyeOdds fluorescent_odds(const Scene *scene, __global const Material *m, float quantum_yield,
                                const SampledWavelengths *w, int light_side)
{
    DyeOdds o;
#if SCENE_HAS_FLUORESCENCE_MATRIX
    if (m->ior_model != MATERIAL_NO_SPECTRUM) {  /* a non-separable matrix (fluorescence_matrix.cl) */
        o.odds = fluorescent_matrix_odds(scene->spectra, m->ior_model, quantum_yield, w->lambda.x, light_side,
                                         &o.line, &o.t);
        return o;
    }
#endif
    int offset = light_side ? m->reflectance_offset : m->transmittance_offset;
    o.spectral = quantum_yield * table_lerp(scene->spectra, offset + w->grid_index.x, w->grid_frac.x);
    o.odds = light_side ? o.spectral : o.spectral * m->coat_internal_reflectance;
    return o;
}

/* The re-emission's other wavelength, drawn with u after the choice o (camera side: λi ∝ a(λ)·λ; light side: λo
 * from e(λ), its CDF a row after it; a matrix: fluorescent_matrix_draw), as the wavelengths the path goes on with:
 * the hero's density of the draw on the camera side, that of the light path's own draw (film.cl) on the light side.
 * *pdf the draw's density (1/nm); *value Q a(λi) e(λo), or Q D(λi, λo). */
inline SampledWavelengths fluorescent_draw(const Scene *scene, __global const Material *m, float quantum_yield,
                                           const DyeOdds *o, const SampledWavelengths *w, int light_side, float u,
                                           float *pdf, float *value)
{
    __global const float *table = scene->spectra;
#if SCENE_HAS_FLUORESCENCE_MATRIX
    if (m->ior_model != MATERIAL_NO_SPECTRUM) {
        float lambda = fluorescent_matrix_draw(table, m->ior_model, quantum_yield, o->line, o->t, light_side, u,
                                               pdf, value);
        return wavelengths_on_grid((float4)(lambda), (float4)(light_side ? w->pdf.x : *pdf));
    }
#endif
    int cdf = light_side ? m->transmittance_offset + GRID_SAMPLES : m->coat_table_offset;
    float lambda = sample_grid_cell_wavelength(table + cdf, u, pdf);
    SampledWavelengths next = wavelengths_on_grid((float4)(lambda), (float4)(light_side ? w->pdf.x : *pdf));
    int other = light_side ? m->transmittance_offset : m->reflectance_offset;
    *value = o->spectral * table_lerp(table, other + next.grid_index.x, next.grid_frac.x);
    return next;
}

/* A dye's choice where a path meets it, the camera's (light_side 0) or a light path's: v->info.material becomes what
 * shades the vertex (the base, a mix of them resolved, or the white re-emission lobe), s->throughput takes the
 * choice's weight, and so does *scatter, a light path's scattering weights for Russian roulette. A re-emission
 * switches a camera path's wavelength (path_wavelengths) and *w of a light path, in every lane, to the wavelength
 * drawn (fluorescent_draw). Any other vertex is left alone and draws nothing, as does a yield of 0 (the base, with
 * its bits). */
inline void fluorescent_choose(const Scene *scene, SampledWavelengths *w, Sampler *sampler, PathState *s,
                               PathVertex *v, float4 *scatter, int light_side)
{
    __global const Material *m = &scene->materials[v->info.material];
    if (m->type != MATERIAL_FLUORESCENT) return;
    int base = fluorescent_base(scene, m, v);
    if (!(m->alpha > 0.0f)) {
        v->info.material = base;
        return;
    }
    float quantum_yield = fluorescent_yield(scene, m, v);
    float u_choice = sample_1d(sampler);
    float u_lambda = sample_1d(sampler);
    DyeOdds o = fluorescent_odds(scene, m, quantum_yield, w, light_side);
    float p_fluoresce = o.odds / (1.0f + o.odds);
    if (!(u_choice < p_fluoresce)) {
        if (light_side) {  /* the same factor on both of a light path's weights */
            float elastic = 1.0f / (1.0f - p_fluoresce);
            s->throughput *= elastic;
            *scatter *= elastic;
        } else {
            s->throughput /= 1.0f - p_fluoresce;
        }
        v->info.material = base;
        return;
    }
    float pdf, value;
    SampledWavelengths next = fluorescent_draw(scene, m, quantum_yield, &o, w, light_side, u_lambda, &pdf, &value);
    float lambda_in = light_side ? w->lambda.x : next.lambda.x;
    float lambda_out = light_side ? next.lambda.x : w->lambda.x;
    float weight = value * (lambda_in / lambda_out) / (pdf * p_fluoresce);
    terminate_secondary(&s->throughput, &s->secondary_terminated);
    s->throughput *= weight;
    if (light_side) {
        *scatter *= weight;
        *w = next;
    } else {
        s->fluorescent_wavelengths = next;
        s->fluoresced = 1;
    }
    v->info.material = m->k_offset;
}

/* fluorescent_choose for a camera path, whose wavelengths at the vertex are *w. */
inline void fluorescent_vertex(const Scene *scene, const SampledWavelengths *w, Sampler *sampler, PathState *s,
                               PathVertex *v)
{
    SampledWavelengths hero = *w;
    float4 unused = (float4)(1.0f);
    fluorescent_choose(scene, &hero, sampler, s, v, &unused, 0);
}

/* fluorescent_choose for a light path, which carries light forward: its hero wavelength is the absorbed λi, and a
 * re-emission draws λo and goes on at it, weighted by
 *     Q a(λi) e(λo) (λi / λo) / (p(λo) P),  P = F / (1 + F),  F = Q a(λi)
 * on the hero alone (x4), the elastic part by 1 / (1 − P) on every lane. *w becomes λo in every lane with the
 * density the hero was drawn with: the camera sees λo, and the film divides by the density of the path's own draw. */
inline void fluorescent_light_vertex(const Scene *scene, SampledWavelengths *w, Sampler *sampler, PathState *s,
                                     PathVertex *v, float4 *scatter)
{
    fluorescent_choose(scene, w, sampler, s, v, scatter, 1);
}

#endif

#endif
