"""A live session's edits write a light's rows again, and with them the images and sampling tables a goniometric
light, an environment map and a projector keep in the texel buffer: an image already there is not stored again, so
however many edits come, of the light itself or of anything else, the buffer holds one copy of each distinct image,
and the session renders the bits of a fresh render of the edited scene file."""

from pathlib import Path

import numpy as np
import pytest

import spectrace
from scene_text import camera_film
from spectrace.io.exr import write_exr
from spectrace.session import Session

SPP = 2
SCENE = """
[sampler]
spp = {spp}

[textures.slide]
type = "bitmap"
file = "slide.png"

[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}

[[shapes]]
name = "floor"
type = "rectangle"
material = "grey"
transform = [{{ rotate = {{ axis = [1, 0, 0], angle = -90 }} }}, {{ scale = 3 }}]

[[lights]]
type = "goniometric"
position = [0, 1.5, 0.5]
file = "lamp.exr"
intensity = {{ value = 2 }}

[[lights]]
type = "envmap"
file = "sky.exr"

[[lights]]
type = "projector"
position = [0, 2, 1]
target = [0, 0, 0]
intensity = {{ value = 3 }}
image = {{ texture = "slide" }}
"""


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory) -> Path:
    from PIL import Image

    folder = tmp_path_factory.mktemp("light_images")
    rng = np.random.default_rng(7)
    write_exr(folder / "lamp.exr", rng.uniform(0.1, 1.0, (8, 8, 3)).astype(np.float32), None, {})
    write_exr(folder / "other_lamp.exr", rng.uniform(0.1, 1.0, (8, 8, 3)).astype(np.float32), None, {})
    write_exr(folder / "sky.exr", rng.uniform(0.0, 0.4, (8, 16, 3)).astype(np.float32), None, {})
    Image.fromarray((rng.uniform(0, 1, (6, 5, 3)) * 255).astype(np.uint8)).save(folder / "slide.png")
    path = folder / "scene.toml"
    camera = camera_film(origin="[0, 1, 4]", target="[0, 0.5, 0]", width="12", height="10")
    path.write_text(camera + SCENE.format(spp=SPP))
    return path


def _texels(session: Session) -> int:
    return len(session.renderer.buffers.texels)


def _same_bits_as_fresh(session: Session, path: Path, overrides: dict[str, object]) -> None:
    session.step()
    expected = spectrace.render(spectrace.load_scene(path, overrides), spp=SPP, progress=False)
    image = session.image()
    assert image.spp == expected.spp
    np.testing.assert_array_equal(image.xyz, expected.xyz)


# Each round of edits: the goniometric light's and the environment map's own keys (their rows, images and tables
# written again) and a material's (the lights left alone).
ROUNDS = [
    {"lights.0.position": [0.2, 1.5, 0.5], "lights.0.up": [0.0, 1.0, 0.3]},
    {"lights.0.intensity": {"value": 3.0}, "lights.1.scale": 2.0},
    {"materials.grey.reflectance": {"value": 0.3}},
    {"lights.1.up": [0.3, 1.0, 0.0], "lights.0.mirrored": True},
]


def test_edits_of_goniometric_and_environment_lights_do_not_grow_the_texels(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        texels = _texels(session)
        applied: dict[str, object] = {}
        for _ in range(3):
            for edit in ROUNDS:
                assert not session.update(edit).rebuilt
                applied |= edit
                assert _texels(session) == texels, edit
        _same_bits_as_fresh(session, scene_file, applied)


def test_the_projectors_table_is_stored_once_over_its_edits(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        # The first edit resolves the slide texture again (a session keeps what it resolves from then on): a
        # texture's row is the texture rows' business, and only the projector's keys follow.
        session.update({"lights.2.position": [0.1, 2.0, 1.0]})
        texels = _texels(session)
        for position in ([0.2, 2.0, 1.0], [0.0, 2.0, 1.2], [0.2, 2.0, 1.0]):
            assert not session.update({"lights.2.position": position}).rebuilt
            assert _texels(session) == texels
        _same_bits_as_fresh(session, scene_file, {"lights.2.position": [0.2, 2.0, 1.0]})


def test_a_goniometric_image_edited_back_and_forth_is_stored_once_per_image(scene_file):
    with Session(scene_file, pass_spp=SPP) as session:
        texels = _texels(session)
        assert not session.update({"lights.0.file": "other_lamp.exr"}).rebuilt
        # The other image and its sampling table: 64 texels and (9 + 8·9) / 4 float4s.
        grown = _texels(session)
        assert grown == texels + 64 + (9 + 8 * 9 + 3) // 4
        for file in ("lamp.exr", "other_lamp.exr", "lamp.exr"):
            assert not session.update({"lights.0.file": file}).rebuilt
            assert _texels(session) == grown
        _same_bits_as_fresh(session, scene_file, {"lights.0.file": "lamp.exr"})


def test_the_environment_maps_texel_spectra_edited_back_and_forth(scene_file):
    """Smooth texels are other numbers in the texel buffer and another kernel branch: the edit renders the bits of
    a fresh render either way, and going back stores nothing again."""
    with Session(scene_file, pass_spp=SPP) as session:
        session.update({"lights.1.texel_spectra": "smooth"})
        _same_bits_as_fresh(session, scene_file, {"lights.1.texel_spectra": "smooth"})
        texels = _texels(session)
        for texel_spectra in ("primaries", "smooth"):
            session.update({"lights.1.texel_spectra": texel_spectra})
            assert _texels(session) <= texels
        _same_bits_as_fresh(session, scene_file, {"lights.1.texel_spectra": "smooth"})
