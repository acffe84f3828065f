/* Heterogeneous media: a medium whose coefficients are the homogeneous medium's spectra σa(λ), σs(λ) times a density
 * d(x) read from a voxel grid (and σs times an optional albedo grid a(x)), inside a box placed by an affine map:
 *   σt(λ, x) = d(x) (σa(λ) + σs(λ)),   σs(λ, x) = a(x) d(x) σs(λ),   0 outside the box.
 *
 * Sources (read to learn, not copied): Woodcock et al. 1965 and Novák et al. 2014, "Residual ratio tracking for
 * estimating attenuation in participating media" (delta and ratio tracking against a majorant); Kutz et al. 2017,
 * "Spectral and decomposition tracking for rendering heterogeneous volumes" (one majorant for several wavelengths,
 * collision probabilities from the path's throughput); pbrt-v4's GridMedium and DDAMajorantIterator (a coarse grid of
 * per-cell maximum densities walked by a 3D DDA, Amanatides & Woo 1987).
 *
 * Contract. The grid's block lives in the scene's float table (`spectra`) at Medium.grid (-1: homogeneous), laid out
 * by spectrace.geometry.grid_volume: the world → unit-box map (3 rows of 4), then as int bits: nx, ny, nz (voxels),
 * mx, my, mz (majorant cells), the offsets of the density, albedo (-1: none) and majorant arrays, x fastest, and
 * the albedo's channels: 1 (a grey value a voxel) or 3 (a colour, stored as 4 floats a voxel: the dimensionless
 * sigmoid coefficients (rgb_spectrum.cl) of the colour over s, then s = 2 × its largest channel), the density's
 * channels in the same sense (1, or 3: a colour density, σt varying with λ voxel by voxel), and what lies outside the
 * box (GRID_OUTSIDE_*). A colour is the mix of the eight surrounding voxels' spectra at the path's wavelengths times
 * the mix of their s, as Mitsuba 3's spectral gridvolume evaluates it: a mix of spectra has the mix of their colours.
 * A colour density's majorant cell holds the cell's largest s times the largest value any of its voxels' spectra
 * takes over the wavelength grid (host side), which bounds that product at every wavelength a path can carry.
 *
 * Free flights: tentative collisions are drawn at rate μ, cell by cell (a flight past a cell's end restarts at the
 * next cell, the exponential being memoryless). At a collision the path scatters with probability
 * Ps = Σ h σs / (Σ h σs + Σ h σn) (h: the path's throughput per lane, σn = μ − σt ≥ 0 the null coefficient) and
 * goes on otherwise; each lane is weighted by σs/(μ Ps) or σn/(μ (1 − Ps)) (Kutz et al.'s spectral tracking):
 * unbiased for every lane, absorption carried by the weights, and the throughput summed over lanes never grows.
 * Transmittance (shadow rays): ratio tracking, Π σn/μ over the collisions, per lane. Their random numbers after the
 * flight's first come from a hash chain seeded by the sampler's draws (or the shadow ray's query), so a flight takes
 * the same two sampler draws as in a homogeneous medium and renders stay deterministic. */
#ifndef SPECTRACE_MEDIUM_GRID_CL
#define SPECTRACE_MEDIUM_GRID_CL

#include "hash.cl"
#include "rgb_spectrum.cl"

/* A guard against a flight that never ends (a NaN, a majorant of 0 with an infinite box): far above any scene's. */
#define GRID_MAX_COLLISIONS 1048576

#define GRID_HEADER_INT(spectra, grid, i) as_int((spectra)[(grid) + 12 + (i)])

/* What a grid holds outside its box: nothing (the medium ends there), the values at its faces (the grid fills all
 * space), or copies of itself (it tiles space). The last two are for an albedo over a homogeneous σt (Mitsuba 3's
 * gridvolume lookups, clamped or repeated); their majorant is one cell, unbounded, of the grid's largest value. */
#define GRID_OUTSIDE_EMPTY 0
#define GRID_OUTSIDE_CLAMP 1
#define GRID_OUTSIDE_REPEAT 2

/* The point of world position p in the grid's unit box. */
inline float3 grid_unit_point(__global const float *spectra, int grid, float3 p)
{
    __global const float *m = spectra + grid;
    return (float3)(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                    m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

inline float3 grid_unit_vector(__global const float *spectra, int grid, float3 d)
{
    __global const float *m = spectra + grid;
    return (float3)(m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                    m[8] * d.x + m[9] * d.y + m[10] * d.z);
}

/* The eight voxels around unit-box point u (inside the box) and the weights between them. */
inline float3 grid_corners(int3 n, float3 u, int3 *i0, int3 *i1)
{
    float3 q = clamp(u * convert_float3(n) - 0.5f, (float3)(0.0f), convert_float3(n - 1));
    *i0 = min(convert_int3(floor(q)), n - 1);
    *i1 = min(*i0 + 1, n - 1);
    return q - convert_float3(*i0);
}

/* grid_corners for a grid that tiles space: the lookup wraps around at the faces (Mitsuba 3's repeat mode). */
inline float3 grid_corners_repeat(int3 n, float3 u, int3 *i0, int3 *i1)
{
    float3 q = u * convert_float3(n) - 0.5f;
    float3 low = floor(q);
    int3 i = convert_int3(low) % n;
    *i0 = select(i, i + n, i < (int3)(0));
    *i1 = select(*i0 + 1, (int3)(0), *i0 + 1 >= n);
    return q - low;
}

/* The eight voxels around any unit-box point u of a grid whose outside is `outside` (not empty). */
inline float3 grid_corners_outside(int outside, int3 n, float3 u, int3 *i0, int3 *i1)
{
    return outside == GRID_OUTSIDE_REPEAT ? grid_corners_repeat(n, u, i0, i1) : grid_corners(n, u, i0, i1);
}

/* The trilinear value of the voxel array at `offset` (dimensions n) between voxels i0 and i1 at weights f. */
inline float grid_trilinear(__global const float *spectra, int offset, int3 n, int3 i0, int3 i1, float3 f)
{
    __global const float *v = spectra + offset;
#define GRID_AT(ix, iy, iz) v[((iz) * n.y + (iy)) * n.x + (ix)]
    float c00 = mix(GRID_AT(i0.x, i0.y, i0.z), GRID_AT(i1.x, i0.y, i0.z), f.x);
    float c10 = mix(GRID_AT(i0.x, i1.y, i0.z), GRID_AT(i1.x, i1.y, i0.z), f.x);
    float c01 = mix(GRID_AT(i0.x, i0.y, i1.z), GRID_AT(i1.x, i0.y, i1.z), f.x);
    float c11 = mix(GRID_AT(i0.x, i1.y, i1.z), GRID_AT(i1.x, i1.y, i1.z), f.x);
#undef GRID_AT
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

/* The trilinear value of the voxel array at `offset` (dimensions n) at unit-box point u, 0 outside the box. */
inline float grid_lookup(__global const float *spectra, int offset, int3 n, float3 u)
{
    if (any(u < (float3)(0.0f)) || any(u > (float3)(1.0f))) return 0.0f;
    int3 i0, i1;
    float3 f = grid_corners(n, u, &i0, &i1);
    return grid_trilinear(spectra, offset, n, i0, i1, f);
}

/* A colour between voxels i0 and i1 at weights f: the trilinear mix of the voxels' spectra at the four wavelengths
 * times the trilinear mix of their scales. */
inline float4 grid_trilinear_colour(__global const float *spectra, int offset, int3 n, int3 i0, int3 i1, float3 f,
                                    float4 lambda)
{
    __global const float *v = spectra + offset;
#define GRID_VOXEL(ix, iy, iz) vload4(((iz) * n.y + (iy)) * n.x + (ix), v)
#define GRID_SPECTRUM(c) sigmoid_polynomial_dimensionless((c).xyz, lambda)
    float4 v000 = GRID_VOXEL(i0.x, i0.y, i0.z), v100 = GRID_VOXEL(i1.x, i0.y, i0.z);
    float4 v010 = GRID_VOXEL(i0.x, i1.y, i0.z), v110 = GRID_VOXEL(i1.x, i1.y, i0.z);
    float4 v001 = GRID_VOXEL(i0.x, i0.y, i1.z), v101 = GRID_VOXEL(i1.x, i0.y, i1.z);
    float4 v011 = GRID_VOXEL(i0.x, i1.y, i1.z), v111 = GRID_VOXEL(i1.x, i1.y, i1.z);
    float4 c00 = mix(GRID_SPECTRUM(v000), GRID_SPECTRUM(v100), f.x);
    float4 c10 = mix(GRID_SPECTRUM(v010), GRID_SPECTRUM(v110), f.x);
    float4 c01 = mix(GRID_SPECTRUM(v001), GRID_SPECTRUM(v101), f.x);
    float4 c11 = mix(GRID_SPECTRUM(v011), GRID_SPECTRUM(v111), f.x);
    float s00 = mix(v000.w, v100.w, f.x), s10 = mix(v010.w, v110.w, f.x);
    float s01 = mix(v001.w, v101.w, f.x), s11 = mix(v011.w, v111.w, f.x);
#undef GRID_SPECTRUM
#undef GRID_VOXEL
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z) * mix(mix(s00, s10, f.y), mix(s01, s11, f.y), f.z);
}

/* A colour at unit-box point u inside the box (grid_trilinear_colour). */
inline float4 grid_lookup_colour(__global const float *spectra, int offset, int3 n, float3 u, float4 lambda)
{
    int3 i0, i1;
    float3 f = grid_corners(n, u, &i0, &i1);
    return grid_trilinear_colour(spectra, offset, n, i0, i1, f, lambda);
}

/* A value of the array at `offset` with `channels` (1 or 3) at the four wavelengths. */
inline float4 grid_value(__global const float *spectra, int offset, int channels, int3 n, int3 i0, int3 i1, float3 f,
                         float4 lambda)
{
    return channels == 3 ? grid_trilinear_colour(spectra, offset, n, i0, i1, f, lambda)
                         : (float4)(grid_trilinear(spectra, offset, n, i0, i1, f));
}

/* Density d(λ, x) and, where `albedo` is not 0, albedo a(λ, x) (1 without an albedo grid) of a grid that is not
 * empty outside its box or has a colour density. */
inline float4 grid_density_albedo_general(__global const float *spectra, int grid, float3 x, float4 lambda,
                                          float4 *albedo)
{
    float3 u = grid_unit_point(spectra, grid, x);
    int3 n = (int3)(GRID_HEADER_INT(spectra, grid, 0), GRID_HEADER_INT(spectra, grid, 1),
                    GRID_HEADER_INT(spectra, grid, 2));
    int outside = GRID_HEADER_INT(spectra, grid, 11);
    if (outside == GRID_OUTSIDE_EMPTY && (any(u < (float3)(0.0f)) || any(u > (float3)(1.0f)))) {
        if (albedo) *albedo = (float4)(1.0f);
        return (float4)(0.0f);
    }
    int3 i0, i1;
    float3 f = grid_corners_outside(outside, n, u, &i0, &i1);
    float4 density = grid_value(spectra, GRID_HEADER_INT(spectra, grid, 6), GRID_HEADER_INT(spectra, grid, 10), n, i0,
                                i1, f, lambda);
    if (albedo) {
        int offset = GRID_HEADER_INT(spectra, grid, 7);
        *albedo = offset < 0 || !any(density > (float4)(0.0f))
                      ? (float4)(1.0f)
                      : grid_value(spectra, offset, GRID_HEADER_INT(spectra, grid, 9), n, i0, i1, f, lambda);
    }
    return density;
}

/* Whether a grid takes the general lookups: a colour density, or values outside its box. */
inline int grid_is_general(__global const float *spectra, int grid)
{
    return GRID_HEADER_INT(spectra, grid, 10) != 1 || GRID_HEADER_INT(spectra, grid, 11) != GRID_OUTSIDE_EMPTY;
}

/* Density d(λ, x) at world point x, at the four wavelengths. */
inline float4 grid_density(__global const float *spectra, int grid, float3 x, float4 lambda)
{
    if (grid_is_general(spectra, grid)) return grid_density_albedo_general(spectra, grid, x, lambda, 0);
    float3 u = grid_unit_point(spectra, grid, x);
    int3 n = (int3)(GRID_HEADER_INT(spectra, grid, 0), GRID_HEADER_INT(spectra, grid, 1),
                    GRID_HEADER_INT(spectra, grid, 2));
    return (float4)(grid_lookup(spectra, GRID_HEADER_INT(spectra, grid, 6), n, u));
}

/* Density d(λ, x) at world point x, and in *albedo a(λ, x) at the four wavelengths (1 without an albedo grid). */
inline float4 grid_density_albedo(__global const float *spectra, int grid, float3 x, float4 lambda, float4 *albedo)
{
    if (grid_is_general(spectra, grid)) return grid_density_albedo_general(spectra, grid, x, lambda, albedo);
    float3 u = grid_unit_point(spectra, grid, x);
    int3 n = (int3)(GRID_HEADER_INT(spectra, grid, 0), GRID_HEADER_INT(spectra, grid, 1),
                    GRID_HEADER_INT(spectra, grid, 2));
    float density = grid_lookup(spectra, GRID_HEADER_INT(spectra, grid, 6), n, u);
    int offset = GRID_HEADER_INT(spectra, grid, 7);
    if (offset < 0 || !(density > 0.0f)) {
        *albedo = (float4)(1.0f);
    } else if (GRID_HEADER_INT(spectra, grid, 9) == 3) {
        *albedo = grid_lookup_colour(spectra, offset, n, u, lambda);  /* density > 0: u is inside the box */
    } else {
        *albedo = (float4)(grid_lookup(spectra, offset, n, u));
    }
    return (float4)(density);
}

#include "medium_emission.cl"

/* The majorant cells a ray crosses inside the unit box, in order (a 3D DDA). t is the ray's own parameter. */
typedef struct {
    float3 next;    /* t at which the ray enters the next cell along each axis */
    float3 delta;   /* t across one cell along each axis */
    int3 cell;
    int3 step;
    int3 cells;
    float t;        /* where the current cell starts */
    float t_end;    /* where the walk ends: the box's far face or the caller's limit */
    int majorant;   /* offset of the majorant array */
} GridWalk;

/* A walk along origin + t·direction for t in [0, t_max]; returns 0 when the ray misses the box in that range. */
inline int grid_walk_start(__global const float *spectra, int grid, float3 origin, float3 direction, float t_max,
                           GridWalk *walk)
{
    if (GRID_HEADER_INT(spectra, grid, 11) != GRID_OUTSIDE_EMPTY) {
        /* The grid fills all space: one cell, the whole ray, never stepped out of by the DDA. */
        if (!(t_max > 0.0f)) return 0;
        walk->cells = (int3)(1);
        walk->majorant = GRID_HEADER_INT(spectra, grid, 8);
        walk->cell = (int3)(0);
        walk->step = (int3)(1);
        walk->next = (float3)(INFINITY);
        walk->delta = (float3)(INFINITY);
        walk->t = 0.0f;
        walk->t_end = t_max;
        return 1;
    }
    float3 o = grid_unit_point(spectra, grid, origin);
    float3 d = grid_unit_vector(spectra, grid, direction);
    float3 inv = 1.0f / d;  /* ±∞ along an axis the ray does not move along */
    float3 ta = -o * inv, tb = (1.0f - o) * inv;
    float3 lo = select(fmin(ta, tb), (float3)(-INFINITY), d == (float3)(0.0f));
    float3 hi = select(fmax(ta, tb), (float3)(INFINITY), d == (float3)(0.0f));
    if (any((d == (float3)(0.0f)) & (o < (float3)(0.0f) | o > (float3)(1.0f)))) return 0;
    float t0 = fmax(fmax(fmax(lo.x, lo.y), lo.z), 0.0f);
    float t1 = fmin(fmin(fmin(hi.x, hi.y), hi.z), t_max);
    if (!(t0 < t1)) return 0;
    walk->cells = (int3)(GRID_HEADER_INT(spectra, grid, 3), GRID_HEADER_INT(spectra, grid, 4),
                         GRID_HEADER_INT(spectra, grid, 5));
    walk->majorant = GRID_HEADER_INT(spectra, grid, 8);
    float3 m = convert_float3(walk->cells);
    float3 start = clamp((o + t0 * d) * m, (float3)(0.0f), m);
    walk->cell = clamp(convert_int3(floor(start)), (int3)(0), walk->cells - 1);
    walk->step = select((int3)(-1), (int3)(1), d >= (float3)(0.0f));
    float3 md = d * m;
    float3 face = convert_float3(walk->cell + select((int3)(0), (int3)(1), walk->step > (int3)(0)));
    walk->next = select((face - o * m) / md, (float3)(INFINITY), md == (float3)(0.0f));
    walk->delta = select(fabs(1.0f / md), (float3)(INFINITY), md == (float3)(0.0f));
    walk->t = t0;
    walk->t_end = t1;
    return 1;
}

/* The current cell's span [*t_enter, *t_exit] and its majorant density, then a step to the next cell. Returns 0 when
 * the walk has ended. */
inline int grid_walk_cell(__global const float *spectra, GridWalk *walk, float *t_enter, float *t_exit,
                          float *majorant)
{
    if (!(walk->t < walk->t_end)) return 0;
    int3 c = walk->cell;
    *majorant = spectra[walk->majorant + (c.z * walk->cells.y + c.y) * walk->cells.x + c.x];
    float exit = fmin(fmin(walk->next.x, walk->next.y), fmin(walk->next.z, walk->t_end));
    *t_enter = walk->t;
    *t_exit = exit;
    int axis = walk->next.x <= walk->next.y ? (walk->next.x <= walk->next.z ? 0 : 2)
                                            : (walk->next.y <= walk->next.z ? 1 : 2);
    if (axis == 0) {
        walk->cell.x += walk->step.x;
        walk->next.x += walk->delta.x;
    } else if (axis == 1) {
        walk->cell.y += walk->step.y;
        walk->next.y += walk->delta.y;
    } else {
        walk->cell.z += walk->step.z;
        walk->next.z += walk->delta.z;
    }
    walk->t = exit;
    if (any(walk->cell < (int3)(0)) || any(walk->cell >= walk->cells)) walk->t_end = exit;
    return 1;
}

/* A uniform number in [0, 1) from a hash chain. */
inline float grid_random(uint *state)
{
    *state = hash_u32(*state + 0x9e3779b9U);
    return (float)(*state >> 8) * 0x1.0p-24f;
}

/* Tentative collisions at the majorant along a ray, cell by cell: the walk of the free flights and of ratio tracking
 * alike. A collision's distance past the last one is exponential at the current cell's rate μ = its maximum density
 * × sigma_bound; a flight past the cell's end restarts at the next cell (the exponential being memoryless), which
 * spends the uniform it drew. */
typedef struct {
    GridWalk walk;
    float sigma_bound;  /* the largest σt over the lanes: μ's factor */
    float majorant;     /* μ in the current cell (1/m) */
    float t;            /* the last tentative collision, or the current cell's start */
    float t_exit;       /* the current cell's end */
    int collisions;
} GridTracking;

/* Tracking along origin + t·direction for t in [0, t_max] through grid `grid`; returns 0 when nothing can collide
 * there (σt of 0, or the ray misses the box). */
inline int grid_tracking_start(__global const float *spectra, int grid, float3 origin, float3 direction, float t_max,
                               float sigma_bound, GridTracking *k)
{
    if (!(sigma_bound > 0.0f) || !grid_walk_start(spectra, grid, origin, direction, t_max, &k->walk)) return 0;
    k->sigma_bound = sigma_bound;
    k->majorant = 0.0f;  /* no cell yet: the first call enters the first */
    k->t = 0.0f;
    k->t_exit = 0.0f;
    k->collisions = 0;
    return 1;
}

/* The next tentative collision, at k->t with rate k->majorant: 1; the walk's end: 0; past GRID_MAX_COLLISIONS: -1.
 * Each distance is drawn from *u, which then takes the chain's next number (state), so the caller's own decisions
 * read the uniforms that follow. */
inline int grid_next_collision(__global const float *spectra, GridTracking *k, float *u, uint *state)
{
    for (;;) {
        if (k->majorant > 0.0f) {
            k->t -= log(1.0f - *u) / k->majorant;
            *u = grid_random(state);
            if (k->t < k->t_exit) return ++k->collisions > GRID_MAX_COLLISIONS ? -1 : 1;
        }
        float t_enter, cell_density;
        if (!grid_walk_cell(spectra, &k->walk, &t_enter, &k->t_exit, &cell_density)) return 0;
        k->majorant = cell_density * k->sigma_bound;
        k->t = t_enter;
    }
}

/* One free flight through grid medium m from `origin` along unit `direction` toward the surface at t_surface, with
 * medium_sample_flight's contract (the flight's first distance from u_distance); `throughput`, the path's per
 * lane, weighs the collision probabilities. */
inline FreeFlight grid_sample_flight(__global const Medium *m, __global const float *spectra,
                                     const SampledWavelengths *w, float3 origin, float3 direction, float t_surface,
                                     int hero_only, float4 throughput, float u_lane, float u_distance)
{
    FreeFlight flight;
    flight.distance = t_surface;
    flight.scattered = 0;
    float4 lanes = hero_only ? (float4)(1.0f, 0.0f, 0.0f, 0.0f) : (float4)(1.0f);
    flight.weight = lanes;  /* lanes a dispersive event ended carry nothing, as in medium_sample_flight */
#if SCENE_HAS_MEDIUM_EMISSION
    flight.emitted = (float4)(0.0f);
#endif
    float4 sigma_s = medium_sigma_s(m, spectra, w) * lanes;
    float4 sigma_t = medium_sigma_t(m, spectra, w) * lanes;
    float sigma_bound = fmax(fmax(sigma_t.x, sigma_t.y), fmax(sigma_t.z, sigma_t.w));
    GridTracking k;
    if (!grid_tracking_start(spectra, m->grid, origin, direction, t_surface, sigma_bound, &k)) return flight;
    uint state = hash_u32(as_uint(u_lane) ^ hash_u32(as_uint(u_distance)));
    float u = u_distance;
    int found;
    while ((found = grid_next_collision(spectra, &k, &u, &state)) > 0) {
        float majorant = k.majorant, t = k.t;
        float4 albedo;
        float4 density = grid_density_albedo(spectra, m->grid, origin + t * direction, w->lambda, &albedo);
        float4 sigma_t_x = density * sigma_t;
        float4 sigma_s_x = density * albedo * sigma_s;
        float4 sigma_n_x = fmax((float4)(majorant) - sigma_t_x, (float4)(0.0f));
#if SCENE_HAS_MEDIUM_EMISSION
        if (m->emission >= 0) {
            /* before this collision's choice: the weight so far estimates the transmittance to it */
            float4 le = medium_emission_spectrum(m, spectra, w)
                      * grid_emission_factor(spectra, m->grid, origin + t * direction, w->lambda);
            flight.emitted += flight.weight * (sigma_t_x - sigma_s_x) * le / majorant;
        }
#endif
        float4 h = fabs(throughput * flight.weight);
        float scatter = dot(h, sigma_s_x), null = dot(h, sigma_n_x);
        if (!(scatter + null > 0.0f)) {
            flight.weight = (float4)(0.0f);
            return flight;
        }
        float p_scatter = scatter / (scatter + null);
        if (u < p_scatter) {
            flight.weight *= sigma_s_x / (majorant * p_scatter);
            flight.distance = t;
            flight.scattered = 1;
            return flight;
        }
        flight.weight *= sigma_n_x / (majorant * (1.0f - p_scatter));
        u = grid_random(&state);
    }
    if (found < 0) flight.weight = (float4)(0.0f);
    return flight;
}

/* The transmittance per lane of the stretch origin + t·direction, t in [0, length], through grid medium m, by ratio
 * tracking with random numbers from `seed`: an unbiased estimate of exp(−∫ σt). */
inline float4 grid_transmittance(__global const Medium *m, __global const float *spectra,
                                 const SampledWavelengths *w, float3 origin, float3 direction, float length,
                                 uint seed)
{
    float4 sigma_t = medium_sigma_t(m, spectra, w);
    float sigma_bound = fmax(fmax(sigma_t.x, sigma_t.y), fmax(sigma_t.z, sigma_t.w));
    GridTracking k;
    float4 transmittance = (float4)(1.0f);
    if (!grid_tracking_start(spectra, m->grid, origin, direction, length, sigma_bound, &k)) return transmittance;
    uint state = hash_u32(seed ^ 0x6a09e667U);
    float u = grid_random(&state);
    int found;
    while ((found = grid_next_collision(spectra, &k, &u, &state)) > 0) {
        float4 density = grid_density(spectra, m->grid, origin + k.t * direction, w->lambda);
        transmittance *= fmax((float4)(k.majorant) - density * sigma_t, (float4)(0.0f)) / k.majorant;
        if (all(transmittance == (float4)(0.0f))) return transmittance;
    }
    return found < 0 ? (float4)(0.0f) : transmittance;
}

/* scene_transmittance's stretch through grid medium `medium`: from `carried` before `origin` (cut-outs passed since
 * the last medium boundary) to `length` past it along unit `direction`; the shadow ray's query and the boundary
 * count seed the tracking. */
inline float4 grid_stretch(__global const Medium *media, __global const float *spectra, const SampledWavelengths *w,
                           int medium, float3 origin, float3 direction, float carried, float length, uint query,
                           int crossing)
{
    return grid_transmittance(&media[medium], spectra, w, origin - carried * direction, direction,
                              carried + fmax(length, 0.0f), hash_u32(query ^ hash_u32((uint)crossing)));
}

#endif
