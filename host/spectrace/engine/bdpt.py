"""Bidirectional path tracing on the host: what the `bdpt` integrator (kernels/bdpt.cl) refuses beyond the light
tracer's limits, and how many pixels share a light subpath. Its passes are the light tracer's
(spectrace.engine.light_tracer): every pixel sample writes its own pixel's estimate to that pixel's row and its
light-to-camera connections as splat records, which the host adds to the film in a fixed order (every pixel's own
estimate, then the records)."""

from spectrace.scene.model import Scene

# Subpaths live in fixed arrays in the kernel (kernels/bdpt.cl's BDPT_MAX_SEGMENTS).
BDPT_MAX_SEGMENTS = 16
# Consecutive pixels whose camera subpaths share one light subpath, a work-item each group (kernels/bdpt.cl's
# BDPT_PIXELS_PER_LIGHT_PATH), unless the scene sets integrator.pixels_per_light_path: where some path of light
# can reach the camera through a smooth or glossy surface or a medium (a caustic that mostly the light-to-camera
# strategy finds), and where every surface is diffuse and no medium fills a shape (the light-to-camera strategy
# then adds little that the others do not). Measured in docs/integrators.md ("Sharing light subpaths").
PIXELS_PER_LIGHT_PATH = 2
PIXELS_PER_LIGHT_PATH_DIFFUSE = 4


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


def only_diffuse(scene: Scene) -> bool:
    """Every surface of the scene (its instanced objects' too) is diffuse, and no medium fills a shape."""
    shapes = list(scene.shapes) + [shape for instance in scene.instances for shape in instance.object.shapes]
    return all(shape.material is not None and shape.material.is_diffuse and shape.interior is None for shape in shapes)


def pixels_per_light_path(scene: Scene) -> int:
    """Neighbouring pixels whose camera subpaths share one light subpath: the scene's integrator.pixels_per_light_path,
    else PIXELS_PER_LIGHT_PATH_DIFFUSE where only_diffuse, else PIXELS_PER_LIGHT_PATH."""
    if scene.pixels_per_light_path is not None:
        return int(scene.pixels_per_light_path)
    return PIXELS_PER_LIGHT_PATH_DIFFUSE if only_diffuse(scene) else PIXELS_PER_LIGHT_PATH
