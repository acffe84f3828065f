"""The live session of a scene built in Python: its materials, lights, emitters, media and textures are named by
their place (materials by the shape that uses them, lights by index, a shape's emitter and medium through the shape)
and edited by key path; after each kind of edit the image is the same bits as a fresh render of the same scene built
with the edited argument, and a bad key or value is one error naming the key, with nothing applied."""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from spectrace.errors import SpectraceError
from spectrace.session import Session

SCENES = Path(__file__).resolve().parents[2] / "scenes"
SPP = 2
GLAZE = (SCENES / "teapot" / "glaze.png").as_posix()
WOOD = (SCENES / "teapot" / "wood.png").as_posix()

# The arguments the scene is built from: each test builds it again with one of them changed.
BASE = {
    "red": (0.7, 0.1, 0.1),
    "amount": 0.3,
    "gold_roughness": 0.2,
    "picture": GLAZE,
    "uv_scale": 1.0,
    "power": 20.0,
    "sky": 0.05,
    "lamp_scale": 1.0,
    "sigma_s": 2.0,
    "g": 0.3,
}


def build(**changed: object) -> spectrace.Scene:
    a = BASE | changed
    red = spectrace.diffuse(a["red"])
    gold = spectrace.conductor("Au", roughness=a["gold_roughness"])
    picture = spectrace.bitmap(a["picture"], uv_scale=a["uv_scale"])
    post = spectrace.instanced_object(
        [spectrace.shape("cube", spectrace.diffuse(0.6), transform=[{"scale": [0.1, 0.4, 0.1]}], name="post")]
    )
    return spectrace.Scene(
        camera=spectrace.Camera(origin=(0.3, 1.4, 4.0), target=(0.0, 0.5, 0.0), fov_degrees=40.0),
        width=12,
        height=10,
        shapes=[
            spectrace.shape(
                "rectangle",
                spectrace.diffuse(0.5),
                transform=[{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 3}],
                name="floor",
            ),
            spectrace.shape(
                "rectangle",
                spectrace.diffuse(picture),
                transform=[{"scale": 0.6}, {"translate": [-0.8, 0.7, -0.5]}],
                name="panel",
            ),
            spectrace.shape("sphere", spectrace.mix([red, gold], a["amount"]), radius=0.35, center=(0.7, 0.35, 0.2)),
            spectrace.shape("cube", red, transform=[{"scale": 0.2}, {"translate": [-0.2, 0.2, 1.0]}], name="box"),
            spectrace.shape(
                "sphere",
                interior=spectrace.medium(0.5, a["sigma_s"], g=a["g"]),
                radius=0.2,
                center=(-0.3, 0.3, 0.9),
                name="cloud",
            ),
            spectrace.shape(
                "rectangle",
                spectrace.diffuse(0.0),
                emitter=spectrace.area_emitter(4.0, scale=a["lamp_scale"]),
                transform=[{"scale": 0.5}, {"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"translate": [0, 2.5, 0]}],
                name="lamp",
            ),
        ],
        lights=[
            spectrace.point_light((1.0, 1.8, 1.5), power_w=a["power"]),
            spectrace.constant_environment(a["sky"]),
        ],
        instances=[spectrace.instance(post, [{"translate": [1.2, 0.4, 0.8]}], name="post")],
        spp=SPP,
    )


def _render(scene: spectrace.Scene) -> spectrace.Image:
    return spectrace.render(scene, progress=False)


@pytest.fixture(scope="module")
def base_image() -> spectrace.Image:
    return _render(build())


# Each edit as a session key and as the argument the scene is built with; the kind of in-place step it takes.
EDITS = [
    pytest.param(
        {"materials.box.reflectance": (0.1, 0.6, 0.2)}, {"red": (0.1, 0.6, 0.2)}, "materials", id="reflectance"
    ),
    pytest.param({"materials.sphere.amount": 0.8}, {"amount": 0.8}, "materials", id="mix amount"),
    pytest.param(
        {"materials.sphere.materials.1.roughness": 0.02}, {"gold_roughness": 0.02}, "materials", id="a mix's part"
    ),
    pytest.param({"materials.panel.reflectance.source": WOOD}, {"picture": WOOD}, "materials", id="texture file"),
    pytest.param({"materials.panel.reflectance.uv_scale": 3.0}, {"uv_scale": 3.0}, "materials", id="texture scale"),
    pytest.param({"lights.0.power": 60.0}, {"power": 60.0}, "lights", id="point light power"),
    pytest.param({"lights.1.radiance": 0.3}, {"sky": 0.3}, "lights", id="environment radiance"),
    pytest.param({"shapes.lamp.emitter.scale": 3.0}, {"lamp_scale": 3.0}, "lights", id="area light scale"),
    pytest.param(
        {"shapes.cloud.interior.sigma_s": (0.5, 2.0, 4.0), "shapes.cloud.interior.g": -0.2},
        {"sigma_s": (0.5, 2.0, 4.0), "g": -0.2},
        "media",
        id="medium",
    ),
]


@pytest.mark.parametrize(("changes", "arguments", "kind"), EDITS)
def test_an_edit_of_a_python_scene_renders_the_bits_of_the_scene_built_edited(base_image, changes, arguments, kind):
    expected = _render(build(**arguments))
    assert not np.array_equal(expected.xyz, base_image.xyz)  # the edit shows in the image
    with Session(build(), pass_spp=SPP) as session:
        session.step()
        np.testing.assert_array_equal(session.image().xyz, base_image.xyz)
        report = session.update(changes)
        assert report.restarted and not report.rebuilt, str(report)
        assert [step.what for step in report.steps if step.how == "in place"][0] == kind
        session.step()
        np.testing.assert_array_equal(session.image().xyz, expected.xyz)
        for key, value in changes.items():
            assert session.parameters()[key] == (list(value) if isinstance(value, tuple) else value)
        # session.scene is the edited scene: rendered afresh, it is the same bits.
        np.testing.assert_array_equal(_render(session.scene).xyz, expected.xyz)


def test_parameters_name_a_python_scenes_objects_as_a_scene_file_would():
    with Session(build()) as session:
        parameters = session.parameters()
    assert parameters["materials.floor.reflectance"] == 0.5
    assert parameters["materials.box.reflectance"] == [0.7, 0.1, 0.1]
    assert parameters["materials.sphere.amount"] == 0.3  # an unnamed shape goes by its geometry's name
    assert parameters["materials.sphere.materials.1.roughness"] == 0.2
    assert parameters["materials.panel.reflectance.uv_scale"] == 1.0
    assert parameters["lights.0.power"] == 20.0  # the scene file's name of the API's power_w
    assert parameters["shapes.lamp.emitter.scale"] == 1.0
    assert parameters["shapes.cloud.interior.g"] == 0.3
    assert parameters["camera.fov"] == 40.0


def test_materials_of_shapes_sharing_a_name_go_by_their_position():
    from spectrace.session.python_scene import materials_by_label

    grey, white, red = spectrace.diffuse(0.5), spectrace.diffuse(0.9), spectrace.diffuse((0.7, 0.1, 0.1))
    shapes = [spectrace.shape("rectangle", m) for m in (grey, white)] + [spectrace.shape("cube", red, name="box")]
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0.0, 1.0, 4.0), target=(0.0, 0.0, 0.0)), width=4, height=4, shapes=shapes
    )
    assert {label: id(m) for label, m in materials_by_label(scene).items()} == {
        "0": id(grey),
        "1": id(white),
        "box": id(red),
    }


def test_edits_add_up_and_a_shared_material_changes_everywhere(base_image):
    # The red material is the box's and the sphere's mix's first part: one edit changes both.
    changes = {"materials.box.reflectance": 0.2, "lights.0.power": 35.0, "camera.fov": 50.0}
    with Session(build(), pass_spp=SPP) as session:
        assert not session.update(changes).rebuilt
        assert not session.update({"materials.sphere.amount": 0.6, "shapes.lamp.emitter.scale": 2.0}).rebuilt
        session.step()
        expected = build(red=0.2, power=35.0, amount=0.6, lamp_scale=2.0)
        expected = spectrace.Scene(
            **{
                **expected.__dict__,
                "camera": spectrace.Camera(origin=(0.3, 1.4, 4.0), target=(0.0, 0.5, 0.0), fov_degrees=50.0),
            }
        )
        np.testing.assert_array_equal(session.image().xyz, _render(expected).xyz)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"materials.box.reflectance": (2.0, 0.1, 0.1)}, "materials.box.reflectance"),
        ({"materials.box.colour": 0.5}, "has no parameter 'colour'"),
        ({"materials.nothing.reflectance": 0.5}, "materials.nothing.reflectance"),
        ({"lights.0.power": -1.0}, "lights.0.power"),
        ({"lights.5.power": 1.0}, "lights"),
        ({"shapes.cloud.interior.g": 1.5}, "shapes.cloud.interior.g"),
        ({"materials.panel.reflectance.wrap": "sideways"}, "materials.panel.reflectance.wrap"),
        ({"materials.sphere.amount": "half"}, "materials.sphere.amount"),
        ({"film.width": 20}, "film.width"),
    ],
)
def test_a_bad_edit_of_a_python_scene_is_one_error_and_changes_nothing(base_image, changes, message):
    with Session(build(), pass_spp=SPP) as session:
        before = session.parameters()
        with pytest.raises(SpectraceError) as caught:
            session.update({"lights.0.power": 50.0, **changes})  # a good edit beside it is not applied either
        assert message in str(caught.value) and "\n" not in str(caught.value)
        assert session.parameters().keys() == before.keys()
        assert session.parameters()["lights.0.power"] == 20.0
        session.step()
        np.testing.assert_array_equal(session.image().xyz, base_image.xyz)


def test_many_image_edits_keep_the_texel_buffer_its_size():
    # Fifty distinct images of the same size: each takes the slot of the one it replaces.
    rng = np.random.default_rng(5)
    images = [rng.uniform(0.05, 0.95, (8, 8, 3)) for _ in range(50)]
    with Session(build(picture=images[0]), pass_spp=SPP) as session:
        texels, rows = len(session.renderer.buffers.texels), session.renderer.buffers.texture_count
        for image in images[1:]:
            assert not session.update({"materials.panel.reflectance.source": image}).rebuilt
            assert len(session.renderer.buffers.texels) == texels
            assert session.renderer.buffers.texture_count == rows
        session.step()
        expected = _render(build(picture=images[-1]))
        assert not np.array_equal(expected.xyz, _render(build(picture=images[0])).xyz)
        np.testing.assert_array_equal(session.image().xyz, expected.xyz)


def test_a_scene_files_texture_and_emitter_images_edited_many_times_keep_the_texel_buffer_its_size(tmp_path):
    from PIL import Image as PILImage

    from scene_text import camera_film

    rng = np.random.default_rng(9)
    for i in range(12):
        pixels = rng.integers(20, 235, (8, 8, 3), dtype=np.uint8)
        PILImage.fromarray(pixels).save(tmp_path / f"picture{i}.png")
    scene = tmp_path / "scene.toml"
    scene.write_text(
        camera_film(origin="[0, 0.5, 4]", target="[0, 0.5, 0]", width="12", height="10")
        + """
[sampler]
spp = 2

[textures.picture]
type = "bitmap"
file = "picture0.png"

[materials.painted]
type = "diffuse"
reflectance = { texture = "picture" }

[[shapes]]
name = "panel"
type = "rectangle"
material = "painted"

[[shapes]]
name = "screen"
type = "rectangle"
material = "painted"
transform = [{ scale = 0.3 }, { translate = [0.5, 0.5, 0.5] }]
emitter = { radiance = { texture = "picture" }, scale = 0.5 }

[[lights]]
type = "point"
position = [0, 1, 3]
power = 30.0
"""
    )
    with Session(scene, pass_spp=SPP) as session:
        texels = len(session.renderer.buffers.texels)
        for i in range(1, 12):
            assert not session.update({"textures.picture.file": f"picture{i}.png"}).rebuilt
            assert len(session.renderer.buffers.texels) == texels
        session.step()
        edited = {"textures.picture.file": "picture11.png"}
        expected = spectrace.render(spectrace.load_scene(scene, edited), progress=False)
        assert not np.array_equal(expected.xyz, spectrace.render(spectrace.load_scene(scene), progress=False).xyz)
        np.testing.assert_array_equal(session.image().xyz, expected.xyz)


def test_a_python_scenes_film_observers_are_edited_over_the_same_buffers():
    edit = {"film.observer": "CIE 1964 10°", "film.observers": ["CIE 1931 2°"]}
    with Session(build(), pass_spp=SPP) as session:
        buffers = session.renderer.buffers
        report = session.update(edit)
        assert [(step.what, step.how) for step in report.steps][-1] == ("film", "rebuilt")
        assert session.renderer.buffers is buffers  # the BVH and every scene buffer kept
        session.step()
        response = spectrace.FilmResponse(observer="CIE 1964 10°", observers=("CIE 1931 2°",))
        expected = _render(spectrace.Scene(**{**build().__dict__, "film_response": response}))
        assert not np.array_equal(expected.xyz, _render(build()).xyz)
        np.testing.assert_array_equal(session.image().xyz, expected.xyz)
        np.testing.assert_array_equal(session.image().channels["cie1931_2.Y"], expected.channels["cie1931_2.Y"])
        with pytest.raises(SpectraceError, match="film.observer"):
            session.update({"film.observer": "no such observer"})
