"""The same glTF file rendered by spectrace (`import-gltf`) and by Cycles after Blender's own glTF importer
(tests/interop/gltf_cycles.py, in a child process), at the camera spectrace imported, the same lights and the same
exposure: block means of 8×8 pixels and the whole image's mean, per channel.

The exposure: a uniform white environment of radiance 1 is pixel value 1 in both. glTF's lights are photometric;
Blender's importer turns I candela into a light of 4π I / 683 W, whose Cycles pixel values are spectrace's film
values (Y = ∫ L ȳ dλ / ∫ ȳ dλ, with L in W/(m² sr nm)) times ∫ ȳ dλ, the CIE 1931 ȳ summed at 1 nm over
360–830 nm, 106.857 nm; lux likewise. An emissive strength is 683 ∫ ȳ dλ times brighter in Cycles (see the
emissive test).

The allowance for RGB against spectral transport and the two principled models is measured on grey versions of
the files first (every material grey, metallic 0, roughness 1, no textures), where the two renderers must agree
closely; the tolerance of a block adds 4 σ of the difference of two independent estimates, σ from spectrace's
per-pixel standard error (Cycles' noise taken as equal at equal samples). The sample assets are public files kept
outside the repository: SPECTRACE_GLTF_SAMPLES names the folder that holds them (the glTF-Sample-Models names
below, searched under it); without it, or without bpy, those tests skip saying why. The test on a file it writes
itself runs wherever bpy is installed."""

from __future__ import annotations

import importlib.util
import json
import os
import struct
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from tests.interop.gltf_builder import Gltf

HAS_BPY = importlib.util.find_spec("bpy") is not None
needs_bpy = pytest.mark.skipif(
    not HAS_BPY, reason="bpy (Blender as a Python module, installed apart: pip install bpy) is absent"
)
ROOT = Path(__file__).resolve().parents[2]
SAMPLES = os.environ.get("SPECTRACE_GLTF_SAMPLES")
Y_INTEGRAL_NM = 106.857  # ∫ ȳ dλ of CIE 1931 over 360–830 nm: photometric lights' Cycles/spectrace ratio
BLOCK = 8
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 Y of linear sRGB


def _cycles(model: Path, view: dict, out: Path) -> np.ndarray:
    from spectrace.io.exr import read_exr

    view_file = out.with_suffix(".json")
    view_file.write_text(json.dumps(view))
    env = os.environ.copy()
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    args = [sys.executable, "-m", "tests.interop.gltf_cycles", str(model), str(view_file), str(out)]
    done = subprocess.run(args, capture_output=True, text=True, env=env, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return read_exr(out)[0]["RGBA"][..., :3]


def _spectrace(
    model: Path, tmp_path: Path, width: int, spp: int, materials: str
) -> tuple[np.ndarray, np.ndarray, dict]:
    """(linear sRGB, per-pixel standard error of Y, the view Cycles is to share) of spectrace's render."""
    from spectrace.api import render
    from spectrace.interop.gltf import import_gltf
    from spectrace.scene import load_scene

    toml = tmp_path / f"{model.stem}.toml"
    import_gltf(model, toml, material_model=materials)
    data = tomllib.loads(toml.read_text(encoding="utf-8"))
    scene = load_scene(toml)
    height = max(BLOCK, round(width * scene.height / scene.width / BLOCK) * BLOCK)
    scene = scene.with_overrides(width=width, height=height, spp=spp, seed=1)
    image = render(scene, progress=False, aovs="variance")
    camera = data["camera"]
    assert camera["type"] == "perspective" and camera.get("fov_axis") == "y"
    view = {
        "origin": camera["origin"],
        "target": camera["target"],
        "up": camera.get("up", [0.0, 1.0, 0.0]),
        "fov": camera["fov"],
        "width": width,
        "height": height,
        "spp": spp,
        "environment": any(light["type"] == "constant" for light in data.get("lights", [])),
    }
    return image.to_linear_srgb(), image.aovs["variance"].reshape(height, width), view


def _blocks(image: np.ndarray) -> np.ndarray:
    h, w = image.shape[:2]
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, -1).mean(axis=(1, 3))


def compare(
    model: Path, tmp_path: Path, width: int = 64, spp: int = 64, exposure: float = 1.0, materials: str = "principled"
) -> dict:
    """Block means (8×8 pixels) of Cycles' render over spectrace's (times `exposure`), per channel, the relative
    standard error of each block of spectrace's, and the image means' ratio."""
    ours, stderr, view = _spectrace(model, tmp_path, width, spp, materials)
    ours = ours * exposure
    theirs = _cycles(model, view, tmp_path / f"{model.stem}_cycles.exr")
    assert theirs.shape == ours.shape
    ours_blocks, theirs_blocks = _blocks(ours), _blocks(theirs)
    luminance = _blocks(ours @ LUMINANCE)[..., 0]
    block_stderr = np.sqrt(_blocks(stderr[..., None] ** 2)[..., 0] / BLOCK**2) * exposure
    return {
        "ratio": theirs_blocks / np.maximum(ours_blocks, 1e-12),
        "sigma": block_stderr / np.maximum(luminance, 1e-12),
        "luminance": luminance,
        "mean": theirs.mean(axis=(0, 1)) / ours.mean(axis=(0, 1)),
        "channels": ours_blocks,
    }


def _check(result: dict, allowance: float, mean_allowance: float) -> None:
    """Every block bright enough to measure within the allowance plus 4 σ of the difference of two renders,
    and the image mean within its own allowance."""
    lit = result["luminance"] > 0.02 * result["luminance"].max()
    assert lit.sum() >= 4, "too few lit blocks to compare"
    tolerance = allowance + 4.0 * np.sqrt(2.0) * result["sigma"]
    # a channel far below the block's brightest (the blue of a red box) is too noisy to compare on its own
    measured = result["channels"] >= 0.2 * result["channels"].max(axis=-1, keepdims=True)
    deviation = np.where(measured, np.abs(result["ratio"] - 1.0), 0.0).max(axis=-1)
    bad = lit & (deviation > tolerance)
    assert not bad.any(), (
        f"blocks {np.argwhere(bad).tolist()} off by {deviation[bad].round(3).tolist()} "
        f"(tolerance {tolerance[bad].round(3).tolist()})"
    )
    assert np.all(np.abs(result["mean"] - 1.0) < mean_allowance), result["mean"]


def grey_copy(model: Path, out: Path) -> Path:
    """The file with every material grey (base colour 0.5, metallic 0, roughness 1, no textures or extensions),
    written as a .glb beside nothing else: buffers that are files are read and packed into its BIN chunk."""
    from spectrace.interop.gltf.document import GltfDocument

    doc = GltfDocument(model)
    document = json.loads(json.dumps(doc.json))
    for material in document.get("materials", []):
        keep = {k: material[k] for k in ("name", "doubleSided") if k in material}
        material.clear()
        material.update(keep, pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0})
    for key in ("textures", "images", "samplers"):
        document.pop(key, None)
    document.pop("extensionsRequired", None)
    document["extensionsUsed"] = [name for name in document.get("extensionsUsed", []) if "materials" not in name]
    # every buffer packed into one, the views moved by its offset
    data = bytearray()
    offsets = []
    for index in range(len(document.get("buffers", []))):
        data += b"\0" * (-len(data) % 4)
        offsets.append(len(data))
        data += doc.buffer(index, f"/buffers/{index}")
    for view in document.get("bufferViews", []):
        view["byteOffset"] = view.get("byteOffset", 0) + offsets[view["buffer"]]
        view["buffer"] = 0
    data += b"\0" * (-len(data) % 4)
    document["buffers"] = [{"byteLength": len(data)}]
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(data), 0x004E4942) + data
    out.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)
    return out


def _box(gltf: Gltf, low, high, material: int) -> int:
    """A closed box with outward normals, flat per face."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    positions, normals, indices = [], [], []
    for axis in range(3):
        for side in (0, 1):
            normal = np.zeros(3)
            normal[axis] = 1.0 if side else -1.0
            u, v = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                point = np.empty(3)
                point[axis] = (low, high)[side][axis]
                point[u] = (low, high)[a][u]
                point[v] = (low, high)[b][v]
                corners.append(point)
            base = len(positions)
            positions += corners
            normals += [normal] * 4
            order = [0, 1, 2, 0, 2, 3] if side else [0, 2, 1, 0, 3, 2]
            indices += [base + i for i in order]
    return gltf.mesh(np.array(positions), indices, np.array(normals), material=material)


def lit_scene(path: Path, grey: bool, emissive: bool = False) -> Path:
    """A floor, a box and a textured panel seen by the file's camera, lit by a point light (candela) and a
    directional light (lux), or (`emissive`) by a double-sided emissive square above them (nits, with
    KHR_materials_emissive_strength); `grey`: every material a grey of 0.5 with no texture."""
    gltf = Gltf()
    # no specular layer: Blender's Principled BSDF is then Lambertian, as spectrace's import with diffuse materials
    lambert = {"extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
    gltf.json["extensionsUsed"] = ["KHR_materials_specular"]
    floor = gltf.material(
        pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}, **lambert
    )
    if grey:
        box = panel = floor
    else:
        box = gltf.material(
            pbrMetallicRoughness={"baseColorFactor": [0.8, 0.25, 0.1, 1.0], "metallicFactor": 0.0}, **lambert
        )
        checker = np.kron((np.indices((4, 4)).sum(axis=0) % 2)[..., None], np.ones((8, 8, 1)))
        pixels = np.where(checker > 0, [40, 160, 220], [230, 220, 60]).astype(np.uint8)
        texture = gltf.image_texture(pixels, {"magFilter": 9728, "minFilter": 9728})
        panel = gltf.material(
            pbrMetallicRoughness={"baseColorTexture": {"index": texture}, "metallicFactor": 0.0},
            doubleSided=True,
            **lambert,
        )
    gltf.node(mesh=gltf.quad(3.0, floor), rotation=[-0.7071068, 0.0, 0.0, 0.7071068])  # z up → y up: the floor
    gltf.node(mesh=_box(gltf, [-1.2, 0.0, -0.6], [-0.2, 1.0, 0.4], box))
    gltf.node(mesh=gltf.quad(0.7, panel), translation=[0.8, 0.8, -0.5], rotation=[0.0, -0.2588190, 0.0, 0.9659258])
    if emissive:
        glowing = gltf.material(
            pbrMetallicRoughness={"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
            emissiveFactor=[1.0, 0.9, 0.8],
            doubleSided=True,
            extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 500.0}, **lambert["extensions"]},
        )
        gltf.json["extensionsUsed"].append("KHR_materials_emissive_strength")
        gltf.node(mesh=gltf.quad(0.5, glowing), translation=[0.3, 2.5, 0.5], rotation=[0.7071068, 0.0, 0.0, 0.7071068])
    else:
        point = gltf.light(type="point", intensity=4000.0, color=[1.0, 0.9, 0.8])
        gltf.node(extensions={"KHR_lights_punctual": {"light": point}}, translation=[0.5, 2.5, 1.5])
        sun = gltf.light(type="directional", intensity=300.0)
        # its node's −z turned to shine along (−0.31, −0.74, −0.60): down, to the left and away from the camera
        gltf.node(extensions={"KHR_lights_punctual": {"light": sun}}, rotation=[-0.3946, 0.2114, 0.0864, 0.8897])
    camera = gltf.camera(type="perspective", perspective={"yfov": 0.8, "aspectRatio": 1.0, "znear": 0.01})
    gltf.node(camera=camera, translation=[0.0, 1.6, 4.5], rotation=[-0.1305262, 0.0, 0.0, 0.9914449])
    return gltf.write(path)


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
@pytest.mark.parametrize(
    "grey, emissive", [(True, False), (False, False), (False, True)], ids=["grey", "coloured", "emissive"]
)
def test_a_lit_gltf_renders_as_cycles_renders_it(tmp_path, grey, emissive):
    """A floor, a coloured box and a textured panel lit by a point light and a directional light in glTF's
    photometric units, or by an emissive square in nits, Lambertian in both renderers (no specular layer in the
    file; spectrace's import with diffuse materials), at 64×64 and 64 spp each. Measured on the grey version:
    every block within 1.9 % (median 0.5 %), the means within 0.1 %: the light units agree. The coloured version
    (RGB colours and a texture uplifted to spectra, against Cycles' RGB) within 5.0 % at a noisy block on the
    panel's edge, median 0.6 %, means within 0.3 %; lit by the emissive square within 5.5 %, median 0.7 %, means
    within 0.3 %. The allowance, 4 % a block besides 4 σ and 2 % the mean, covers them.

    Blender's importer reads an emissive strength S as Cycles' emission strength S (a pixel value of S, as many
    real-time engines take 1 to be a fully exposed pixel), where spectrace takes it in nits as glTF defines: the
    two differ by 683 lm/W · ∫ ȳ dλ."""
    model = lit_scene(tmp_path / "lit.glb", grey, emissive)
    exposure = Y_INTEGRAL_NM * (683.0 if emissive else 1.0)
    result = compare(model, tmp_path, width=64, spp=64, exposure=exposure, materials="diffuse")
    _check(result, allowance=0.04, mean_allowance=0.02)


# Public sample assets lit by spectrace's uniform white environment (none has lights of its own), found under
# SPECTRACE_GLTF_SAMPLES by file name. Measured at 64×64, 64 spp (largest block deviation, grey version then the
# file as it is): BoxTextured 4.9 % / 5.8 %, Duck 2.9 % / 3.8 %, 17_ior (transmission, ior) 1.7 % / 5.5 %,
# 19_sheen 1.9 % / 4.1 %; image means within 1 %. The grey versions' few percent are the two principled models
# (spectrace's follows Burley's with its retro-reflection, Blender's is energy-conserving layers), the rest the
# extensions' approximations (sheen) and noise in glass.
SAMPLE_ASSETS = ("BoxTextured.glb", "Duck.glb", "17_ior.gltf", "19_sheen.gltf")


def _sample(name: str) -> Path:
    if not SAMPLES:
        pytest.skip("SPECTRACE_GLTF_SAMPLES (a folder of the public glTF sample models) is not set")
    found = sorted(Path(SAMPLES).rglob(name))
    if not found:
        pytest.skip(f"{name} is not under SPECTRACE_GLTF_SAMPLES ({SAMPLES})")
    return found[0]


@needs_bpy
@pytest.mark.subprocess
@pytest.mark.slow
@pytest.mark.parametrize("name", SAMPLE_ASSETS)
def test_a_sample_asset_renders_as_cycles_renders_it(tmp_path, name):
    result = compare(_sample(name), tmp_path, width=64, spp=64)
    _check(result, allowance=0.07, mean_allowance=0.02)
