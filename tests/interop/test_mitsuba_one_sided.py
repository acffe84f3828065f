"""One-sided reflection: Mitsuba 3's reflecting BSDFs are black from the back of the surface unless wrapped in
`twosided`, and the importer gives their materials `two_sided = false`. Checked two ways: the back of a one-sided
material is exactly black in every integrator while its front keeps the two-sided material's bits (a closed form:
the flag changes nothing on the front), and a scene of back faces renders as Mitsuba 3 renders the same XML. Which
side is the front: the vertex normals' where a mesh has them (Mitsuba's shading frame), whatever the winding."""

import numpy as np
import pytest

import spectrace
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.geometry import primitives
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.scene.model import Scene
from spectrace.spectral import xyz_to_linear_srgb

SIZE = 32

# Four rectangles side by side facing away from the camera (flip_normals: their fronts face -z) in front of a wall,
# lit by a point light on the camera's side: Mitsuba sees the backs of the plain diffuse, rough conductor and rough
# plastic black, and the `twosided` diffuse lit. The wall is plain diffuse facing the camera.
SCENE = f"""<scene version="3.0.0">
  <integrator type="$integrator"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="6"/><translate z="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
  <shape type="rectangle"><boolean name="flip_normals" value="$flip"/>
    <transform name="to_world"><scale x="0.45" y="1.2"/><translate x="-1.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf></shape>
  <shape type="rectangle"><boolean name="flip_normals" value="$flip"/>
    <transform name="to_world"><scale x="0.45" y="1.2"/><translate x="-0.5"/></transform>
    <bsdf type="roughconductor"><string name="material" value="Au"/><float name="alpha" value="0.3"/></bsdf></shape>
  <shape type="rectangle"><boolean name="flip_normals" value="$flip"/>
    <transform name="to_world"><scale x="0.45" y="1.2"/><translate x="0.5"/></transform>
    <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.7"/>
      <float name="alpha" value="0.2"/></bsdf></shape>
  <shape type="rectangle"><boolean name="flip_normals" value="$flip"/>
    <transform name="to_world"><scale x="0.45" y="1.2"/><translate x="1.5"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.7, 0.3"/></bsdf></bsdf></shape>
  <emitter type="point"><point name="position" x="0.3" y="0.8" z="3"/><rgb name="intensity" value="6, 5, 4"/>
  </emitter>
</scene>"""


def _xml(tmp_path, integrator: str, flip: bool = True):
    path = tmp_path / f"{integrator}_{flip}.xml"
    path.write_text(SCENE.replace("$integrator", integrator).replace("$flip", "true" if flip else "false"))
    return path


def test_reflecting_bsdfs_outside_twosided_import_one_sided(tmp_path):
    data, _ = mitsuba_scene_data(_xml(tmp_path, "path"))
    sides = sorted((table["type"], table.get("two_sided", True)) for table in data["materials"].values())
    assert sides == [
        ("conductor", False),
        ("diffuse", False),
        ("diffuse", False),
        ("diffuse", True),
        ("plastic", False),
    ]
    glass = tmp_path / "glass.xml"
    glass.write_text(
        '<scene version="3.0.0"><sensor type="perspective"/>'
        '<shape type="rectangle"><bsdf type="roughdielectric"/></shape>'
        '<shape type="rectangle"><bsdf type="thindielectric"/></shape></scene>'
    )
    tables = mitsuba_scene_data(glass)[0]["materials"].values()
    assert sorted(t["type"] for t in tables) == ["dielectric", "thindielectric"]
    assert not any("two_sided" in t for t in tables)  # transmitting BSDFs have two sides by nature


def _square_scene(material, integrator: str, facing_camera: bool) -> Scene:
    """A square of `material` seen head-on, front or back toward the camera, lit by a point light beside the
    camera (so the lit side is the seen side)."""
    square = spectrace.shape(
        "rectangle", material, transform=[] if facing_camera else [{"rotate": {"axis": [0, 1, 0], "angle": 180}}]
    )
    return Scene(
        camera=spectrace.Camera(origin=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), fov_degrees=30.0),
        width=8,
        height=8,
        shapes=[square],
        lights=[spectrace.point_light((0.5, 0.5, 2.0), intensity=10.0)],
        integrator=integrator,
        max_depth=3,
        spp=4,
    )


@pytest.mark.parametrize("integrator", ["path", "direct", "light", "bdpt"])
@pytest.mark.parametrize(
    "make",
    [lambda s: spectrace.diffuse(0.5, two_sided=s), lambda s: spectrace.plastic(0.5, roughness=0.2, two_sided=s)],
)
def test_one_sided_back_is_black_and_front_unchanged(device, integrator, make):
    def image(two_sided: bool, facing: bool) -> np.ndarray:
        renderer = Renderer(_square_scene(make(two_sided), integrator, facing), device)
        renderer.render(spp=4)
        return renderer.image().xyz

    front = image(True, True)
    assert front[..., 1].mean() > 0.01
    np.testing.assert_array_equal(image(False, True), front)
    assert image(True, False)[..., 1].mean() > 0.01  # a two-sided back is lit ...
    assert np.all(image(False, False) == 0.0)  # ... a one-sided one black


def test_a_transmitting_material_ignores_two_sided(device):
    def image(two_sided: bool) -> np.ndarray:
        renderer = Renderer(_square_scene(spectrace.dielectric(1.5, two_sided=two_sided), "path", False), device)
        renderer.render(spp=4)
        return renderer.image().xyz

    np.testing.assert_array_equal(image(False), image(True))


@pytest.mark.peer
@pytest.mark.slow
@pytest.mark.parametrize("integrator, theirs", [("path", "path"), ("ptracer", "ptracer"), ("bdpt", "path")])
def test_back_faces_render_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral, integrator, theirs):
    """REPLICAS independent images from each renderer: 8 x 8-pixel block means and the image mean within 5 standard
    errors (tests/replica_agreement.py). BDPT (Mitsuba 3 has none) is compared with Mitsuba's path tracer. The same
    scene with every material two-sided disagrees with Mitsuba's image (the comparison sees the backs)."""
    mi = mitsuba_scalar_spectral
    # The light tracers' images are the noisier: more samples keep the image mean's power under 5 %.
    replicas, replica_spp, block = 8, 128 if integrator == "ptracer" else 8, 8
    by_mitsuba = np.stack(
        [
            np.array(mi.render(mi.load_file(str(_xml(tmp_path, theirs))), spp=replica_spp, seed=seed))
            for seed in range(replicas)
        ]
    )
    scene = load_mitsuba_scene(_xml(tmp_path, integrator))
    ours = xyz_to_linear_srgb(spectrace_replicas(Renderer(scene, device), replicas, replica_spp))
    assert_replicas_agree(ours, by_mitsuba, block)
    assert by_mitsuba.mean() > 0.02
    two_sided = xyz_to_linear_srgb(spectrace_replicas(Renderer(_all_two_sided(scene), device), replicas, replica_spp))
    with pytest.raises(AssertionError):
        assert_replicas_agree(two_sided, by_mitsuba, block)


def _all_two_sided(scene: Scene) -> Scene:
    from dataclasses import replace

    return replace(scene, shapes=[replace(s, material=replace(s.material, detail=None)) for s in scene.shapes])


def _write_inward_wound_sphere(path) -> None:
    """An ASCII PLY icosphere with outward vertex normals and every face wound inward, as exporters that do not keep
    the winding write them."""
    mesh = primitives.sphere(subdivisions=3)
    header = (
        f"ply\nformat ascii 1.0\nelement vertex {len(mesh.vertices)}\n"
        + "".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz"))
        + f"element face {len(mesh.faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rows = [" ".join(f"{x:.9g}" for x in (*p, *n)) for p, n in zip(mesh.vertices, mesh.normals, strict=True)]
    rows += [f"3 {c} {b} {a}" for a, b, c in mesh.faces]
    path.write_text(header + "\n".join(rows) + "\n")


# A one-sided diffuse sphere and a one-sided spherical lamp, both that PLY file, over a floor, lit by the lamp and
# a point light: Mitsuba sees the sphere lit and the lamp bright, from their normals' side.
WOUND_INWARD = f"""<scene version="3.0.0">
  <integrator type="$integrator"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, -4, 1.2" target="0, 0, -0.2" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="4"/><translate z="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
  <shape type="ply"><string name="filename" value="sphere.ply"/>
    <transform name="to_world"><scale value="0.8"/><translate x="-0.5" z="-0.2"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf></shape>
  <shape type="ply"><string name="filename" value="sphere.ply"/>
    <transform name="to_world"><scale value="0.3"/><translate x="0.9" y="-0.6" z="0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="4, 3.5, 3"/></emitter></shape>
  <emitter type="point"><point name="position" x="-1.5" y="-2.5" z="2.5"/><rgb name="intensity" value="8, 8, 8"/>
  </emitter>
</scene>"""


@pytest.mark.peer
@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["path", "ptracer", "bdpt"])
def test_a_mesh_wound_against_its_normals_renders_as_in_mitsuba(tmp_path, device, mitsuba_scalar_spectral, integrator):
    """REPLICAS independent images from each renderer agree (tests/replica_agreement.py); Mitsuba's is lit where
    the sphere is (it decides the side by the shading frame), so a renderer deciding by the winding, which sees both
    spheres from the back, disagrees. Every spectrace integrator is compared with Mitsuba's path tracer: Mitsuba's
    light tracer (`ptracer`) drops the connection to the camera wherever the winding's normal and the shading
    normal disagree (its test against light leaks), so it shows this sphere black, unlike its own path tracer and
    unlike the same sphere wound outward."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 48 if integrator == "ptracer" else 8, 8  # the light tracer is the noisier
    _write_inward_wound_sphere(tmp_path / "sphere.ply")

    def xml(name: str):
        path = tmp_path / f"{name}.xml"
        path.write_text(WOUND_INWARD.replace("$integrator", name))
        return path

    by_mitsuba = np.stack(
        [np.array(mi.render(mi.load_file(str(xml("path"))), spp=replica_spp, seed=seed)) for seed in range(replicas)]
    )
    ours = xyz_to_linear_srgb(
        spectrace_replicas(Renderer(load_mitsuba_scene(xml(integrator)), device), replicas, replica_spp)
    )
    assert_replicas_agree(ours, by_mitsuba, block)
    # The sphere (left of the middle) is lit in Mitsuba's image, not the black back of a one-sided surface.
    assert by_mitsuba[:, SIZE // 2 - 4 : SIZE // 2 + 2, SIZE // 4 : SIZE // 2].mean() > 0.05
