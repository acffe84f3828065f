/* Render-pass program of the `path` integrator as a wavefront (kernels/wavefront_pass.cl); the megakernel is
 * integrator_path.cl. */
#include "path_tracer.cl"
#include "wavefront_pass.cl"
