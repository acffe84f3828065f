"""The viewer's save of a scene built in Python: after edits from the page, the saved scene file, read back by the
loader, renders the bits the view shows (same seed, size and samples)."""

from dataclasses import replace

import numpy as np
import pytest
from tests.render.test_session_python import build
from tests.viewer.conftest import _close, _open

import spectrace


@pytest.mark.slow
def test_saving_a_python_scene_after_an_edit_writes_the_view(tmp_path):
    live, server, client = _open(replace(build(), width=16, height=12, spp=2), tmp_path)
    try:
        client.wait_done()
        edit = {"materials.box.reflectance": [0.1, 0.6, 0.2], "lights.0.power": 35.0}
        assert client.post("/api/update", {"changes": edit})[0] == 200
        assert client.post("/api/display", {"exposure": 0.5})[0] == 200
        client.wait_done()
        status, reply = client.post("/api/save", {"kind": "scene", "name": "built.toml"})
        assert status == 200, reply
        saved = spectrace.load_scene(server.save_folder / "built.toml")
        assert (saved.width, saved.height, saved.spp, saved.exposure) == (16, 12, 2, 0.5)
        fresh = spectrace.render(saved, device=live.session.image().device, progress=False)
        assert np.array_equal(fresh.xyz, live.image().xyz)
        # The edit is in the file: the unedited scene renders other bits.
        unedited = spectrace.render(replace(build(), width=16, height=12, spp=2), progress=False)
        assert not np.array_equal(unedited.xyz, fresh.xyz)
        status, reply = client.post("/api/save", {"kind": "scene", "name": "../out.toml"})
        assert status != 200 and "name" in reply["error"] and "\n" not in reply["error"]
    finally:
        _close(live, server)
