/* Render-pass program of the `direct` integrator (the local model). */
#include "whitted.cl"
#define TRACE_RADIANCE trace_direct
#include "render_pass.cl"
