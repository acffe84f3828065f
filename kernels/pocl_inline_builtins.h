/* Inline twins of the hot OpenCL builtins, for PoCL builds that cannot inline their own.
 *
 * Why: PoCL from PyPI (pocl-binary-distribution, a "distro" build) compiles kernels for the CPU LLVM names (znver3 on
 * a Zen 3) but links the kernel library variant it built for a family of CPUs (avx2: target-cpu haswell; avx512:
 * skylake-avx512). LLVM inlines a callee only when the caller's CPU implies every feature bit the callee's CPU does
 * (X86TTIImpl::areInlineCompatible), which neither pair meets, so every builtin call stays a call: dot, mad, fmax, any,
 * shuffle, length... took about a fifth of the CPU samples of a process rendering the Cornell box. The host builds
 * every program with SPECTRACE_INLINE_BUILTINS and this header first on that runtime only
 * (spectrace.device.builtin_inlining).
 *
 * Contract: same bits as PoCL's library. Each twin repeats the arithmetic of PoCL 3.0's kernel library as its bitcode
 * holds it (the .cl files of its lib/kernel folder, compiled without FP contraction), operation for operation and in
 * the same order:
 *   - mad(a, b, c) = a*b + c, rounded twice (not fused); dot = products summed as (x+y)+z, (x+y)+(z+w);
 *   - fmax(a, b) = (a > b or b is NaN) ? a : b, fmin likewise with <, clamp = fmin(fmax(x, lo), hi);
 *   - length, distance, normalize of float3 rescale by 2^86 below FLT_MIN and by 2^-65 (2^-66) at overflow, as PoCL;
 *   - fabs, floor, sqrt, isfinite, isinf, any, all, shuffle are exact (bit operations, or one correctly rounded op).
 * A NaN result may carry another NaN operand's payload: x86 returns the first of two NaN operands, and the compiler
 * orders a commutative operation as it likes, in PoCL's inlined library as here.
 * The products and sums are separate statements, so even a build that contracts within a statement keeps them
 * unfused. tests/device/test_inline_builtins.py compares every twin with the builtin on edge values, bit for bit
 * (NaN payloads aside).
 * Other types reach PoCL's own function (`_cl_<name>`: its headers rename each builtin to that, with a macro this
 * header replaces). cospi, sinpi and log stay calls: their polynomials are PoCL's to change.
 * Source: the OpenCL C 1.2 specification, 6.12 (the builtins' definitions). */
#ifndef SPECTRACE_POCL_INLINE_BUILTINS_H
#define SPECTRACE_POCL_INLINE_BUILTINS_H

/* Only PoCL renames its builtins; elsewhere (or unasked) this header is empty. */
#if defined(SPECTRACE_INLINE_BUILTINS) && defined(dot) && defined(mad) && defined(shuffle)

#define SPECTRACE_OVL static __attribute__((overloadable))

/* ---- mad: unfused, as PoCL's library ---- */
#define SPECTRACE_MAD(T)                                                                                            \
    SPECTRACE_OVL T spectrace_mad(T a, T b, T c) {                                                                  \
        T product = a * b;                                                                                          \
        return product + c;                                                                                         \
    }
SPECTRACE_MAD(float)
SPECTRACE_MAD(float2)
SPECTRACE_MAD(float3)
SPECTRACE_MAD(float4)
SPECTRACE_MAD(float8)
SPECTRACE_MAD(float16)
#undef mad
#define mad spectrace_mad

/* ---- fmax, fmin, clamp: the NaN in the second operand loses, as PoCL's ---- */
#define SPECTRACE_MINMAX(T)                                                                                      \
    SPECTRACE_OVL T spectrace_fmax(T a, T b) { return ((a > b) | (b != b)) ? a : b; }                               \
    SPECTRACE_OVL T spectrace_fmin(T a, T b) { return ((a < b) | (b != b)) ? a : b; }                               \
    SPECTRACE_OVL T spectrace_clamp(T x, T lo, T hi) { return spectrace_fmin(spectrace_fmax(x, lo), hi); }
#define SPECTRACE_MINMAX_SCALAR_BOUND(T)                                                                            \
    SPECTRACE_OVL T spectrace_fmax(T a, float b) { return spectrace_fmax(a, (T)(b)); }                              \
    SPECTRACE_OVL T spectrace_fmin(T a, float b) { return spectrace_fmin(a, (T)(b)); }                              \
    SPECTRACE_OVL T spectrace_clamp(T x, float lo, float hi) {                                                      \
        return spectrace_fmin(spectrace_fmax(x, (T)(lo)), (T)(hi));                                                 \
    }
SPECTRACE_MINMAX(float)
SPECTRACE_MINMAX(float2)
SPECTRACE_MINMAX(float3)
SPECTRACE_MINMAX(float4)
SPECTRACE_MINMAX(float8)
SPECTRACE_MINMAX(float16)
SPECTRACE_MINMAX_SCALAR_BOUND(float2)
SPECTRACE_MINMAX_SCALAR_BOUND(float3)
SPECTRACE_MINMAX_SCALAR_BOUND(float4)
SPECTRACE_MINMAX_SCALAR_BOUND(float8)
SPECTRACE_MINMAX_SCALAR_BOUND(float16)
/* clamp of integers is PoCL's */
#define SPECTRACE_CLAMP_FORWARD(T, S)                                                                               \
    SPECTRACE_OVL T spectrace_clamp(T x, T lo, T hi) { return _cl_clamp(x, lo, hi); }                               \
    SPECTRACE_OVL T spectrace_clamp(T x, S lo, S hi) { return _cl_clamp(x, lo, hi); }
#define SPECTRACE_CLAMP_FORWARD_ALL(S)                                                                              \
    SPECTRACE_OVL S spectrace_clamp(S x, S lo, S hi) { return _cl_clamp(x, lo, hi); }                               \
    SPECTRACE_CLAMP_FORWARD(S##2, S)                                                                                \
    SPECTRACE_CLAMP_FORWARD(S##3, S)                                                                                \
    SPECTRACE_CLAMP_FORWARD(S##4, S)                                                                                \
    SPECTRACE_CLAMP_FORWARD(S##8, S)                                                                                \
    SPECTRACE_CLAMP_FORWARD(S##16, S)
SPECTRACE_CLAMP_FORWARD_ALL(char)
SPECTRACE_CLAMP_FORWARD_ALL(uchar)
SPECTRACE_CLAMP_FORWARD_ALL(short)
SPECTRACE_CLAMP_FORWARD_ALL(ushort)
SPECTRACE_CLAMP_FORWARD_ALL(int)
SPECTRACE_CLAMP_FORWARD_ALL(uint)
SPECTRACE_CLAMP_FORWARD_ALL(long)
SPECTRACE_CLAMP_FORWARD_ALL(ulong)
#undef fmax
#define fmax spectrace_fmax
#undef fmin
#define fmin spectrace_fmin
#undef clamp
#define clamp spectrace_clamp

/* ---- exact single operations ---- */
#define SPECTRACE_EXACT(T, U)                                                                                       \
    SPECTRACE_OVL T spectrace_fabs(T x) { return as_##T(as_##U(x) & (U)(0x7fffffffu)); }
SPECTRACE_EXACT(float, uint)
SPECTRACE_EXACT(float2, uint2)
SPECTRACE_EXACT(float3, uint3)
SPECTRACE_EXACT(float4, uint4)
SPECTRACE_EXACT(float8, uint8)
SPECTRACE_EXACT(float16, uint16)
#undef fabs
#define fabs spectrace_fabs

SPECTRACE_OVL float spectrace_sqrt(float x) { return __builtin_sqrtf(x); }
#define SPECTRACE_SQRT_FORWARD(T)                                                                                   \
    SPECTRACE_OVL T spectrace_sqrt(T x) { return _cl_sqrt(x); }
SPECTRACE_SQRT_FORWARD(float2)
SPECTRACE_SQRT_FORWARD(float3)
SPECTRACE_SQRT_FORWARD(float4)
SPECTRACE_SQRT_FORWARD(float8)
SPECTRACE_SQRT_FORWARD(float16)
#undef sqrt
#define sqrt spectrace_sqrt

SPECTRACE_OVL float spectrace_floor(float x) { return __builtin_floorf(x); }
SPECTRACE_OVL float2 spectrace_floor(float2 x) { return (float2)(__builtin_floorf(x.x), __builtin_floorf(x.y)); }
SPECTRACE_OVL float3 spectrace_floor(float3 x) {
    return (float3)(__builtin_floorf(x.x), __builtin_floorf(x.y), __builtin_floorf(x.z));
}
SPECTRACE_OVL float4 spectrace_floor(float4 x) {
    return (float4)(__builtin_floorf(x.x), __builtin_floorf(x.y), __builtin_floorf(x.z), __builtin_floorf(x.w));
}
SPECTRACE_OVL float8 spectrace_floor(float8 x) { return (float8)(spectrace_floor(x.lo), spectrace_floor(x.hi)); }
SPECTRACE_OVL float16 spectrace_floor(float16 x) { return (float16)(spectrace_floor(x.lo), spectrace_floor(x.hi)); }
#undef floor
#define floor spectrace_floor

SPECTRACE_OVL int spectrace_isfinite(float x) { return (as_uint(x) << 1) < 0xff000000u; }
SPECTRACE_OVL int spectrace_isinf(float x) { return (as_uint(x) & 0x7fffffffu) == 0x7f800000u; }
#define SPECTRACE_CLASSIFY_FORWARD(T, I)                                                                            \
    SPECTRACE_OVL I spectrace_isfinite(T x) { return _cl_isfinite(x); }                                             \
    SPECTRACE_OVL I spectrace_isinf(T x) { return _cl_isinf(x); }
SPECTRACE_CLASSIFY_FORWARD(float2, int2)
SPECTRACE_CLASSIFY_FORWARD(float3, int3)
SPECTRACE_CLASSIFY_FORWARD(float4, int4)
SPECTRACE_CLASSIFY_FORWARD(float8, int8)
SPECTRACE_CLASSIFY_FORWARD(float16, int16)
#undef isfinite
#define isfinite spectrace_isfinite
#undef isinf
#define isinf spectrace_isinf

/* ---- any, all: the sign bit of any (every) component; an OR (AND) of the components keeps it ---- */
#define SPECTRACE_ANY_ALL(S)                                                                                        \
    SPECTRACE_OVL int spectrace_any(S x) { return x < 0; }                                                          \
    SPECTRACE_OVL int spectrace_all(S x) { return x < 0; }                                                          \
    SPECTRACE_OVL int spectrace_any(S##2 x) { return (x.x | x.y) < 0; }                                             \
    SPECTRACE_OVL int spectrace_all(S##2 x) { return (x.x & x.y) < 0; }                                             \
    SPECTRACE_OVL int spectrace_any(S##3 x) { return (x.x | x.y | x.z) < 0; }                                       \
    SPECTRACE_OVL int spectrace_all(S##3 x) { return (x.x & x.y & x.z) < 0; }                                       \
    SPECTRACE_OVL int spectrace_any(S##4 x) { return spectrace_any(x.lo | x.hi); }                                  \
    SPECTRACE_OVL int spectrace_all(S##4 x) { return spectrace_all(x.lo & x.hi); }                                  \
    SPECTRACE_OVL int spectrace_any(S##8 x) { return spectrace_any(x.lo | x.hi); }                                  \
    SPECTRACE_OVL int spectrace_all(S##8 x) { return spectrace_all(x.lo & x.hi); }                                  \
    SPECTRACE_OVL int spectrace_any(S##16 x) { return spectrace_any(x.lo | x.hi); }                                 \
    SPECTRACE_OVL int spectrace_all(S##16 x) { return spectrace_all(x.lo & x.hi); }
SPECTRACE_ANY_ALL(char)
SPECTRACE_ANY_ALL(short)
SPECTRACE_ANY_ALL(int)
SPECTRACE_ANY_ALL(long)
#undef any
#define any spectrace_any
#undef all
#define all spectrace_all

/* ---- shuffle: float4 by a uint4 mask is the triangle test's; the other types are PoCL's ---- */
SPECTRACE_OVL float4 spectrace_shuffle(float4 x, uint4 mask) {
    return (float4)(x[mask.x & 3u], x[mask.y & 3u], x[mask.z & 3u], x[mask.w & 3u]);
}
#define SPECTRACE_SHUFFLE_FORWARD(T, M) \
    SPECTRACE_OVL T spectrace_shuffle(T x, M mask) { return _cl_shuffle(x, mask); }
#define SPECTRACE_SHUFFLE_FORWARD_N(T, M, N)                                                                        \
    SPECTRACE_OVL T##N spectrace_shuffle(T##2 x, M##N mask) { return _cl_shuffle(x, mask); }                        \
    SPECTRACE_OVL T##N spectrace_shuffle(T##4 x, M##N mask) { return _cl_shuffle(x, mask); }                        \
    SPECTRACE_OVL T##N spectrace_shuffle(T##8 x, M##N mask) { return _cl_shuffle(x, mask); }                        \
    SPECTRACE_OVL T##N spectrace_shuffle(T##16 x, M##N mask) { return _cl_shuffle(x, mask); }
#define SPECTRACE_SHUFFLE_FORWARD_ALL(T, M)                                                                         \
    SPECTRACE_SHUFFLE_FORWARD_N(T, M, 2)                                                                            \
    SPECTRACE_SHUFFLE_FORWARD_N(T, M, 8)                                                                            \
    SPECTRACE_SHUFFLE_FORWARD_N(T, M, 16)                                                                           \
    SPECTRACE_OVL T##4 spectrace_shuffle(T##2 x, M##4 mask) { return _cl_shuffle(x, mask); }                        \
    SPECTRACE_OVL T##4 spectrace_shuffle(T##8 x, M##4 mask) { return _cl_shuffle(x, mask); }                        \
    SPECTRACE_OVL T##4 spectrace_shuffle(T##16 x, M##4 mask) { return _cl_shuffle(x, mask); }
SPECTRACE_SHUFFLE_FORWARD_ALL(char, uchar)
SPECTRACE_SHUFFLE_FORWARD_ALL(uchar, uchar)
SPECTRACE_SHUFFLE_FORWARD_ALL(short, ushort)
SPECTRACE_SHUFFLE_FORWARD_ALL(ushort, ushort)
SPECTRACE_SHUFFLE_FORWARD_ALL(int, uint)
SPECTRACE_SHUFFLE_FORWARD_ALL(uint, uint)
SPECTRACE_SHUFFLE_FORWARD_ALL(long, ulong)
SPECTRACE_SHUFFLE_FORWARD_ALL(ulong, ulong)
SPECTRACE_SHUFFLE_FORWARD_ALL(float, uint)
SPECTRACE_SHUFFLE_FORWARD(char4, uchar4)
SPECTRACE_SHUFFLE_FORWARD(uchar4, uchar4)
SPECTRACE_SHUFFLE_FORWARD(short4, ushort4)
SPECTRACE_SHUFFLE_FORWARD(ushort4, ushort4)
SPECTRACE_SHUFFLE_FORWARD(int4, uint4)
SPECTRACE_SHUFFLE_FORWARD(uint4, uint4)
SPECTRACE_SHUFFLE_FORWARD(long4, ulong4)
SPECTRACE_SHUFFLE_FORWARD(ulong4, ulong4)
#undef shuffle
#define shuffle spectrace_shuffle

/* ---- dot, length, distance, normalize: PoCL's sums and rescaling ---- */
SPECTRACE_OVL float spectrace_dot(float a, float b) { return a * b; }
SPECTRACE_OVL float spectrace_dot(float2 a, float2 b) {
    float2 m = a * b;
    return m.x + m.y;
}
SPECTRACE_OVL float spectrace_dot(float3 a, float3 b) {
    float3 m = a * b;
    float xy = m.x + m.y;
    return m.z + xy;
}
SPECTRACE_OVL float spectrace_dot(float4 a, float4 b) {
    float4 m = a * b;
    float xy = m.x + m.y;
    float zw = m.z + m.w;
    return xy + zw;
}
#undef dot
#define dot spectrace_dot

SPECTRACE_OVL float spectrace_length(float3 v) {
    float s = spectrace_dot(v, v);
    if (s < 0x1p-126f) {
        float3 w = v * 0x1p86f;
        return __builtin_sqrtf(spectrace_dot(w, w)) * 0x1p-86f;
    }
    if (s == INFINITY) {
        float3 w = v * 0x1p-65f;
        return __builtin_sqrtf(spectrace_dot(w, w)) * 0x1p65f;
    }
    return __builtin_sqrtf(s);
}
#define SPECTRACE_LENGTH_FORWARD(T)                                                                                 \
    SPECTRACE_OVL float spectrace_length(T v) { return _cl_length(v); }                                             \
    SPECTRACE_OVL float spectrace_distance(T a, T b) { return _cl_distance(a, b); }                                 \
    SPECTRACE_OVL T spectrace_normalize(T v) { return _cl_normalize(v); }
SPECTRACE_LENGTH_FORWARD(float)
SPECTRACE_LENGTH_FORWARD(float2)
SPECTRACE_LENGTH_FORWARD(float4)

SPECTRACE_OVL float spectrace_distance(float3 a, float3 b) { return spectrace_length(a - b); }

SPECTRACE_OVL float3 spectrace_normalize(float3 v) {
    if (v.x == 0.0f && v.y == 0.0f && v.z == 0.0f) return v;
    float s = spectrace_dot(v, v);
    float3 w = v;
    if (s < 0x1p-126f) {
        w = v * 0x1p86f;
        s = spectrace_dot(w, w);
    } else if (s == INFINITY) {
        w = v * 0x1p-66f;
        s = spectrace_dot(w, w);
        if (s == INFINITY) {
            /* only the infinite components remain, as ±1 */
            int3 infinite = (as_int3(w) & 0x7fffffff) == 0x7f800000;
            uint3 unit = as_uint3(infinite ? (float3)(1.0f) : (float3)(0.0f));
            w = as_float3(unit | (as_uint3(w) & 0x80000000u));
            s = spectrace_dot(w, w);
        }
    }
    float inverse = 1.0f / __builtin_sqrtf(s);
    return w * inverse;
}
#undef length
#define length spectrace_length
#undef distance
#define distance spectrace_distance
#undef normalize
#define normalize spectrace_normalize

#undef SPECTRACE_OVL

#endif
#endif
