"""glTF's TANGENT attribute (glTF 2.0, 3.7.2.1) frames normal maps where a model supplies it: the map's x along
the supplied tangent, its y along cross(normal, tangent) · w, whatever the texture layout's dp/du says.

A plane under a directional light, seen from above, with a constant normal map tilted off its normal: a Lambertian
surface's radiance is ρ E cos θ / π with θ the angle between the light and the turned normal, so the mapped plane
over the plain one is (n · l) / (N · l), n = a T + b B + c N with (T, B) the supplied frame and (a, b, c) the
texel's 2c/255 − 1. The layouts chosen make the supplied frame disagree with dp/du (as in Khronos'
NormalTangentMirrorTest's mirror cells), so a renderer that ignored TANGENT gives another, stated, value. One bounce
from a delta light with the same seed in both renders: the ratio is exact to float rounding."""

from __future__ import annotations

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf
from tests.interop.test_gltf_normal_tangents import LAYOUTS, LIGHT, TEXEL, _quaternion_to

S = 3.0
Z = np.array([0.0, 0.0, 1.0])
# name: (glTF texture coordinates of the corners, the supplied tangent (xyz, w))
CASES = {
    "reversed": (LAYOUTS["upright"][0], [-1.0, 0.0, 0.0, 1.0]),
    "left_handed": (LAYOUTS["upright"][0], [0.0, -1.0, 0.0, -1.0]),
    "mirror_cell": (LAYOUTS["mirrored_u"][0], [1.0, 0.0, 0.0, 1.0]),
}


def _expected(tangent, normal=Z) -> float:
    """(n · l) / (N · l) of the frame glTF defines from `tangent` (xyz, w) about `normal`."""
    t = np.asarray(tangent[:3], float)
    b = np.cross(normal, t) * tangent[3]
    a, bb, c = 2.0 * TEXEL / 255.0 - 1.0
    n = a * t + bb * b + c * normal
    return float((n / np.linalg.norm(n)) @ LIGHT / (normal @ LIGHT))


def _write(path, corners, uvs, tangent, normal_map: bool, nodes=({},)):
    gltf = Gltf()
    material: dict = {
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0},
        "doubleSided": True,
    }
    if normal_map:
        pixels = np.broadcast_to(TEXEL.astype(np.uint8), (4, 4, 3))
        material["normalTexture"] = {"index": gltf.image_texture(pixels, {"magFilter": 9728, "minFilter": 9728})}
    positions = np.column_stack([corners, np.zeros(4)])
    mesh = gltf.mesh(positions, [0, 1, 2, 0, 2, 3], [[0, 0, 1]] * 4, uvs, gltf.material(**material))
    gltf.json["meshes"][mesh]["primitives"][0]["attributes"]["TANGENT"] = gltf.accessor([tangent] * 4)
    for node in nodes:
        gltf.node(mesh=mesh, **node)
    sun = gltf.light(type="directional", intensity=100.0)
    gltf.node(extensions={"KHR_lights_punctual": {"light": sun}}, rotation=_quaternion_to(-LIGHT))
    camera = gltf.camera(type="perspective", perspective={"yfov": 0.5, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 0.0, 2.0])
    return gltf.write(path)


def _render(path, tmp_path) -> np.ndarray:
    from spectrace.api import render
    from spectrace.interop.gltf import import_gltf
    from spectrace.scene import load_scene

    toml = tmp_path / f"{path.stem}.toml"
    import_gltf(path, toml, material_model="diffuse")
    scene = load_scene(toml).with_overrides(width=8, height=8, spp=4, seed=3)
    return render(scene, progress=False).xyz[..., 1]


def _ratio(tmp_path, corners, uvs, tangent, nodes=({},)) -> np.ndarray:
    mapped = _render(_write(tmp_path / "mapped.glb", corners, uvs, tangent, True, nodes), tmp_path)
    plain = _render(_write(tmp_path / "plain.glb", corners, uvs, tangent, False, nodes), tmp_path)
    assert plain.min() > 0.0
    return mapped / plain


SQUARE = np.array([[-S, -S], [S, -S], [S, S], [-S, S]])


@pytest.mark.parametrize("case", CASES)
def test_supplied_tangents_frame_the_normal_map(tmp_path, case):
    uvs, tangent = CASES[case]
    layout = "mirrored_u" if case == "mirror_cell" else "upright"
    _, along_u, up = LAYOUTS[layout]
    # What dp/du with the layout's handedness (the frame without TANGENT) gives: a different value, so the check
    # below can fail.
    handedness = float(np.sign(np.cross(Z, along_u) @ up))
    assert abs(_expected([*along_u, handedness]) - _expected(tangent)) > 0.05
    np.testing.assert_allclose(_ratio(tmp_path, SQUARE, uvs, tangent), _expected(tangent), rtol=2e-5)


def test_a_mirroring_instance_mirrors_the_supplied_frame(tmp_path):
    """One half-plane mesh placed twice (an instanced object): as it is on the right, mirrored in x on the left.
    The mirror takes the tangent to M t and w to −w (the surface's v direction moves with it, its normal stays), so
    the left half shades with the frame (M t, −w)."""
    uvs, tangent = CASES["reversed"]
    half = np.array([[0.0, -S], [S, -S], [S, S], [0.0, S]])
    ratio = _ratio(tmp_path, half, uvs, tangent, nodes=({}, {"scale": [-1.0, 1.0, 1.0]}))
    mirrored = [-tangent[0], tangent[1], tangent[2], -tangent[3]]
    assert abs(_expected(mirrored) - _expected(tangent)) > 0.05
    # Columns away from the seam at x = 0 (the pixel filter spans neighbours); image x runs along world +x.
    np.testing.assert_allclose(ratio[:, 5:], _expected(tangent), rtol=2e-5)
    np.testing.assert_allclose(ratio[:, :3], _expected(mirrored), rtol=2e-5)


def test_the_import_writes_the_instanced_object_once(tmp_path):
    from spectrace.interop.gltf import import_gltf

    uvs, tangent = CASES["reversed"]
    half = np.array([[0.0, -S], [S, -S], [S, S], [0.0, S]])
    path = _write(tmp_path / "twice.glb", half, uvs, tangent, True, nodes=({}, {"scale": [-1.0, 1.0, 1.0]}))
    import_gltf(path, tmp_path / "twice.toml", material_model="diffuse")
    assert "[[instances]]" in (tmp_path / "twice.toml").read_text()
