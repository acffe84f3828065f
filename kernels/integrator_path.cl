/* Render-pass program of the `path` integrator (the global model). */
#include "path_tracer.cl"
#define TRACE_RADIANCE trace_path
#include "render_pass.cl"
