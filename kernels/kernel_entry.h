/* How every kernel is declared: KERNEL in place of __kernel.
 *
 * Each work-item runs one path (or one query) as written, in scalar and float4 arithmetic. The vec_type_hint says
 * so (OpenCL C 1.2, 6.7.2): the kernel's own data is float4-wide. Intel's CPU compiler then leaves the kernel as it
 * is instead of vectorising it across work-items (its build log: "Kernel can't be vectorized due to unsupported vec
 * type hint"); other compilers may ignore the hint.
 *
 * Across work-items does not pay for these kernels: forced 16 wide, the Cornell box's render kernel grew from 2,831
 * to 59,097 instructions (1,668 gathers) and took 8x the CPU time per pass. Left to itself, the compiler keeps the
 * scene kernels scalar (same code with and without the hint) but vectorises the all-features kernels 8 wide, and
 * those rendered wrong images (the Cornell box 33 % too dark; analytic shapes' and instances' kernels too, wrong
 * shading normals at instanced hits), as did a BSDF test kernel once (pdf values in other work-items' slots); PoCL
 * is right on the same source. SPECTRACE_VECTORISE_ACROSS_ITEMS (set by the host from the environment variable of
 * that name, docs/devices.md) drops the hint to study that. */
#ifndef SPECTRACE_KERNEL_ENTRY_H
#define SPECTRACE_KERNEL_ENTRY_H

#ifdef SPECTRACE_VECTORISE_ACROSS_ITEMS
#define KERNEL __kernel
#else
#define KERNEL __kernel __attribute__((vec_type_hint(float4)))
#endif

#endif
