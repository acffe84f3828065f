"""Scene-file text shared by tests that write small scenes: a camera and a tiny film, optionally a diffuse
material, to which a test appends its shapes and settings. Values are given as TOML text, so a test keeps the
exact literals (integers or floats) it always wrote."""


def camera_film(origin="[0, 0, 5]", target="[0, 0, 0]", fov="40", width="8", height="6", camera="") -> str:
    """The [camera] and [film] tables; `camera` is more of the camera's keys (`up`, `type`, ...), one a line.
    `fov` None leaves the key out (for a camera type that takes none, given in `camera`)."""
    fov_line = "" if fov is None else f"fov = {fov}\n"
    more = f"{camera.strip()}\n" if camera.strip() else ""
    return f"""
[camera]
origin = {origin}
target = {target}
{fov_line}{more}
[film]
width = {width}
height = {height}
"""


def diffuse(name="grey", reflectance="value = 0.5") -> str:
    """A diffuse material table; `reflectance` is the text inside its inline table."""
    return f"""
[materials.{name}]
type = "diffuse"
reflectance = {{ {reflectance} }}
"""


CAMERA_FILM_GREY = camera_film() + diffuse()


def emitting_screen(
    reflectance="value = 0", shape='type = "rectangle"', radiance="value = 1", extra="", width=8, height=8, fov=20
) -> str:
    """One emitting shape, black itself, filling a narrow camera's view: one bounce, 64 samples a pixel.
    `radiance` is the text inside the emitter's radiance table; `extra` follows the shape."""
    return (
        camera_film(origin="[0, 0, 3]", fov=fov, width=width, height=height)
        + f"""
[integrator]
max_depth = 1

[sampler]
spp = 64
{diffuse("black", reflectance)}
[[shapes]]
{shape}
material = "black"
emitter = {{ radiance = {{ {radiance} }} }}
{extra}"""
    )


def glowing_rectangle(width="8", height="6") -> str:
    """A grey rectangle that emits 1 everywhere, in front of the shared camera. The film comes first: tests that
    break this text expect their errors on the lines where they are now."""
    return f"""\
[film]
width = {width}
height = {height}

[camera]
origin = [0, 0, 5]
target = [0, 0, 0]
fov = 40
{diffuse()}
[[shapes]]
type = "rectangle"
material = "grey"
emitter = {{ radiance = {{ value = 1.0 }} }}
"""


def mitsuba_envmap_over_plate(image_file: str, reflectance_rgb: str, size: int) -> str:
    """A Mitsuba 3 scene: an orthographic camera looking down at a level diffuse plate (an `<rgb>` reflectance,
    "r, g, b") that fills its view, lit by the envmap `image_file` only. Mitsuba's map has its rows along local +y:
    turned so that they run down from the world's +z, each row a ring of equal elevation over the plate."""
    return f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="2"/></integrator>
<sensor type="orthographic">
  <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<emitter type="envmap"><string name="filename" value="{image_file}"/>
  <transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>
<shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="{reflectance_rgb}"/></bsdf></shape>
</scene>
"""
