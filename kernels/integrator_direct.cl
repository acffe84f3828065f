/* Render-pass program of the `direct` integrator (the local model). */
#include "whitted.cl"
#define TRACE_RADIANCE trace_direct
#define TRACE_PATH_STATE trace_direct_state
#include "render_pass.cl"
