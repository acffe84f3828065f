"""An anisotropic lobe in the frame a mesh file's tangents give, against Mitsuba 3 with the same frame made from the
texture coordinates. Mitsuba frames its BSDFs along dp/du and does not read tangents; a floor whose uvs are turned
by 60° about its normal has dp/du along (cos 60°, sin 60°, 0) there. spectrace gets the same turned square with uvs
planar in x and y (dp/du along x) and supplied tangents along Mitsuba's dp/du: the highlight must stretch as
Mitsuba's does.
The scene and the comparison are test_mitsuba_principled_anisotropic's (replicas within 5 standard errors)."""

import numpy as np
import pytest

from materials.test_mitsuba_materials import _scene
from materials.test_mitsuba_principled import BLOCK
from materials.test_mitsuba_principled_anisotropic import ANISOTROPIC_METAL, CASES, GREY, LIGHT
from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.mitsuba.export import mitsuba_film_xyz
from spectrace.interop.pbrt.meshes import MeshData, write_ply

pytestmark = pytest.mark.peer

TURN = np.radians(60.0)
TURNED_FLOOR = CASES[2][1]  # Mitsuba's rectangle turned 60° about its normal: dp/du along (cos 60°, sin 60°, 0)


def _supplied_floor(path) -> None:
    """The same turned square as triangles whose uvs are not turned (dp/du along x) and whose tangents are along
    the turned rectangle's dp/du."""
    c, s = np.cos(TURN), np.sin(TURN)
    square = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    corners = np.column_stack([square @ np.array([[c, s], [-s, c]]), np.zeros(4)])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    tangents = np.tile([c, s, 0.0, 1.0], (4, 1))
    uvs = 0.5 * (corners[:, :2] + 1.0)  # planar in x and y: dp/du along x
    write_ply(path, MeshData(corners, np.array([[0, 1, 2], [0, 2, 3]]), normals, uvs, tangents))


@pytest.mark.slow
def test_supplied_tangents_frame_an_anisotropic_lobe_as_mitsubas_dpdu(tmp_path, device, mitsuba_scalar_spectral):
    """Measured (12 replicas of 64 spp, Intel's CPU runtime): largest block 3.7 σ, whole image 1.2 σ (as
    test_mitsuba_principled_anisotropic's turned floor, whose frame this is); the same floor without its tangents
    (dp/du along x) fails at 8.6 σ."""
    mi = mitsuba_scalar_spectral
    _supplied_floor(tmp_path / "floor.ply")
    ours_body = f"""
    <shape type="sphere"><transform name="to_world"></transform>{GREY}</shape>
    <shape type="ply"><string name="filename" value="floor.ply"/>
        <transform name="to_world"><scale value="4"/><translate value="0, 0, -1"/></transform>
        {ANISOTROPIC_METAL}</shape>{LIGHT}"""
    theirs_xml, ours_xml = tmp_path / "theirs.xml", tmp_path / "ours.xml"
    theirs_xml.write_text(_scene(TURNED_FLOOR, origin="0, -3.4, 0.8", max_depth=8))
    ours_xml.write_text(_scene(ours_body, origin="0, -3.4, 0.8", max_depth=8))
    replicas, spp = 12, 64
    mitsuba_scene = mi.load_file(str(theirs_xml))
    theirs = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=spp, seed=seed), mi) for seed in range(replicas)])
    scene = load_mitsuba_scene(ours_xml)
    assert scene.shapes[1].mesh.tangents is not None
    ours = spectrace_replicas(Renderer(scene, device), replicas, spp)
    assert theirs[..., 1].mean() > 0.02  # a lit image
    assert_replicas_agree(ours, theirs, BLOCK, what="supplied tangents")
