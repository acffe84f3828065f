/* Render-pass program of the `path` integrator (the global model). */
#include "path_tracer.cl"
#define TRACE_RADIANCE trace_path
#define TRACE_PATH_STATE trace_path_state
#include "render_pass.cl"
