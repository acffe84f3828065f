/* How every kernel is declared: KERNEL in place of __kernel.
 *
 * Each work-item runs one path (or one query) as written, in scalar and float4 arithmetic. The vec_type_hint says
 * so (OpenCL C 1.2, 6.7.2): the kernel's own data is float4-wide. Intel's CPU compiler then leaves the kernel as it
 * is instead of vectorising it across work-items, which it has done wrongly here: a BSDF test kernel wrote pdf
 * values into other work-items' slots, and the all-features render kernels and textured analytic-shape scenes
 * rendered wrong images, all right with that vectoriser turned off and on PoCL. Other compilers may ignore the hint. */
#ifndef SPECTRACE_KERNEL_ENTRY_H
#define SPECTRACE_KERNEL_ENTRY_H

#define KERNEL __kernel __attribute__((vec_type_hint(float4)))

#endif
