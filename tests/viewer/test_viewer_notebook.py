"""`spectrace.view(scene)` in a notebook, executed headless (nbclient, ipykernel): the live view as a frame onto the
viewer's page, and the scene edited from code while it renders, giving the image a fresh render of the edited scene
gives."""

import json
import os

import pytest

nbformat = pytest.importorskip("nbformat", reason="the notebook test needs nbformat (the viewer-test extra)")
nbclient = pytest.importorskip("nbclient", reason="the notebook test needs nbclient (the viewer-test extra)")
pytest.importorskip("ipykernel", reason="the notebook test needs ipykernel (the viewer-test extra)")

pytestmark = [pytest.mark.subprocess, pytest.mark.slow]

SETUP = """
import json, urllib.request
import numpy as np
import spectrace
from spectrace.resources import scenes_dir
scene = spectrace.load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=24, height=16, spp=3)
widget = spectrace.view(scene, save_folder={folder!r})
widget
"""
EDIT = """
first = widget.wait(timeout=300)
widget.session.update({"camera.fov": 30.0})
done = widget.wait(timeout=300)
state = json.load(urllib.request.urlopen(widget.url.replace("/?", "/api/state?")))
fresh = spectrace.render(widget.session.scene, progress=False)
print(json.dumps({
    "first": first, "done": done, "page_spp": state["spp"],
    "fov": widget.session.parameters()["camera.fov"], "same_bits": bool(np.array_equal(widget.image().xyz, fresh.xyz)),
}))
widget.close()
"""


def test_the_widget_renders_and_takes_edits_from_code(tmp_path):
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(SETUP.format(folder=str(tmp_path))), nbformat.v4.new_code_cell(EDIT)]
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3", resources={"metadata": {}})
    client.execute(env=os.environ.copy())
    shown = notebook.cells[0].outputs[0]["data"]["text/html"]
    assert "<iframe" in shown and "http://127.0.0.1:" in shown and "token=" in shown
    printed = json.loads("".join(o.get("text", "") for o in notebook.cells[1].outputs))
    # The image after the edit is a fresh render's of the edited scene: the accumulation restarted.
    assert printed["first"] == 3
    assert printed["done"] == 3 and printed["page_spp"] == 3 and printed["fov"] == 30.0
    assert printed["same_bits"]
