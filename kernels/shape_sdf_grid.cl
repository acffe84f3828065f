/* A signed-distance grid (Mitsuba 3's `sdfgrid` shape): samples f[z][y][x] at the corners of nx−1 × ny−1 × nz−1
 * voxels filling the unit cube of object space (sample (i, j, k) at (i/(nx−1), j/(ny−1), k/(nz−1))), placed by the
 * AnalyticShape's affine map. The surface is the zero set of the trilinear interpolant inside the voxels whose
 * corners take both signs (f ≥ 0 and f ≤ 0 among them), as Mitsuba 3 defines it; its geometric normal is the
 * interpolant's gradient (pointing to f > 0, the outside); its shading normal either that ("analytic") or the
 * gradients of the eight voxels around the nearest sample blended trilinearly ("smooth": Hansson-Söderlund, Evans,
 * Akenine-Möller, "Ray Tracing of Signed Distance Function Grids", JCGT 11(3), 2022, sec. 5, in Mitsuba 3's
 * variant: each voxel's gradient is the difference across the voxel of the interpolant on its two faces, at the
 * point's position along the other axes).
 *
 * Intersection: the ray is walked through the voxels it crosses (Amanatides & Woo, "A Fast Voxel Traversal
 * Algorithm for Ray Tracing", Eurographics 1987). Along the ray the interpolant of one voxel is a cubic in t
 * (Hansson-Söderlund et al. 2022, sec. 4.1); its first root in the voxel's stretch is bracketed between the roots of
 * its derivative, which split the stretch into monotonic pieces, and refined by Newton steps that fall back to
 * bisection whenever they leave the bracket (Marmitt, Kleer, Wald, Friedrich, "Fast and Accurate Ray-Voxel
 * Intersection Techniques for Iso-Surface Ray Tracing", VMV 2004). The value where the ray leaves a voxel is handed
 * on as the value where it enters the next one, so a root on a shared face is never lost between two voxels.
 *
 * Data: the row's `sphere` field holds, as int bits, in x the offset in floats from the row itself to its block in
 * the same buffer (after every row); the block is 4 int words (nx, ny, nz, smooth shading normals 1/0), then the
 * nx·ny·nz samples, x fastest. Hits: no texture coordinates (Mitsuba gives none), so Hit.b12 keeps the object-space
 * hit point instead, 20 bits an axis packed into two positive normal floats (sdf_grid_pack_point); its reconstruction
 * is within 5e-7 of the grid's extent, far below the ray offsets (ray.cl). Units: object space [0, 1]³; t in the
 * caller's units (the object-space direction is not renormalised). */
#ifndef SPECTRACE_SHAPE_SDF_GRID_CL
#define SPECTRACE_SHAPE_SDF_GRID_CL

#define SDF_GRID_POINT_STEPS 1048575.0f  /* 2²⁰ − 1: the packed point's steps per axis */
#define SDF_GRID_MAX_NEWTON 48

typedef struct {
    __global const float *samples;
    int nx, ny, nz;
    int smooth;    /* 1: the blended ("smooth") shading normal; 0: the interpolant's gradient */
    float3 cells;  /* voxels per axis: (nx − 1, ny − 1, nz − 1) */
} SdfGrid;

inline SdfGrid sdf_grid_of(__global const AnalyticShape *s)
{
    __global const float *block = (__global const float *)s + as_int(s->sphere.x);
    __global const int *header = (__global const int *)block;
    SdfGrid g;
    g.nx = header[0];
    g.ny = header[1];
    g.nz = header[2];
    g.smooth = header[3];
    g.samples = block + 4;
    g.cells = (float3)((float)(g.nx - 1), (float)(g.ny - 1), (float)(g.nz - 1));
    return g;
}

inline float sdf_grid_sample(const SdfGrid *g, int x, int y, int z)
{
    x = clamp(x, 0, g->nx - 1);
    y = clamp(y, 0, g->ny - 1);
    z = clamp(z, 0, g->nz - 1);
    return g->samples[(z * g->ny + y) * g->nx + x];
}

/* The eight corners of voxel (x, y, z), corner c at offset (c & 1, (c >> 1) & 1, c >> 2). */
inline void sdf_grid_corners(const SdfGrid *g, int x, int y, int z, float f[8])
{
    __global const float *base = g->samples + (z * g->ny + y) * g->nx + x;
    int row = g->nx, slab = g->nx * g->ny;
    f[0] = base[0];
    f[1] = base[1];
    f[2] = base[row];
    f[3] = base[row + 1];
    f[4] = base[slab];
    f[5] = base[slab + 1];
    f[6] = base[slab + row];
    f[7] = base[slab + row + 1];
}

/* The interpolant of a voxel written as k0 + k1 x + k2 y + k3 xy + k4 z + k5 xz + k6 yz + k7 xyz (local x, y, z in
 * [0, 1]). */
inline void sdf_grid_monomials(const float f[8], float k[8])
{
    k[0] = f[0];
    k[1] = f[1] - f[0];
    k[2] = f[2] - f[0];
    k[3] = f[3] - f[2] - f[1] + f[0];
    k[4] = f[4] - f[0];
    k[5] = f[5] - f[4] - f[1] + f[0];
    k[6] = f[6] - f[4] - f[2] + f[0];
    k[7] = f[7] - f[6] - f[5] + f[4] - f[3] + f[2] + f[1] - f[0];
}

inline float sdf_grid_trilinear(const float f[8], float3 w)
{
    float x00 = mix(f[0], f[1], w.x), x10 = mix(f[2], f[3], w.x);
    float x01 = mix(f[4], f[5], w.x), x11 = mix(f[6], f[7], w.x);
    return mix(mix(x00, x10, w.y), mix(x01, x11, w.y), w.z);
}

/* The interpolant's gradient in voxel units at local w. */
inline float3 sdf_grid_gradient(const float f[8], float3 w)
{
    float dx = mix(mix(f[1] - f[0], f[3] - f[2], w.y), mix(f[5] - f[4], f[7] - f[6], w.y), w.z);
    float dy = mix(mix(f[2] - f[0], f[3] - f[1], w.x), mix(f[6] - f[4], f[7] - f[5], w.x), w.z);
    float dz = mix(mix(f[4] - f[0], f[5] - f[1], w.x), mix(f[6] - f[2], f[7] - f[3], w.x), w.y);
    return (float3)(dx, dy, dz);
}

inline float sdf_grid_cubic(float4 c, float s)
{
    return fma(fma(fma(c.w, s, c.z), s, c.y), s, c.x);
}

/* The first root in [0, length] of the cubic c (c.x + c.y s + c.z s² + c.w s³) whose values at the ends are taken
 * to be f_start, f_end (the values the walk carries); -1 when its sign does not change there. */
inline float sdf_grid_first_root(float4 c, float span, float f_start, float f_end)
{
    /* The derivative's roots, c.y + 2 c.z s + 3 c.w s² = 0, ordered. */
    float a = 3.0f * c.w, b = 2.0f * c.z;
    float r0 = INFINITY, r1 = INFINITY;
    if (a != 0.0f) {
        float discriminant = b * b - 4.0f * a * c.y;
        if (discriminant >= 0.0f) {
            float q = -0.5f * (b + copysign(sqrt(discriminant), b));
            float s0 = q / a, s1 = q != 0.0f ? c.y / q : s0;
            r0 = fmin(s0, s1);
            r1 = fmax(s0, s1);
        }
    } else if (b != 0.0f) {
        r0 = -c.y / b;
    }
    float t_near = 0.0f, t_far = span, f_near = f_start, f_far = f_end;
    float splits[2] = {r0, r1};
    for (int k = 0; k < 2; ++k) {
        float r = splits[k];
        if (!(r > t_near && r < t_far)) continue;
        float f_r = sdf_grid_cubic(c, r);
        if (f_near * f_r <= 0.0f) {  /* the first piece holds a root: keep it */
            t_far = r;
            f_far = f_r;
            break;
        }
        t_near = r;
        f_near = f_r;
    }
    if (!(f_near * f_far <= 0.0f)) return -1.0f;
    if (f_near == 0.0f) return t_near;
    if (f_far == 0.0f) return t_far;
    float t = t_near + (t_far - t_near) * (f_near / (f_near - f_far));
    if (!(t >= t_near && t <= t_far)) t = 0.5f * (t_near + t_far);
    float tolerance = 1.0e-6f * span;
    for (int i = 0; i < SDF_GRID_MAX_NEWTON; ++i) {
        float f_t = sdf_grid_cubic(c, t);
        if (f_t == 0.0f) break;
        if ((f_t < 0.0f) == (f_near < 0.0f)) t_near = t; else t_far = t;
        float slope = fma(fma(3.0f * c.w, t, 2.0f * c.z), t, c.y);
        float next = t - f_t / slope;
        if (!(next > t_near && next < t_far)) next = 0.5f * (t_near + t_far);
        float step = fabs(next - t);
        t = next;
        if (!(step > tolerance)) break;
    }
    return t;
}

/* b12 of an object-space point of the unit cube: 20 bits an axis, z split over the two words; each word is offset
 * into the positive normal floats, so no runtime's handling of denormals or NaNs can touch it. */
inline float2 sdf_grid_pack_point(float3 p)
{
    uint3 q = convert_uint3_rte(clamp(p, 0.0f, 1.0f) * SDF_GRID_POINT_STEPS);
    uint x = q.x | ((q.z & 0x3FFu) << 20), y = q.y | ((q.z >> 10) << 20);
    return (float2)(as_float(x + 0x00800000u), as_float(y + 0x00800000u));
}

inline float3 sdf_grid_unpack_point(float2 b12)
{
    uint x = as_uint(b12.x) - 0x00800000u, y = as_uint(b12.y) - 0x00800000u;
    uint3 q = (uint3)(x & 0xFFFFFu, y & 0xFFFFFu, (x >> 20) | ((y >> 20) << 10));
    return convert_float3(q) * (1.0f / SDF_GRID_POINT_STEPS);
}

/* intersect_shape for an SDF grid. */
inline float intersect_sdf_grid(__global const AnalyticShape *s, float3 origin, float3 direction, float t_max,
                                float2 *uv)
{
    SdfGrid g = sdf_grid_of(s);
    /* The ray in grid units (one voxel a unit); t is unchanged. */
    float3 o = shape_point_to_object(s, origin) * g.cells;
    float3 d = shape_vector_to_object(s, direction) * g.cells;
    float3 inv = 1.0f / d;
    float3 ta = (0.0f - o) * inv, tb = (g.cells - o) * inv;
    /* A ray parallel to a slab: inside (NaN from 0 · ∞ on a face, counted as inside) or outside for good. */
    float3 lo = fmin(ta, tb), hi = fmax(ta, tb);
    lo = select(lo, (float3)(-INFINITY), isnan(lo));
    hi = select(hi, (float3)(INFINITY), isnan(hi));
    float t_enter = fmax(fmax(fmax(lo.x, lo.y), lo.z), 0.0f);
    float t_leave = fmin(fmin(fmin(hi.x, hi.y), hi.z), t_max);
    if (!(t_enter < t_leave)) return t_max;
    int3 last = (int3)(g.nx - 2, g.ny - 2, g.nz - 2);
    int3 cell = clamp(convert_int3_rtn(o + t_enter * d), (int3)(0), last);
    int3 step = (int3)(d.x >= 0.0f ? 1 : -1, d.y >= 0.0f ? 1 : -1, d.z >= 0.0f ? 1 : -1);
    float3 t_delta = fabs(inv);
    float3 next_face = convert_float3(cell + select((int3)(0), (int3)(1), step > 0));
    float3 t_next = (next_face - o) * inv;
    t_next = select(t_next, (float3)(INFINITY), isnan(t_next) || d == 0.0f);
    int carried = 0;
    float f_carried = 0.0f;
    int walked = g.nx + g.ny + g.nz;
    for (int visit = 0; visit < walked && t_enter < t_leave; ++visit) {
        float t_exit = fmin(fmin(fmin(t_next.x, t_next.y), t_next.z), t_leave);
        float f[8];
        sdf_grid_corners(&g, cell.x, cell.y, cell.z, f);
        int some_outside = 0, some_inside = 0;
        for (int c = 0; c < 8; ++c) {
            some_outside |= f[c] >= 0.0f;
            some_inside |= f[c] <= 0.0f;
        }
        if (some_outside && some_inside && t_exit > t_enter) {
            float k[8];
            sdf_grid_monomials(f, k);
            float3 w = o + t_enter * d - convert_float3(cell);  /* where the ray enters, in the voxel */
            float m3 = fma(k[7], w.z, k[3]), m5 = fma(k[5], w.z, k[1]), m6 = fma(k[6], w.z, k[2]);
            float4 cubic;
            cubic.x = fma(k[4], w.z, k[0]) + w.x * m5 + w.y * m6 + w.x * w.y * m3;
            cubic.y = d.x * m5 + d.y * m6 + (w.x * d.y + w.y * d.x) * m3
                    + d.z * (k[4] + k[5] * w.x + k[6] * w.y + k[7] * w.x * w.y);
            cubic.z = d.x * d.y * m3 + d.z * (k[5] * d.x + k[6] * d.y + k[7] * (w.x * d.y + w.y * d.x));
            cubic.w = k[7] * d.x * d.y * d.z;
            float span = t_exit - t_enter;
            float f_start = carried ? f_carried : cubic.x;
            float f_end = sdf_grid_trilinear(f, clamp(w + span * d, 0.0f, 1.0f));
            float s_root = sdf_grid_first_root(cubic, span, f_start, f_end);
            float t = t_enter + s_root;
            if (s_root >= 0.0f && t > 0.0f && t < t_max) {
                float3 within = clamp(w + s_root * d, 0.0f, 1.0f);
                *uv = sdf_grid_pack_point((convert_float3(cell) + within) / g.cells);
                return t;
            }
            carried = 1;
            f_carried = f_end;
        } else {
            carried = 0;
        }
        /* On to the neighbour across the face the ray leaves by. */
        t_enter = t_exit;
        if (t_next.x <= t_next.y && t_next.x <= t_next.z) {
            cell.x += step.x;
            t_next.x += t_delta.x;
            if (cell.x < 0 || cell.x > last.x) break;
        } else if (t_next.y <= t_next.z) {
            cell.y += step.y;
            t_next.y += t_delta.y;
            if (cell.y < 0 || cell.y > last.y) break;
        } else {
            cell.z += step.z;
            t_next.z += t_delta.z;
            if (cell.z < 0 || cell.z > last.z) break;
        }
    }
    return t_max;
}

/* The voxel holding object-space point p and p's place in it. */
inline int3 sdf_grid_cell(const SdfGrid *g, float3 p, float3 *w)
{
    float3 scaled = p * g->cells;
    int3 cell = clamp(convert_int3_rtn(scaled), (int3)(0), (int3)(g->nx - 2, g->ny - 2, g->nz - 2));
    *w = clamp(scaled - convert_float3(cell), 0.0f, 1.0f);
    return cell;
}

/* shape_surface's object-space part for an SDF grid at a hit's b12: the point and the interpolant's gradient (object
 * units); no texture coordinates, so no tangents. */
inline void sdf_grid_local(__global const AnalyticShape *s, float2 b12, float3 *point, float3 *n_local, float3 *dpdu,
                           float3 *dpdv)
{
    SdfGrid g = sdf_grid_of(s);
    float3 p = sdf_grid_unpack_point(b12), w;
    int3 cell = sdf_grid_cell(&g, p, &w);
    float f[8];
    sdf_grid_corners(&g, cell.x, cell.y, cell.z, f);
    *point = p;
    *n_local = sdf_grid_gradient(f, w) * g.cells;
    *dpdu = (float3)(0.0f);
    *dpdv = (float3)(0.0f);
}

/* The interpolant on the sample plane `plane` across `axis` at the point's position (cell + w) along the two
 * other axes. */
inline float sdf_grid_plane(const SdfGrid *g, int axis, int plane, int3 cell, float3 w)
{
    int3 i0 = cell;
    float u, v;
    int3 du, dv;
    if (axis == 0) {
        i0.x = plane;
        du = (int3)(0, 1, 0);
        dv = (int3)(0, 0, 1);
        u = w.y;
        v = w.z;
    } else if (axis == 1) {
        i0.y = plane;
        du = (int3)(0, 0, 1);
        dv = (int3)(1, 0, 0);
        u = w.z;
        v = w.x;
    } else {
        i0.z = plane;
        du = (int3)(1, 0, 0);
        dv = (int3)(0, 1, 0);
        u = w.x;
        v = w.y;
    }
    int3 i1 = i0 + du, i2 = i0 + dv, i3 = i0 + du + dv;
    float f0 = sdf_grid_sample(g, i0.x, i0.y, i0.z), f1 = sdf_grid_sample(g, i1.x, i1.y, i1.z);
    float f2 = sdf_grid_sample(g, i2.x, i2.y, i2.z), f3 = sdf_grid_sample(g, i3.x, i3.y, i3.z);
    return mix(mix(f0, f1, u), mix(f2, f3, u), v);
}

/* The object-space shading normal (not normalised to world space) at a hit's b12: the gradient with "analytic"
 * normals; with "smooth" ones, the normalised gradients of the 2 × 2 × 2 voxels around the sample nearest the point,
 * blended by the point's place between their centres (a voxel off the grid's lower end weighs nothing; one off its
 * upper end has no difference along that axis, the samples there being clamped). */
inline float3 sdf_grid_shading_local(__global const AnalyticShape *s, float2 b12)
{
    SdfGrid g = sdf_grid_of(s);
    float3 p = sdf_grid_unpack_point(b12), w;
    int3 cell = sdf_grid_cell(&g, p, &w);
    if (!g.smooth) {
        float f[8];
        sdf_grid_corners(&g, cell.x, cell.y, cell.z, f);
        return sdf_grid_gradient(f, w) * g.cells;
    }
    float3 scaled = p * g.cells;
    int3 low = convert_int3_rte(scaled) - 1;        /* the lower voxel of the block around the nearest sample */
    float3 blend = scaled - convert_float3(low) - 0.5f;
    float lower[3], upper[3];  /* each axis' difference in the block's lower and upper voxel, object units */
    float cells[3] = {g.cells.x, g.cells.y, g.cells.z};
    int cell_of[3] = {cell.x, cell.y, cell.z}, low_of[3] = {low.x, low.y, low.z};
    for (int axis = 0; axis < 3; ++axis) {
        int c = cell_of[axis];
        float g0 = sdf_grid_plane(&g, axis, c, cell, w), g1 = sdf_grid_plane(&g, axis, c + 1, cell, w);
        float across = g1 - g0;
        if (c != low_of[axis]) {  /* the point's voxel is the block's upper one along this axis */
            lower[axis] = (g0 - sdf_grid_plane(&g, axis, c - 1, cell, w)) * cells[axis];
            upper[axis] = across * cells[axis];
        } else {
            lower[axis] = across * cells[axis];
            upper[axis] = (sdf_grid_plane(&g, axis, c + 2, cell, w) - g1) * cells[axis];
        }
    }
    blend = select(blend, (float3)(1.0f), low < 0);
    float3 result = (float3)(0.0f);
    for (int corner = 0; corner < 8; ++corner) {
        int3 hi = (int3)(corner & 1, (corner >> 1) & 1, corner >> 2);
        if ((!hi.x && low.x < 0) || (!hi.y && low.y < 0) || (!hi.z && low.z < 0)) continue;
        float3 gradient = (float3)(hi.x ? upper[0] : lower[0], hi.y ? upper[1] : lower[1], hi.z ? upper[2] : lower[2]);
        float len = length(gradient);
        if (!(len > 0.0f)) continue;
        float weight = (hi.x ? blend.x : 1.0f - blend.x) * (hi.y ? blend.y : 1.0f - blend.y)
                     * (hi.z ? blend.z : 1.0f - blend.z);
        result += weight * (gradient / len);
    }
    return result;
}

#endif
