/* A 2-D density given by its values on a regular grid over the unit square and interpolated bilinearly, sampled
 * continuously and without seams: the row coordinate y from the marginal (the rows' integrals, joined linearly),
 * then x from the conditional (the two neighbouring rows' values, joined linearly at that y), each by inverting a
 * linear density on one cell in closed form; `invert` is the exact inverse of `sample`. This is the "continuous"
 * variant of Mitsuba 3's Marginal2D (include/mitsuba/core/distr_2d.h; Dupuy & Jakob 2018, sec. 5), whose inverse
 * map the RGL measured BSDFs are tabulated in: the sampled point's coordinates are that parameterisation.
 *
 * A table may depend on up to three parameters (a viewer's φ and θ, a wavelength), tabulated on increasing values:
 * its slices are joined linearly in each, clamped at the ends, the sampling tables as the values (a mixture of
 * normalised densities is sampled through the mixture of their integrals).
 *
 * Layout (spectrace.materials.measured._warp_tables), all in one float buffer, int fields at the same offsets as
 * floats: per slice, `data` height × width values (row-major, x the contiguous axis), `marginal` height − 1
 * running integrals of the rows' totals, `conditional` height × (width − 1) running integrals along each row; the
 * slices of parameter k follow one another with the product of the later parameters' counts as stride. Units: the
 * unit square's; a normalised table's values are a density on it. */
#ifndef SPECTRACE_WARP_BILINEAR_2D_CL
#define SPECTRACE_WARP_BILINEAR_2D_CL

#define WARP_MAX_PARAMETERS 3

/* Where a query's slices lie: `first` the lowest slice's index, stride[k] the distance to the next value of
 * parameter k (0 where it has one value) and w[k] the weight of that next value. */
typedef struct {
    int count;
    int first;
    int stride[WARP_MAX_PARAMETERS];
    float w[WARP_MAX_PARAMETERS];
} WarpSlices;

/* The slices of parameters `values` (count[k] increasing values at offset[k] of `buf`) at `at`. */
inline WarpSlices warp_slices(__global const float *buf, int n, const int *offset, const int *count, const float *at)
{
    WarpSlices s;
    s.count = n;
    s.first = 0;
    int stride = 1;
    for (int k = n - 1; k >= 0; --k) {
        s.stride[k] = count[k] > 1 ? stride : 0;
        s.w[k] = 0.0f;
        if (count[k] > 1) {
            /* The interval [v_i, v_i+1] holding `at`, i in [0, count − 2]. */
            __global const float *v = buf + offset[k];
            int lo = 0, hi = count[k] - 2;
            while (lo < hi) {
                int mid = (lo + hi + 1) >> 1;
                if (v[mid] < at[k]) lo = mid; else hi = mid - 1;
            }
            s.w[k] = clamp((at[k] - v[lo]) / (v[lo + 1] - v[lo]), 0.0f, 1.0f);
            s.first += lo * s.stride[k];
        }
        stride *= count[k];
    }
    return s;
}

/* A table that depends on no parameter. */
inline WarpSlices warp_no_slices(void)
{
    WarpSlices s;
    s.count = 0;
    s.first = 0;
    return s;
}

/* The value at index i of the table at `table` (slices of `slice_size` floats), joined across the slices. */
inline float warp_lookup(__global const float *buf, int table, int slice_size, const WarpSlices *s, int i)
{
    float sum = 0.0f;
    int corners = 1 << s->count;
    for (int c = 0; c < corners; ++c) {
        float weight = 1.0f;
        int index = table + s->first * slice_size + i;
        for (int k = 0; k < s->count; ++k) {
            int upper = (c >> k) & 1;
            weight *= upper ? s->w[k] : 1.0f - s->w[k];
            index += upper * s->stride[k] * slice_size;
        }
        if (weight != 0.0f) sum += weight * buf[index];
    }
    return sum;
}

/* A table of `width` × `height` values (and its sampling tables where it is sampled). */
typedef struct {
    int data, marginal, conditional;
    int width, height;
} WarpTable;

/* The bilinear interpolant at p ∈ [0, 1]². */
inline float warp_eval(__global const float *buf, const WarpTable *t, const WarpSlices *s, float2 p)
{
    p = clamp(p, 0.0f, 1.0f) * (float2)((float)(t->width - 1), (float)(t->height - 1));
    int x = min((int)p.x, t->width - 2), y = min((int)p.y, t->height - 2);
    p -= (float2)((float)x, (float)y);
    int size = t->width * t->height, i = y * t->width + x;
    float v00 = warp_lookup(buf, t->data, size, s, i), v10 = warp_lookup(buf, t->data, size, s, i + 1);
    float v01 = warp_lookup(buf, t->data, size, s, i + t->width);
    float v11 = warp_lookup(buf, t->data, size, s, i + t->width + 1);
    return mix(mix(v00, v10, p.x), mix(v01, v11, p.x), p.y);
}

/* The position in [0, 1] of a cell of `width` whose density runs linearly from v0 to v1 where its integral from
 * the cell's start reaches `mass`. */
inline float warp_sample_cell(float mass, float width, float v0, float v1)
{
    int sloped = fabs(v0 - v1) > 1e-4f * (v0 + v1);
    float t = 2.0f * mass / width;
    float divisor = sloped ? v0 - v1 : v0 + v1;
    if (sloped) t = v0 - sqrt(fmax(v0 * v0 + t * (v1 - v0), 0.0f));
    return divisor != 0.0f ? t / divisor : t;
}

/* The integral from a cell's start to t of the density running linearly from v0 to v1 over `width`. */
inline float warp_invert_cell(float t, float width, float v0, float v1)
{
    return t * mix(v0, v1, 0.5f * t) * width;
}

/* The point of a normalised table sampled by u ∈ [0, 1]², its density in *pdf. */
inline float2 warp_sample(__global const float *buf, const WarpTable *t, const WarpSlices *s, float2 u, float *pdf)
{
    int w = t->width, h = t->height;
    int n_marginal = h - 1, n_conditional = h * (w - 1), n_data = w * h;
    u = clamp(u, 0x1p-24f, 1.0f - 0x1p-24f);
    /* The row: the first whose running marginal reaches u.y. */
    int lo = 0, hi = n_marginal - 1;
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        if (warp_lookup(buf, t->marginal, n_marginal, s, mid) < u.y) lo = mid + 1; else hi = mid;
    }
    int row = lo;
    if (row > 0) u.y -= warp_lookup(buf, t->marginal, n_marginal, s, row - 1);
    int conditional = row * (w - 1);
    float r0 = warp_lookup(buf, t->conditional, n_conditional, s, conditional + w - 2);
    float r1 = warp_lookup(buf, t->conditional, n_conditional, s, conditional + 2 * (w - 1) - 1);
    float y = warp_sample_cell(u.y, 1.0f / (float)(h - 1), r0, r1);
    u.x *= mix(r0, r1, y);
    /* The column: the first whose running conditional, at y, reaches u.x. */
    lo = 0;
    hi = w - 2;
    while (lo < hi) {
        int mid = (lo + hi) >> 1;
        float c = mix(warp_lookup(buf, t->conditional, n_conditional, s, conditional + mid),
                      warp_lookup(buf, t->conditional, n_conditional, s, conditional + mid + w - 1), y);
        if (c < u.x) lo = mid + 1; else hi = mid;
    }
    int col = lo;
    if (col > 0)
        u.x -= mix(warp_lookup(buf, t->conditional, n_conditional, s, conditional + col - 1),
                   warp_lookup(buf, t->conditional, n_conditional, s, conditional + col - 1 + w - 1), y);
    int i = row * w + col;
    float v00 = warp_lookup(buf, t->data, n_data, s, i), v10 = warp_lookup(buf, t->data, n_data, s, i + 1);
    float v01 = warp_lookup(buf, t->data, n_data, s, i + w), v11 = warp_lookup(buf, t->data, n_data, s, i + w + 1);
    float c0 = mix(v00, v01, y), c1 = mix(v10, v11, y);
    float x = warp_sample_cell(u.x, 1.0f / (float)(w - 1), c0, c1);
    *pdf = mix(c0, c1, x);
    return (float2)(((float)col + x) / (float)(w - 1), ((float)row + y) / (float)(h - 1));
}

/* The u that warp_sample maps to p ∈ [0, 1]², the density at p in *pdf. */
inline float2 warp_invert(__global const float *buf, const WarpTable *t, const WarpSlices *s, float2 p, float *pdf)
{
    int w = t->width, h = t->height;
    int n_marginal = h - 1, n_conditional = h * (w - 1), n_data = w * h;
    p = clamp(p, 0.0f, 1.0f) * (float2)((float)(w - 1), (float)(h - 1));
    int col = min((int)p.x, w - 2), row = min((int)p.y, h - 2);
    p -= (float2)((float)col, (float)row);
    int i = row * w + col;
    float v00 = warp_lookup(buf, t->data, n_data, s, i), v10 = warp_lookup(buf, t->data, n_data, s, i + 1);
    float v01 = warp_lookup(buf, t->data, n_data, s, i + w), v11 = warp_lookup(buf, t->data, n_data, s, i + w + 1);
    float c0 = mix(v00, v01, p.y), c1 = mix(v10, v11, p.y);
    *pdf = mix(c0, c1, p.x);
    float ux = warp_invert_cell(p.x, 1.0f / (float)(w - 1), c0, c1);
    int conditional = row * (w - 1);
    if (col > 0)
        ux += mix(warp_lookup(buf, t->conditional, n_conditional, s, conditional + col - 1),
                  warp_lookup(buf, t->conditional, n_conditional, s, conditional + col - 1 + w - 1), p.y);
    float r0 = warp_lookup(buf, t->conditional, n_conditional, s, conditional + w - 2);
    float r1 = warp_lookup(buf, t->conditional, n_conditional, s, conditional + 2 * (w - 1) - 1);
    ux /= mix(r0, r1, p.y);
    float uy = warp_invert_cell(p.y, 1.0f / (float)(h - 1), r0, r1);
    if (row > 0) uy += warp_lookup(buf, t->marginal, n_marginal, s, row - 1);
    return (float2)(ux, uy);
}

#endif
