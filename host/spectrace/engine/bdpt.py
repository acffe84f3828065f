"""Bidirectional path tracing on the host: what the `bdpt` integrator (kernels/bdpt.cl) refuses beyond the light
tracer's limits. Its passes are the light tracer's (spectrace.engine.light_tracer): every pixel sample writes its
own pixel's estimate to that pixel's row and its light-to-camera connections as splat records, which the host adds
to the film in a fixed order (every pixel's own estimate, then the records)."""

from spectrace.scene.model import Scene

# Subpaths live in fixed arrays in the kernel (kernels/bdpt.cl's BDPT_MAX_SEGMENTS).
BDPT_MAX_SEGMENTS = 16
# Consecutive pixels whose camera subpaths share one light subpath: a work-item each (kernels/bdpt.cl's
# BDPT_PIXELS_PER_LIGHT_PATH).
BDPT_PIXELS_PER_LIGHT_PATH = 2


def bdpt_problem(scene: Scene) -> str | None:
    """Why the bidirectional path tracer cannot render this scene, or None (the light tracer's checks come first)."""
    if scene.max_depth < 0 or scene.max_depth > BDPT_MAX_SEGMENTS:
        return (
            f"integrator 'bdpt' keeps paths of at most {BDPT_MAX_SEGMENTS} segments: "
            f"set integrator.max_depth between 1 and {BDPT_MAX_SEGMENTS}, not {scene.max_depth}"
        )
    if scene.camera.type == "equirectangular":
        # Its importance is over the sphere of directions: kernels/bdpt.cl's eye vertex and MIS densities are the
        # film-plane cameras'.
        return "integrator 'bdpt' supports the perspective, thinlens and orthographic cameras, not 'equirectangular'"
    return None
