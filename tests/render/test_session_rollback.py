"""A live session's update is all or nothing even where it fails after the re-packing began: a texture over the
device budget, an upload the device refuses. The error is one line, the next pass renders the unedited scene bit
for bit, and later edits start from the unedited packing, so they render as a fresh render of the scene with those
edits alone."""

import numpy as np
import pytest
from tests.render.test_session import CLOUD, SCENES, SPP, _fresh, _same_bits, _write

import spectrace.textures
from spectrace.errors import SpectraceError
from spectrace.session import Session


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    return _write(tmp_path_factory.mktemp("rollback"), CLOUD)


def _texture_state(session: Session) -> tuple:
    textures = session.renderer.buffers.packing.textures
    return dict(textures.index), list(textures.free), list(textures.sizes), textures.bytes, len(textures.rows)


def test_a_texture_over_the_budget_changes_nothing(scene_file, monkeypatch):
    with Session(scene_file, pass_spp=SPP) as session:
        session.step()
        before = _texture_state(session)
        # The budget the scene's one picture fits in, but not a second image beside it: the edit lets the picture's
        # slot go, and the wood, whose texels are longer, needs more than there is.
        monkeypatch.setattr(spectrace.textures, "MAX_TEXTURE_BYTES", before[3])
        wood = (SCENES / "teapot" / "wood.png").as_posix()
        with pytest.raises(SpectraceError) as caught:
            session.update({"textures.picture.file": wood, "materials.red.reflectance": {"rgb": [0.1, 0.6, 0.2]}})
        assert "at most" in str(caught.value) and "\n" not in str(caught.value)
        assert _texture_state(session) == before  # the picture keeps its slot, none is free
        session.step()
        _same_bits(session, _fresh(scene_file, {}, spp=2 * SPP))
        monkeypatch.undo()
        # A later edit re-packs every material from the packing as it was before the failed one.
        session.update({"materials.gold.roughness": 0.05})
        session.step()
        _same_bits(session, _fresh(scene_file, {"materials.gold.roughness": 0.05}))


def test_a_light_edit_the_device_refuses_to_upload_changes_nothing(scene_file, monkeypatch):
    from spectrace.engine.renderer import Renderer

    with Session(scene_file, pass_spp=SPP) as session:
        session.step()
        power = list(session.renderer.buffers.packing.light_power)
        lights = session.renderer.buffers.lights.copy()
        upload = Renderer.replace_scene

        def refused(renderer, scene, buffers, changed):
            # The first buffer written, the next refused: the device holds half the edit when the update fails.
            first = sorted(changed)[:1]
            upload(renderer, scene, buffers, first)
            raise SpectraceError("the device is out of memory", where="lights.0.power")

        monkeypatch.setattr(Renderer, "replace_scene", refused)
        with pytest.raises(SpectraceError) as caught:
            session.update({"lights.0.power": 70.0, "shapes.lamp.emitter.scale": 0.5})
        assert "out of memory" in str(caught.value) and "\n" not in str(caught.value)
        monkeypatch.undo()
        assert session.renderer.buffers.packing.light_power == power
        np.testing.assert_array_equal(session.renderer.buffers.lights, lights)
        session.step()  # the failed upload was undone, and the accumulation restarted with it
        _same_bits(session, _fresh(scene_file, {}))
        # Another light's edit picks lights by the power of the unedited point light and lamp.
        session.update({"lights.1.radiance": {"value": 0.2}})
        session.step()
        _same_bits(session, _fresh(scene_file, {"lights.1.radiance": {"value": 0.2}}))
