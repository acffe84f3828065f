"""Mitsuba's `null` bsdf, as exporters write it on the quads of area lights: a surface without material that every
ray crosses unchanged while its emitter still emits. spectrace keeps such a shape as a surface with no material (the
kernels cross it as they cross a medium's index-matched boundary) rather than dropping it for a light alone, so that
every integrator still meets the light where a path reaches it: the path tracer's MIS, BDPT's strategy that ends on
it, what the camera sees. Checked by the exact tables the import writes, and by rendering against Mitsuba 3's
volpath (whose shadow rays cross null surfaces, as spectrace's do; its `path` lets a null quad cast a shadow)."""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.scene.model import Scene
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32
QUAD = """<shape type="rectangle">
    <transform name="to_world"><scale x="0.8" y="0.5"/><rotate x="1" angle="90"/><translate z="0.5"/></transform>
    {bsdf}<emitter type="area"><rgb name="radiance" value="1.0, 0.8, 0.6"/></emitter></shape>"""
NULL = '<bsdf type="null"/>'
BLACK = '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'

# A lamp quad facing the camera in front of a wall, over a floor with a ball: the camera sees the quad's emission and
# the wall through it; a point light low beside the camera lights the wall through the quad (no shadow there).
SCENE = f"""<scene version="3.0.0">
  <integrator type="$integrator"><integer name="max_depth" value="6"/></integrator>
  <sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, -4, 0.5" target="0, 0, 0.3" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="90"/><translate y="2"/>
    </transform><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></shape>
  $quad
  <shape type="sphere"><float name="radius" value="0.4"/><point name="center" x="0.6" y="-0.8" z="-0.6"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf></shape>
  <emitter type="point"><point name="position" x="0.5" y="-3" z="0.8"/><rgb name="intensity" value="40, 40, 40"/>
  </emitter>
</scene>"""


def _xml(folder: Path, integrator: str, bsdf: str = NULL, name: str = "") -> Path:
    path = folder / f"{name or integrator}.xml"
    path.write_text(SCENE.replace("$integrator", integrator).replace("$quad", QUAD.format(bsdf=bsdf)))
    return path


def test_a_null_emitter_imports_as_a_shape_without_material(tmp_path):
    shapes = mitsuba_scene_data(_xml(tmp_path, "path"))[0]["shapes"]
    (quad,) = [shape for shape in shapes if "emitter" in shape]
    assert "material" not in quad
    assert quad["emitter"] == {"radiance": {"rgb": [1.0, 0.8, 0.6]}}
    scene = load_mitsuba_scene(_xml(tmp_path, "path"))
    (lamp,) = [shape for shape in scene.shapes if shape.emitter is not None]
    assert lamp.material is None and lamp.interior is None


def test_a_null_shape_that_neither_emits_nor_holds_a_medium_is_left_out_with_a_note(tmp_path):
    path = tmp_path / "hidden.xml"
    path.write_text(
        '<scene version="3.0.0"><sensor type="perspective"/><shape type="cube"><bsdf type="null"/></shape>'
        '<shape type="sphere"/></scene>'
    )
    data, notes = mitsuba_scene_data(path)
    assert [shape["type"] for shape in data["shapes"]] == ["sphere"]
    assert any("null bsdf is invisible: not imported" in note for note in notes), notes


def test_a_shape_without_material_needs_an_emitter_or_an_interior(tmp_path):
    lamp = spectrace.shape("rectangle", emitter=spectrace.area_emitter(1.0))
    assert lamp.material is None
    with pytest.raises(SpectraceError, match="only a shape with an interior or an emitter may omit it"):
        spectrace.shape("rectangle")
    toml = tmp_path / "scene.toml"
    toml.write_text(
        "[camera]\norigin = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 30\n[film]\nwidth = 4\nheight = 4\n"
        '[[shapes]]\ntype = "rectangle"\n'
    )
    with pytest.raises(SpectraceError, match="only a shape with an interior or an emitter may omit it"):
        spectrace.load_scene(toml)


def _lamp_square(integrator: str, material) -> Scene:
    """A square lamp facing the camera in front of a lit grey wall."""
    wall = spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 3}, {"translate": [0, 0, -1]}])
    lamp = spectrace.shape("rectangle", material, emitter=spectrace.area_emitter(2.0), transform=[{"scale": 0.5}])
    return Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=40.0),
        width=8,
        height=8,
        shapes=[wall, lamp],
        lights=[spectrace.point_light((0.3, 0.2, 2.0), intensity=8.0)],
        integrator=integrator,
        max_depth=4,
        spp=64,
    )


@pytest.mark.parametrize("integrator", ["path", "direct", "light", "bdpt", "sppm"])
def test_every_integrator_sees_the_wall_through_a_lamp_without_material(device, integrator):
    """The middle of the image looks at the lamp: without material it shows the lamp's radiance plus the lit wall
    behind it; with a black material, the radiance alone. The difference is the wall, as seen beside the lamp
    (the same wall, lit the same: the lamp's light on it is small at its centre and equal in both)."""

    def image(material) -> np.ndarray:
        renderer = Renderer(_lamp_square(integrator, material), device)
        renderer.render(spp=64)
        return renderer.image().xyz[..., 1].astype(np.float64)

    seen_through, opaque = image(None), image(spectrace.diffuse(0.0))
    centre = (slice(3, 5), slice(3, 5))
    assert seen_through[centre].mean() > opaque[centre].mean() * 1.05


@pytest.mark.peer
@pytest.mark.parametrize("integrator", ["path", "ptracer", "bdpt"])
@pytest.mark.slow
def test_a_null_emitter_renders_as_in_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral, integrator):
    """REPLICAS independent images from each renderer: 8 x 8-pixel block means, the image mean and the mean over the
    quad within 5 standard errors (tests/replica_agreement.py); every spectrace integrator against Mitsuba's
    volpath. The same quad with a black diffuse bsdf (Mitsuba's image of it differs: the wall is not seen through)
    disagrees, over the quad."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 64 if integrator == "ptracer" else 16, 8

    def mitsuba(bsdf: str, name: str) -> np.ndarray:
        scene = mi.load_file(str(_xml(tmp_path, "volpath", bsdf, name)))
        return np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])

    by_mitsuba, black_by_mitsuba = mitsuba(NULL, "null"), mitsuba(BLACK, "black")
    # The quad: where the wall seen through it makes Mitsuba's image brighter than with a black quad.
    gain = (by_mitsuba.mean(axis=0) - black_by_mitsuba.mean(axis=0)).sum(axis=-1)
    quad = gain > 0.5 * gain.max()
    assert quad.sum() >= 20 and gain[quad].mean() > 0.4
    scene = load_mitsuba_scene(_xml(tmp_path, integrator))
    ours = xyz_to_linear_srgb(spectrace_replicas(Renderer(scene, device), replicas, replica_spp))
    assert_replicas_agree(ours, by_mitsuba, block)
    assert_replicas_agree(ours, by_mitsuba, block, region=quad)
    black = load_mitsuba_scene(_xml(tmp_path, integrator, BLACK, f"{integrator}_black"))
    opaque = xyz_to_linear_srgb(spectrace_replicas(Renderer(black, device), replicas, replica_spp))
    with pytest.raises(AssertionError):
        assert_replicas_agree(opaque, by_mitsuba, block, region=quad)


@pytest.mark.peer
def test_a_lamp_without_material_exports_as_a_null_bsdf_and_renders_alike(tmp_path, device, mitsuba_scalar_spectral):
    """Exported to Mitsuba (volpath, for the path tracer), the lamp seen through renders as in spectrace: the mean
    film Y over four pixels the lamp covers within 5 standard errors (measured: 2.137 and 2.129, 1.7 apart)."""
    from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict

    mi = mitsuba_scalar_spectral
    scene = _lamp_square("path", None)
    entries = scene_to_mitsuba_dict(scene, tmp_path, spp=256)
    (lamp,) = [entry for entry in entries.values() if isinstance(entry, dict) and "emitter" in entry]
    assert lamp["bsdf"] == {"type": "null"}
    entries["integrator"] = {"type": "volpath", "max_depth": scene.max_depth}
    theirs = mitsuba_film_xyz(mi.render(mi.load_dict(entries), spp=256), mi)[..., 1].astype(np.float64)
    renderer = Renderer(scene, device)
    renderer.render(spp=256)
    ours = renderer.image().xyz[..., 1].astype(np.float64)
    centre = (slice(3, 5), slice(3, 5))  # the lamp covers these pixels whole
    a, b = ours[centre].ravel(), theirs[centre].ravel()
    standard_error = np.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)
    assert abs(a.mean() - b.mean()) <= 5 * standard_error, (a.mean(), b.mean(), standard_error)
    assert b.mean() > 2.05  # the lamp's Y is 2: Mitsuba sees the lit wall through it too
