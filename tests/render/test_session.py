"""The live session (spectrace.session): after every kind of edit, the session's image is the same bits as a fresh
render of the edited scene file with the same seed and samples; edits that change the scene's layout say so and
build it again; a bad key or value is one SpectraceError naming the key path, and nothing is applied."""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.device import host_memory
from spectrace.errors import SpectraceError
from spectrace.session import Session

SCENES = Path(__file__).resolve().parents[2] / "scenes"
SPP = 2

# A bit of every kind of edit: a camera, plain, textured and mixed materials, a metal, an area light, a point light
# and an environment, an object placed twice.
SCENE = f"""
[integrator]
max_depth = 4

[sampler]
spp = {SPP}

[textures.picture]
type = "bitmap"
file = "{(SCENES / "teapot" / "glaze.png").as_posix()}"

[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[materials.red]
type = "diffuse"
reflectance = {{ rgb = [0.7, 0.1, 0.1] }}

[materials.painted]
type = "diffuse"
reflectance = {{ texture = "picture" }}

[materials.gold]
type = "conductor"
metal = "Au"
roughness = 0.2

[materials.blend]
type = "mix"
materials = ["red", "gold"]
amount = 0.3

[materials.lamp]
type = "diffuse"
reflectance = {{ value = 0.0 }}

[[shapes]]
name = "floor"
type = "rectangle"
material = "grey"
transform = [{{ rotate = {{ axis = [1, 0, 0], angle = -90 }} }}, {{ scale = 3 }}]

[[shapes]]
name = "panel"
type = "rectangle"
material = "painted"
transform = [{{ scale = 0.6 }}, {{ translate = [-0.8, 0.7, -0.5] }}]

[[shapes]]
name = "ball"
type = "sphere"
material = "blend"
radius = 0.35
center = [0.7, 0.35, 0.2]

{{cloud}}[[shapes]]
name = "lamp"
type = "rectangle"
material = "lamp"
transform = [{{ scale = 0.5 }}, {{ rotate = {{ axis = [1, 0, 0], angle = 90 }} }}, {{ translate = [0, 2.5, 0] }}]
emitter = {{ radiance = {{ value = 4.0 }} }}

[objects.post]
shapes = [{{ type = "cube", material = "red", transform = [{{ scale = [0.1, 0.4, 0.1] }}] }}]

[[instances]]
object = "post"
name = "left post"
transform = [{{ translate = [-1.2, 0.4, 0.8] }}]

[[instances]]
object = "post"
name = "right post"
transform = [{{ translate = [1.3, 0.4, -0.6] }}]

[[lights]]
type = "point"
position = [1.0, 1.8, 1.5]
power = 20.0

[[lights]]
type = "constant"
radiance = {{ value = 0.05 }}
"""


# A medium, which the sppm integrator does not render: the scene has it, the one without is for every integrator.
CLOUD = """[[shapes]]
name = "cloud"
type = "sphere"
radius = 0.2
center = [-0.3, 0.3, 0.9]
interior = { sigma_a = { value = 0.5 }, sigma_s = { value = 2.0 }, g = 0.3 }

"""


def _write(folder: Path, cloud: str) -> Path:
    path = folder / "scene.toml"
    camera = camera_film(origin="[0.3, 1.4, 4.0]", target="[0, 0.5, 0]", width="12", height="10")
    path.write_text(camera + SCENE.replace("{cloud}", cloud))
    return path


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    return _write(tmp_path_factory.mktemp("session"), CLOUD)


@pytest.fixture(scope="module")
def clear_scene_file(tmp_path_factory):
    return _write(tmp_path_factory.mktemp("session"), "")


def _fresh(path: Path, overrides: dict[str, object], spp: int = SPP) -> spectrace.Image:
    """A render of the scene file with `overrides` at its key paths, from nothing."""
    return spectrace.render(spectrace.load_scene(path, overrides), spp=spp, progress=False)


def _same_bits(session: Session, expected: spectrace.Image) -> None:
    image = session.image()
    assert image.spp == expected.spp
    np.testing.assert_array_equal(image.xyz, expected.xyz)
    np.testing.assert_array_equal(image.to_rgb(), expected.to_rgb())


# Each edit as a session key (arrays' entries by name) and as the same edit at the file's key path (by index).
EDITS = [
    pytest.param({"camera.origin": [0.5, 1.2, 3.5]}, {}, "camera", id="camera origin"),
    pytest.param({"camera.target": [0.1, 0.4, 0.0], "camera.fov": 55.0}, {}, "camera", id="camera target and fov"),
    pytest.param({"camera.up": [0.1, 1.0, 0.0]}, {}, "camera", id="camera up"),
    pytest.param(
        {"camera.type": "thinlens", "camera.aperture_radius": 0.1, "camera.focus_distance": 3.0},
        {},
        "camera",
        id="thin lens",
    ),
    pytest.param({"materials.red.reflectance": {"rgb": [0.1, 0.6, 0.2]}}, {}, "materials", id="reflectance"),
    pytest.param({"materials.gold.roughness": 0.05}, {}, "materials", id="roughness"),
    pytest.param({"materials.blend.amount": 0.8}, {}, "materials", id="mix amount"),
    pytest.param(
        {"textures.picture.file": (SCENES / "teapot" / "wood.png").as_posix()}, {}, "materials", id="texture file"
    ),
    pytest.param({"lights.0.power": 55.0}, {}, "lights", id="point light power"),
    pytest.param({"lights.0.position": [-1.0, 2.0, 1.0]}, {}, "lights", id="point light position"),
    pytest.param({"lights.1.radiance": {"rgb": [0.1, 0.05, 0.02]}}, {}, "lights", id="environment colour"),
    pytest.param(
        {"shapes.lamp.emitter.radiance": {"value": 9.0}},
        {"shapes.4.emitter.radiance": {"value": 9.0}},
        "lights",
        id="area light radiance",
    ),
    pytest.param(
        {"instances.right post.transform": [{"translate": [0.2, 0.4, 1.1]}]},
        {"instances.1.transform": [{"translate": [0.2, 0.4, 1.1]}]},
        "instances",
        id="instance transform",
    ),
    pytest.param(
        {"instances.left post.transform": [{"scale": 4.0}, {"translate": [-6.0, 1.0, -9.0]}]},
        {"instances.0.transform": [{"scale": 4.0}, {"translate": [-6.0, 1.0, -9.0]}]},
        "instances",
        id="instance moving the scene's bounds",
    ),
    pytest.param(
        {"shapes.cloud.interior.sigma_s": {"rgb": [0.5, 2.0, 4.0]}, "shapes.cloud.interior.g": -0.2},
        {"shapes.3.interior.sigma_s": {"rgb": [0.5, 2.0, 4.0]}, "shapes.3.interior.g": -0.2},
        "media",
        id="medium",
    ),
    pytest.param({"sampler.seed": 7}, {}, "seed", id="seed"),
]


@pytest.mark.parametrize(("changes", "file_keys", "kind"), EDITS)
def test_an_edit_renders_the_bits_of_a_fresh_render_of_the_edited_file(scene_file, changes, file_keys, kind):
    with Session(scene_file) as session:
        session.step(SPP)
        _same_bits(session, _fresh(scene_file, {}))
        report = session.update(changes)
        assert report.restarted and session.samples_done == 0
        assert not report.rebuilt, str(report)
        assert [step.what for step in report.steps if step.how == "in place"][0] == kind
        session.step(1)
        session.step(1)
        _same_bits(session, _fresh(scene_file, file_keys or changes))
        # session.scene is the edited scene: a render of it is the same bits too.
        np.testing.assert_array_equal(spectrace.render(session.scene, spp=SPP, progress=False).xyz, session.image().xyz)


def test_edits_of_buffers_in_huge_pages_render_the_bits_of_a_fresh_copied_render(scene_file, monkeypatch):
    # Every scene buffer in huge-page host memory used in place (on a CPU device; spectrace.device.host_memory), the
    # edits rewriting them there; the fresh render's buffers are copied to the runtime's memory.
    changes = {"materials.red.reflectance": {"rgb": [0.1, 0.6, 0.2]}, "lights.0.power": 55.0}
    changes |= {"instances.right post.transform": [{"translate": [0.2, 0.4, 1.1]}]}
    file_keys = {key: value for key, value in changes.items() if not key.startswith("instances")}
    file_keys |= {"instances.1.transform": [{"translate": [0.2, 0.4, 1.1]}]}
    expected = _fresh(scene_file, file_keys)
    monkeypatch.setattr(host_memory, "MIN_HUGE_PAGE_ARRAY_BYTES", 0)
    with Session(scene_file) as session:
        report = session.update(changes)
        assert not report.rebuilt, str(report)
        session.step(SPP)
        _same_bits(session, expected)


def test_a_seed_edits_a_file_without_a_sampler_table_as_one_that_writes_the_seed(tmp_path, clear_scene_file):
    """[sampler] may be left out (importers leave it out): its keys are still there to set, from a session and as a
    load override, and give the bits of the file that writes them."""
    bare = tmp_path / "bare.toml"
    bare.write_text(clear_scene_file.read_text().replace(f"[sampler]\nspp = {SPP}\n", ""))
    assert "[sampler]" not in bare.read_text()
    written = tmp_path / "written.toml"
    written.write_text(bare.read_text() + "\n[sampler]\nseed = 7\n")
    expected = _fresh(written, {})
    assert not np.array_equal(expected.xyz, _fresh(bare, {}).xyz)  # the seed shows in the image
    np.testing.assert_array_equal(_fresh(bare, {"sampler.seed": 7}).xyz, expected.xyz)
    with Session(bare) as session:
        session.update({"sampler.seed": 7})
        session.step(SPP)
        _same_bits(session, expected)


@pytest.mark.parametrize("integrator", ["direct", "bdpt", "light", "sppm"])
def test_every_integrator_renders_an_edit_as_a_fresh_render(clear_scene_file, integrator):
    edit = {"camera.fov": 50.0, "lights.0.power": 35.0, "materials.red.reflectance": {"value": 0.4}}
    base = {"integrator.type": integrator}
    with Session(spectrace.load_scene(clear_scene_file, base), pass_spp=SPP) as session:
        session.step()
        assert not session.update(edit).rebuilt
        session.step()
        _same_bits(session, _fresh(clear_scene_file, base | edit))


def test_edits_add_up_and_a_layout_change_is_built_again(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        first = {"camera.fov": 50.0, "materials.grey.reflectance": {"value": 0.3}, "lights.0.power": 30.0}
        session.update(first)
        # A shape's geometry and the film's size are no in-place edits: built again, and said so.
        report = session.update({"shapes.ball.radius": 0.5, "film.width": 9})
        assert report.rebuilt and [step.how for step in report.steps] == ["checked", "rebuilt"]
        session.step()
        _same_bits(session, _fresh(scene_file, first | {"shapes.2.radius": 0.5, "film.width": 9}))
        # In-place edits work on the rebuilt scene too.
        report = session.update({"materials.red.reflectance": {"value": 0.9}})
        assert not report.rebuilt
        session.step()
        expected = first | {"shapes.2.radius": 0.5, "film.width": 9, "materials.red.reflectance": {"value": 0.9}}
        _same_bits(session, _fresh(scene_file, expected))


def test_a_light_more_or_a_new_feature_is_built_again(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        # The floor starts to emit: a light more, so the light rows' layout changes.
        report = session.update({"shapes.floor.emitter": {"radiance": {"value": 0.2}}})
        assert report.rebuilt
        session.step()
        _same_bits(session, _fresh(scene_file, {"shapes.0.emitter": {"radiance": {"value": 0.2}}}))
    with Session(scene_file, pass_spp=SPP) as session:
        # A material of a type the program was not built for: a program specialised to the scene's features is
        # built again (the BVH kept); the general kernels the suite runs on render every type.
        specialised = session.renderer.specialised
        report = session.update({"materials.grey.type": "plastic", "materials.grey.roughness": 0.1})
        assert [step.what for step in report.steps if step.how == "rebuilt"] == (["program"] if specialised else [])
        session.step()
        _same_bits(session, _fresh(scene_file, {"materials.grey.type": "plastic", "materials.grey.roughness": 0.1}))


def test_the_films_observer_is_built_again_over_the_same_scene(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        buffers = session.renderer.buffers
        report = session.update({"film.observer": "CIE 1964 10°", "film.observers": ["CIE 1931 2°"]})
        assert [(step.what, step.how) for step in report.steps][-1] == ("film", "rebuilt")
        assert session.renderer.buffers is buffers  # the BVH and every scene buffer kept
        session.step()
        expected = _fresh(scene_file, {"film.observer": "CIE 1964 10°", "film.observers": ["CIE 1931 2°"]})
        _same_bits(session, expected)
        np.testing.assert_array_equal(session.image().channels["cie1931_2.Y"], expected.channels["cie1931_2.Y"])


def test_image_settings_keep_the_samples(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        session.step()
        report = session.update({"film.exposure": 1.5, "film.colour_space": "rec2020", "film.white_balance": "D50"})
        assert not report.restarted and session.samples_done == SPP
        image = session.image()
        scene = spectrace.load_scene(scene_file, {"film.exposure": 1.5})
        expected = spectrace.render(scene, progress=False, colour_space="rec2020", white_balance="D50")
        np.testing.assert_array_equal(image.to_rgb(), expected.to_rgb())
        assert session.parameters()["film.colour_space"] == "rec2020"


@pytest.mark.parametrize(
    ("changes", "where"),
    [
        ({"camera.fov": 200.0}, "camera.fov"),
        ({"camera.target": [0.3, 1.4, 4.0]}, "camera.target"),
        ({"materials.red.reflectance": {"rgb": [2.0, 0.1, 0.1]}}, "materials.red.reflectance"),
        ({"materials.red.colour": 0.5}, "materials.red"),
        ({"materials.nothing.reflectance": 0.5}, "materials.nothing"),
        ({"lights.0.power": -1.0}, "lights[0]: power"),
        ({"shapes.no such shape.emitter.scale": 2.0}, "shapes.no such shape"),
        ({"instances.right post.transform": [{"scale": 0.0}]}, "instances[1].transform"),
        ({"film.colour_space": "no such space"}, "film.colour_space"),
        ({"film.exposure": "bright"}, "film.exposure"),
    ],
)
def test_a_bad_edit_is_one_error_naming_the_key_and_changes_nothing(scene_file, changes, where):
    with Session(scene_file, pass_spp=SPP) as session:
        session.step()
        before = session.parameters()
        with pytest.raises(SpectraceError) as caught:
            session.update({"camera.fov": 45.0, **changes})  # a good edit beside it is not applied either
        assert where in str(caught.value)
        assert "\n" not in str(caught.value)
        assert session.parameters() == before and session.samples_done == SPP
        session.step()
        _same_bits(session, _fresh(scene_file, {}, spp=2 * SPP))


def test_parameters_name_the_editable_keys(scene_file):
    with Session(scene_file) as session:
        parameters = session.parameters()
    assert parameters["camera.fov"] == 40
    assert parameters["materials.red.reflectance"] == {"rgb": [0.7, 0.1, 0.1]}
    assert parameters["lights.0.power"] == 20.0
    assert parameters["shapes.lamp.emitter.radiance"] == {"value": 4.0}
    assert parameters["instances.right post.transform"] == [{"translate": [1.3, 0.4, -0.6]}]
    assert parameters["film.exposure"] == 0.0 and parameters["sampler.seed"] == 0
    # An entry of an array of tables goes by its index too.
    with Session(scene_file) as session:
        session.update({"shapes.4.emitter.scale": 3.0, "instances.1.transform": [{"translate": [0, 0.4, 0]}]})
        assert session.parameters()["shapes.lamp.emitter.scale"] == 3.0
        assert session.parameters()["instances.right post.transform"] == [{"translate": [0, 0.4, 0]}]


def test_a_scene_built_in_python_edits_its_camera_and_instances():
    post = spectrace.instanced_object([spectrace.shape("cube", spectrace.diffuse(0.6), transform=[{"scale": 0.3}])])
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=45.0),
        width=10,
        height=8,
        shapes=[spectrace.shape("rectangle", spectrace.diffuse(0.5), transform=[{"scale": 3}], name="ground")],
        lights=[spectrace.point_light((0.0, 2.0, 2.0), power_w=10.0)],
        instances=[spectrace.instance(post, [{"translate": [0.5, 0.3, 0.0]}], name="box")],
        spp=SPP,
    )
    moved = [{"translate": [-0.5, 0.3, 0.5]}]
    with Session(scene, pass_spp=SPP) as session:
        report = session.update({"camera.fov": 60.0, "instances.box.transform": moved})
        assert not report.rebuilt
        session.step()
        expected = spectrace.Scene(
            **{
                **scene.__dict__,
                "camera": spectrace.Camera(origin=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0), fov_degrees=60.0),
                "instances": [spectrace.instance(post, moved, name="box")],
            }
        )
        _same_bits(session, spectrace.render(expected, progress=False))
        with pytest.raises(SpectraceError, match="materials"):
            session.update({"materials.grey.reflectance": 0.2})


def test_an_unchanged_texture_is_neither_read_nor_stored_again(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        session.update({"materials.painted.roughness": 0.5, "materials.painted.type": "plastic"})
        texels = len(session.renderer.buffers.texels)
        for roughness in (0.3, 0.4, 0.3):  # the picture's table is unchanged: its rows and texels are reused
            session.update({"materials.painted.roughness": roughness})
            assert len(session.renderer.buffers.texels) == texels
        session.step()
        edited = {"materials.painted.type": "plastic", "materials.painted.roughness": 0.3}
        _same_bits(session, _fresh(scene_file, edited))


def test_spectral_bands_restart_with_the_edit_too(scene_file):
    with Session(scene_file, pass_spp=SPP, spectral_bins=6) as session:
        session.step()
        session.update({"materials.red.reflectance": {"rgb": [0.1, 0.2, 0.9]}, "camera.fov": 30.0})
        session.step()
        scene = spectrace.load_scene(
            scene_file, {"materials.red.reflectance": {"rgb": [0.1, 0.2, 0.9]}, "camera.fov": 30.0}
        )
        expected = spectrace.render(scene, progress=False, spectral_bins=6)
        np.testing.assert_array_equal(session.image().spectral.radiance, expected.spectral.radiance)


def test_a_closed_session_says_so(scene_file):
    session = Session(scene_file)
    session.close()
    for use in (session.step, session.image, lambda: session.update({"camera.fov": 30.0})):
        with pytest.raises(SpectraceError, match="closed"):
            use()


def test_an_environment_map_is_kept_while_another_light_changes(tmp_path):
    from spectrace.io.exr import write_exr

    rgb = np.random.default_rng(3).uniform(0.0, 0.4, (8, 16, 3)).astype(np.float32)
    rgb[2, 5] = (30.0, 20.0, 8.0)  # a sun the sampler must find
    write_exr(tmp_path / "sky.exr", rgb, None, {})
    path = _write(tmp_path, "")
    constant = 'type = "constant"\nradiance = { value = 0.05 }'
    path.write_text(path.read_text().replace(constant, 'type = "envmap"\nfile = "sky.exr"'))
    with Session(path, pass_spp=SPP) as session:
        texels, tables = len(session.renderer.buffers.texels), session.renderer.buffers.map_cdf
        report = session.update({"lights.0.power": 70.0, "shapes.lamp.emitter.scale": 0.5})
        assert not report.rebuilt
        # The map was not written again: neither its texels appended nor its sampling tables made anew.
        assert len(session.renderer.buffers.texels) == texels and session.renderer.buffers.map_cdf is tables
        session.step()
        _same_bits(session, _fresh(path, {"lights.0.power": 70.0, "shapes.3.emitter.scale": 0.5}))
        # The map's own keys write it again.
        assert not session.update({"lights.1.scale": 2.5, "lights.1.up": [0.3, 1.0, 0.0]}).rebuilt
        session.step()
        expected = {"lights.0.power": 70.0, "shapes.3.emitter.scale": 0.5, "lights.1.scale": 2.5}
        _same_bits(session, _fresh(path, expected | {"lights.1.up": [0.3, 1.0, 0.0]}))
