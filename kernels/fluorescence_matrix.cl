/* A fluorescent material given by a tabulated, non-separable re-radiation (Donaldson) matrix (host:
 * spectrace.spectral.donaldson, spectrace.materials.fluorescent): the re-emission part of the bispectral BSDF is
 *     f(λi → λo) = Q D(λi, λo) (λi / λo) / π
 * with D(λi, λo) photons re-emitted per nm of λo per photon arriving at λi (1/nm), bilinear between the matrix's
 * samples and 0 outside them, Q a factor (1, or a texture of the yield). Donaldson 1954 ("Spectrophotometry of
 * fluorescent pigments", Br. J. Appl. Phys. 5(6)) defined the matrix; Hullin et al. 2010 ("Fluorescent immersion
 * range scanning", ACM TOG 29(4)) render such measured matrices. The estimator is that of fluorescence.cl's separable
 * dye (Mojzík, Fichet and Wilkie 2018), with the emission's and the excitation's spectra replaced by the matrix's
 * column and row:
 *   camera path at λo: P = F / (1 + F), F = Q ∫ D(λi, λo) dλi; λi drawn ∝ D(·, λo); re-emission weight
 *                      Q D(λi, λo) (λi / λo) / (p(λi) P) on the hero (x4); elastic 1 / (1 − P) on every lane.
 *   light path at λi:  P = R / (1 + R), R = Q ∫ D(λi, λo) dλo; λo drawn ∝ D(λi, ·); weight as above over p(λo) P.
 * D at λo between columns j and j + 1 is (1 − t) D_j + t D_{j+1}: the draw picks column j with probability
 * ∝ (1 − t) F_j, j + 1 ∝ t F_{j+1}, then a 1 nm cell of that column by its CDF and a point uniform in it, so
 * p(λi) = ((1 − t) F_j p_j(λi) + t F_{j+1} p_{j+1}(λi)) / ((1 − t) F_j + t F_{j+1}), p_c the column's cell density;
 * rows likewise. p > 0 wherever D > 0, so the estimator is unbiased.
 *
 * The block in the spectra table (its offset in the Material row's ior_model; MATERIAL_NO_SPECTRUM for a separable
 * dye, which takes fluorescence.cl's own route), on the table's 1 nm grid, every number a float:
 *   [0] i0, [1] n_in, [2] j0, [3] n_out   the first grid index and the count of the rows (λi) and columns (λo)
 *   D            n_in × n_out, row-major (1/nm)
 *   R            n_in row integrals ∫ D dλo (photons re-emitted per photon arriving, ≤ 1)
 *   F            n_out column integrals ∫ D dλi (dimensionless)
 *   row CDFs     n_in × n_out, each row's cells over λo (0 to 1; all 0 for a row of zeros)
 *   column CDFs  n_out × n_in, each column's cells over λi
 * The integrals and CDFs are the trapezoid rule on the 1 nm cells, the cells' masses summing to them exactly. */
#ifndef SPECTRACE_FLUORESCENCE_MATRIX_CL
#define SPECTRACE_FLUORESCENCE_MATRIX_CL

#if SCENE_HAS_FLUORESCENCE_MATRIX

typedef struct {
    __global const float *d;        /* D, row-major */
    __global const float *rows;     /* R */
    __global const float *columns;  /* F */
    __global const float *row_cdf;
    __global const float *column_cdf;
    int i0, n_in, j0, n_out;
} DonaldsonMatrix;

inline DonaldsonMatrix donaldson_matrix(__global const float *table, int offset)
{
    __global const float *block = table + offset;
    DonaldsonMatrix dm;
    dm.i0 = (int)block[0];
    dm.n_in = (int)block[1];
    dm.j0 = (int)block[2];
    dm.n_out = (int)block[3];
    int cells = dm.n_in * dm.n_out;
    dm.d = block + 4;
    dm.rows = dm.d + cells;
    dm.columns = dm.rows + dm.n_in;
    dm.row_cdf = dm.columns + dm.n_out;
    dm.column_cdf = dm.row_cdf + cells;
    return dm;
}

/* The sample pair (k, k + 1) that x (a position in samples, 0 at the first) falls between and its fraction t, or 0
 * when x lies outside [0, count − 1]. */
inline int matrix_cell(float x, int count, int *k, float *t)
{
    if (!(x >= 0.0f && x <= (float)(count - 1))) return 0;
    *k = min((int)x, count - 2);
    *t = x - (float)*k;
    return 1;
}

/* The cell a uniform u falls in by `cdf` (count values, 0 to 1) and the point uniform within it (in samples from the
 * first); *mass the cell's mass, its density per sample (1 nm). */
inline float matrix_sample_cell(__global const float *cdf, int count, float u, float *mass)
{
    int lo = 0, hi = count - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    *mass = cdf[lo + 1] - cdf[lo];
    float t = *mass > 0.0f ? (u - cdf[lo]) / *mass : 0.5f;
    return (float)lo + clamp(t, 0.0f, 1.0f);
}

/* The draw along one axis between lines a and a + 1 (columns for a camera path, rows for a light path), blended by
 * t: a line by its weight (1 − t) total_a : t total_{a+1}, u rescaled, then a cell of it. Returns the position in
 * samples along the other axis; *pdf the blend's density there (1/nm). `cdfs` holds `count` values per line. */
inline float matrix_sample_between(__global const float *cdfs, int count, __global const float *totals, int a,
                                   float t, float u, float *pdf)
{
    float wa = (1.0f - t) * totals[a], wb = t * totals[a + 1];
    float pick_a = wa / (wa + wb);
    int line = a;
    if (u < pick_a) {
        u = u / pick_a;
    } else {
        line = a + 1;
        u = (u - pick_a) / (1.0f - pick_a);
    }
    float mass;
    float x = matrix_sample_cell(cdfs + line * count, count, min(u, 0x1.fffffep-1f), &mass);
    int cell = min((int)x, count - 2);
    float mass_a = cdfs[a * count + cell + 1] - cdfs[a * count + cell];
    float mass_b = cdfs[(a + 1) * count + cell + 1] - cdfs[(a + 1) * count + cell];
    *pdf = (wa * mass_a + wb * mass_b) / (wa + wb);
    return x;
}

/* D at row position x and column position y (in samples), both inside the matrix. */
inline float matrix_value(const DonaldsonMatrix *dm, float x, float y)
{
    int k = min((int)x, dm->n_in - 2), j = min((int)y, dm->n_out - 2);
    float s = x - (float)k, t = y - (float)j;
    __global const float *r = dm->d + k * dm->n_out + j;
    float upper = mad(t, r[1] - r[0], r[0]);
    float lower = mad(t, r[dm->n_out + 1] - r[dm->n_out], r[dm->n_out]);
    return mad(s, lower - upper, upper);
}

/* The odds of a re-emission at the matrix block at `offset` (fluorescence.cl's fluorescent_odds): at a camera path's
 * λo, Q times its column total F; at a light path's λi (light_side), Q times its row total R; 0 outside the matrix.
 * *line and *t the column or row below the wavelength and its fraction toward the next, which the draw reads. */
inline float fluorescent_matrix_odds(__global const float *table, int offset, float quantum_yield, float lambda,
                                     int light_side, int *line, float *t)
{
    DonaldsonMatrix dm = donaldson_matrix(table, offset);
    int first = light_side ? dm.i0 : dm.j0, count = light_side ? dm.n_in : dm.n_out;
    __global const float *totals = light_side ? dm.rows : dm.columns;
    if (!matrix_cell(lambda - GRID_MIN_NM - (float)first, count, line, t)) return 0.0f;
    return quantum_yield * mad(*t, totals[*line + 1] - totals[*line], totals[*line]);
}

/* The other wavelength (nm) of a re-emission chosen at (line, t) by fluorescent_matrix_odds, drawn with u: λi along
 * the column for a camera path, λo along the row for a light path. *pdf its density (1/nm), *value Q D(λi, λo). */
inline float fluorescent_matrix_draw(__global const float *table, int offset, float quantum_yield, int line, float t,
                                     int light_side, float u, float *pdf, float *value)
{
    DonaldsonMatrix dm = donaldson_matrix(table, offset);
    /* A row's CDF runs over λo (n_out values), a column's over λi (n_in values). */
    __global const float *cdfs = light_side ? dm.row_cdf : dm.column_cdf;
    __global const float *totals = light_side ? dm.rows : dm.columns;
    int count = light_side ? dm.n_out : dm.n_in, first = light_side ? dm.j0 : dm.i0;
    float drawn = matrix_sample_between(cdfs, count, totals, line, t, u, pdf);
    float along = (float)line + t;
    *value = quantum_yield * (light_side ? matrix_value(&dm, along, drawn) : matrix_value(&dm, drawn, along));
    return GRID_MIN_NM + (float)first + drawn;
}

#endif

#endif
