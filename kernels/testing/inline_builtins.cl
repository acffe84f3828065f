/* Test harness: the builtins kernels/pocl_inline_builtins.h replaces, on one item's inputs each. Built with and
 * without SPECTRACE_INLINE_BUILTINS, the same source calls PoCL's library or the header's twins; the outputs must
 * agree bit for bit (NaN payloads aside). Each item reads three float4 (x, y, z) and writes INLINE_BUILTIN_OUTPUTS
 * float4; integer results are written as their bits. */
#include "kernel_entry.h"

#define INLINE_BUILTIN_OUTPUTS 20

KERNEL void builtin_values(__global const float4 *xs, __global const float4 *ys, __global const float4 *zs,
                           __global float4 *out)
{
    int item = get_global_id(0);
    float4 x = xs[item], y = ys[item], z = zs[item];
    float3 x3 = x.xyz, y3 = y.xyz, z3 = z.xyz;
    float8 x8 = (float8)(x, y), y8 = (float8)(z, x), z8 = (float8)(y, z);
    __global float4 *o = out + (size_t)item * INLINE_BUILTIN_OUTPUTS;
    o[0] = (float4)(dot(x3, y3), dot(x, y), dot(x.xy, y.xy), dot(x.x, y.x));
    o[1] = (float4)(length(x3), distance(x3, y3), length(x), length(z.zw));
    o[2] = (float4)(normalize(x3), mad(x.x, y.x, z.x));
    o[3] = (float4)(normalize(y3 * 0x1p100f), sqrt(fabs(x.x)));
    o[4] = mad(x, y, z);
    o[5] = (float4)(mad(x3, y3, z3), sqrt(x.y));
    float8 m8 = mad(x8, y8, z8);
    o[6] = m8.lo;
    o[18] = m8.hi;
    o[7] = fmax(x, y);
    o[8] = fmin(x, y);
    o[9] = (float4)(fmax(x.x, y.x), fmin(x.x, y.x), clamp(x.x, y.x, z.x), clamp(x.y, z.y, y.y));
    o[10] = (float4)(clamp(x, y.x, z.x).xy, fmax(x.zw, y.z));
    o[11] = fmax(x8, y8).hi;
    o[19] = fmin(x8, z8).lo;
    o[12] = floor(x);
    o[13] = (float4)(fabs(x3), floor(y.x));
    o[14] = as_float4((int4)(isfinite(x.x), isinf(x.x), isfinite(y.y), isinf(z.z)));
    int4 xi = as_int4(x), yi = as_int4(y);
    o[15] = as_float4((int4)(any(xi), all(xi), any(xi.xyz), all((int8)(xi, yi))));
    o[16] = as_float4((int4)(any((int8)(xi, yi)), all(yi.xyz), any(xi.x), all(yi.xy)));
    o[17] = shuffle(x, as_uint4(y));
}
