"""A .blend mesh's MikkTSpace tangents in the import (spectrace.interop.blender.meshes): where a material shades a
mesh through a Normal Map, each exported vertex carries the tangent and bitangent sign Blender computes for its
face corners (Mesh.calc_tangents on the UV map the export reads), so that the normal map is framed as Cycles frames
it. Checked here corner by corner against Blender's own values, on a mirrored UV layout (sign −1 on one half) and
a smooth sphere; the rendering against Cycles is test_blender_cycles.py's `normal_mapped`. Skips where bpy is
absent."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from tests.cli_runner import run_spectrace

ROOT = Path(__file__).resolve().parents[2]
needs_bpy = pytest.mark.skipif(
    importlib.util.find_spec("bpy") is None,
    reason="bpy (Blender as a Python module, installed apart: pip install bpy) is absent",
)


def _child(*args: str) -> None:
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
def test_normal_mapped_meshes_carry_blenders_tangents_and_signs(tmp_path):
    from spectrace.geometry.mesh import load_mesh

    blend, toml, corners = tmp_path / "nm.blend", tmp_path / "nm.toml", tmp_path / "corners.npz"
    module = "tests.interop.blender_comparisons"
    _child("-m", module, "normal_mapped_ball", str(blend), str(tmp_path / "c"), "1", "0")
    _child("-m", module, "--tangents", str(blend), str(corners))
    done = run_spectrace("import-blend", str(blend), "-o", str(toml))
    assert done.returncode == 0, done.stderr
    shapes = {s.get("name"): s for s in tomllib.loads(toml.read_text(encoding="utf-8"))["shapes"]}
    blender = np.load(corners)
    for name in ("poster", "ball"):
        mesh = load_mesh(toml.parent / shapes[name]["file"], name)
        assert mesh.tangents is not None and mesh.normals is not None, name
        # each Blender corner is an exported vertex of the same position, UV (the file's v runs down the image),
        # tangent and sign, and each exported vertex is a corner: at the mirror seam two corners share position
        # and UV and differ in the tangent alone, so the whole row is matched
        exported = np.column_stack([mesh.vertices, mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1], mesh.tangents])
        expected = blender[name]
        distance = np.abs(exported[None, :, :] - expected[:, None, :]).max(axis=2)
        assert distance.min(axis=1).max() < 1e-6, name  # float32 in the file
        assert distance.min(axis=0).max() < 1e-6, name
        signs = set(expected[:, 8])
        assert signs == ({-1.0, 1.0} if name == "poster" else {1.0}), (name, signs)
    # the room has no normal map: no tangents written for it
    assert load_mesh(toml.parent / shapes["room"]["file"], "room").tangents is None
