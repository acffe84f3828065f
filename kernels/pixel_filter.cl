/* The pixel's reconstruction filter by filter importance sampling (Ernst et al. 2006, "Filter importance sampling";
 * pbrt-v4, 4th ed., 8.8.1): a pixel sample's position is drawn from the filter's own distribution around the
 * pixel's centre and carries the weight f / (p ∫f), so the film stays a plain per-pixel sum (no splatting into
 * neighbours, hence bit-identical however a render is split) and its expectation is the filtered image
 * ∫ f(x − c) L(x) dx / ∫ f. Every filter is separable, f(x, y) = f(x) f(y), as in Mitsuba 3 and pbrt-v4.
 *
 * - PIXEL_FILTER_BOX: uniform over the pixel (radius ½): the position is the pixel corner plus the 2D draw, as
 *   before filters existed, weight 1.
 * - PIXEL_FILTER_TENT: f(x) = max(0, 1 − |x|/r), inverted in closed form, weight 1.
 * - PIXEL_FILTER_GAUSSIAN: Mitsuba 3's windowed Gaussian, f(x) = max(0, exp(−x²/2σ²) − exp(−r²/2σ²)), r = 4σ.
 * - PIXEL_FILTER_MITCHELL: Mitchell & Netravali 1988, f(x) = k(2|x|/r) with their cubic k on [0, 2] (B, C).
 * The last two are drawn from a piecewise-constant density over PIXEL_FILTER_BINS bins of |f| on [0, r] (filter_cdf,
 * tabulated by spectrace.pixel_filters) and weighted by f / p exactly, so the table's coarseness costs variance,
 * never bias; Mitchell's negative lobes give negative weights. */
#ifndef SPECTRACE_PIXEL_FILTER_CL
#define SPECTRACE_PIXEL_FILTER_CL

#include "types.h"
#ifndef PIXEL_FILTER_TYPE_COUNT
#error "built without the pixel filters' generated sources (spectrace.plugins.generated_sources)"
#endif

/* Mitchell–Netravali's cubic k(x) for x = |offset| in [0, 2] filter units. */
inline float mitchell_1d(float x, float b, float c)
{
    if (x >= 2.0f) return 0.0f;
    float x2 = x * x, x3 = x2 * x;
    if (x < 1.0f)
        return ((12.0f - 9.0f * b - 6.0f * c) * x3 + (-18.0f + 12.0f * b + 6.0f * c) * x2 + (6.0f - 2.0f * b))
               * (1.0f / 6.0f);
    return ((-b - 6.0f * c) * x3 + (6.0f * b + 30.0f * c) * x2 + (-12.0f * b - 48.0f * c) * x + (8.0f * b + 24.0f * c))
           * (1.0f / 6.0f);
}

/* The tabulated filters' f at offset x (pixels). */
inline float tabulated_filter_eval(__global const RenderParams *p, float x)
{
    float radius = p->filter_shape.x;
    if (PIXEL_FILTER_IS(p, PIXEL_FILTER_GAUSSIAN))
        return fmax(0.0f, exp(p->filter_shape.z * x * x) - p->filter_shape.w);
    return mitchell_1d(2.0f * fabs(x) / radius, p->filter_shape.z, p->filter_shape.w);
}

/* One axis of a tabulated filter: an offset in [-radius, radius] from u in [0, 1), and its weight f / (p ∫f). */
inline float tabulated_filter_sample(__global const RenderParams *p, float u, float *weight)
{
    float radius = p->filter_shape.x;
    float side = u < 0.5f ? -1.0f : 1.0f;
    float v = fabs(2.0f * u - 1.0f);  /* uniform on [0, 1]: which side, then where on it */
    int bin = 0;
    while (bin < PIXEL_FILTER_BINS - 1 && !(v < p->filter_cdf[bin])) ++bin;
    float low = bin > 0 ? p->filter_cdf[bin - 1] : 0.0f;
    float mass = p->filter_cdf[bin] - low;
    float bin_width = radius / (float)PIXEL_FILTER_BINS;
    float t = mass > 0.0f ? clamp((v - low) / mass, 0.0f, 1.0f) : 0.5f;
    float x = side * ((float)bin + t) * bin_width;
    /* The density over [-radius, radius] is mass / (2 bin_width) in this bin. */
    *weight = mass > 0.0f ? tabulated_filter_eval(p, x) * (2.0f * bin_width / mass) * p->filter_shape.y : 0.0f;
    return x;
}

/* The film position (pixels) of a sample of pixel (x, y) from the 2D draw u, and the weight its radiance carries
 * (1 for box and tent). */
inline float2 pixel_filter_sample(__global const RenderParams *p, int pixel_x, int pixel_y, float2 u, float *weight)
{
    *weight = 1.0f;
    if (PIXEL_FILTER_IS(p, PIXEL_FILTER_TENT)) {
        float radius = p->filter_shape.x;
        float2 v = fabs(2.0f * u - 1.0f);
        float2 offset = radius * (1.0f - sqrt(1.0f - v));  /* |x| has density ∝ 1 − |x|/r */
        offset = select(offset, -offset, isless(u, (float2)(0.5f)));
        return (float2)((float)pixel_x + 0.5f, (float)pixel_y + 0.5f) + offset;
    }
    if (PIXEL_FILTER_IS(p, PIXEL_FILTER_GAUSSIAN) || PIXEL_FILTER_IS(p, PIXEL_FILTER_MITCHELL)) {
        float wx, wy;
        float2 offset = (float2)(tabulated_filter_sample(p, u.x, &wx), tabulated_filter_sample(p, u.y, &wy));
        *weight = wx * wy;
        return (float2)((float)pixel_x + 0.5f, (float)pixel_y + 0.5f) + offset;
    }
    return (float2)((float)pixel_x + u.x, (float)pixel_y + u.y);
}

#endif
