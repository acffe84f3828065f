"""glTF 2.0 import: what the file's JSON and buffers hold, read back from the scene data against values computed
here from the glTF specification (accessors, node transforms, cameras, texture channels and transforms, alpha
modes, instancing) and the one-line errors for what cannot be read."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from PIL import Image
from tests.interop.gltf_builder import FLOAT, UINT8, UINT16, Gltf

from spectrace.errors import SpectraceError
from spectrace.interop.gltf import gltf_scene_data


def _data(tmp_path, gltf: Gltf, suffix: str = ".glb", **options):
    path = gltf.write(tmp_path / f"model{suffix}")
    return gltf_scene_data(path, tmp_path / "out.toml", **options)


def _mesh_vertices(ctx, shape: dict) -> np.ndarray:
    return ctx.meshes[shape["file"]].vertices


def _world(steps: list[dict]) -> np.ndarray:
    return np.array(steps[0]["matrix"]) if steps else np.eye(4)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_positions_indices_normals_and_uvs_read_from_either_container(tmp_path, suffix):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad(size=2.0))
    data, ctx = _data(tmp_path, gltf, suffix)
    (shape,) = data["shapes"]
    mesh = ctx.meshes[shape["file"]]
    np.testing.assert_array_equal(mesh.vertices, [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]])
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(mesh.normals, [[0, 0, 1]] * 4)
    # glTF's v runs down the image, a PLY's up: the file gets 1 − v
    np.testing.assert_array_equal(mesh.uvs, [[0, 0], [1, 0], [1, 1], [0, 1]])


def test_strided_normalized_and_sparse_accessors(tmp_path):
    """Interleaved positions (byteStride), normalized uint8 texture coordinates (c / 255) and a sparse accessor
    that replaces two of the positions, as glTF 2.0, 3.6.2 lays them out."""
    gltf = Gltf()
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    pad = np.full((3, 1), 7.0, np.float32)
    interleaved = np.hstack([positions, pad])  # 16-byte stride, the 4th float skipped
    view = gltf.view(interleaved.tobytes(), stride=16)
    gltf.json["accessors"] = [{"bufferView": view, "componentType": FLOAT, "count": 3, "type": "VEC3"}]
    uv = gltf.accessor(np.array([[0, 255], [255, 255], [0, 51]]), UINT8, normalized=True)
    sparse_indices = gltf.view(np.array([2], "<u2").tobytes())
    sparse_values = gltf.view(np.array([[0, 3, 0]], "<f4").tobytes())
    gltf.json["accessors"][0]["sparse"] = {
        "count": 1,
        "indices": {"bufferView": sparse_indices, "componentType": UINT16},
        "values": {"bufferView": sparse_values},
    }
    gltf.json["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": uv}}]}]
    gltf.node(mesh=0)
    data, ctx = _data(tmp_path, gltf)
    mesh = ctx.meshes[data["shapes"][0]["file"]]
    np.testing.assert_array_equal(mesh.vertices, [[0, 0, 0], [1, 0, 0], [0, 3, 0]])
    np.testing.assert_allclose(mesh.uvs, [[0, 0], [1, 0], [0, 0.8]])


def test_triangle_strips_and_fans_keep_one_winding(tmp_path):
    gltf = Gltf()
    square = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    gltf.node(mesh=gltf.mesh(square, mode=5))
    gltf.node(mesh=gltf.mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], mode=6))
    data, ctx = _data(tmp_path, gltf)
    for shape in data["shapes"]:
        mesh = ctx.meshes[shape["file"]]
        a, b, c = (mesh.vertices[mesh.faces[:, i]] for i in range(3))
        normals = np.cross(b - a, c - a)
        assert len(mesh.faces) == 2 and np.all(normals[:, 2] > 0), "every triangle faces +z, as the first"


def test_node_hierarchy_composes_translation_rotation_scale_and_matrices(tmp_path):
    """A child's world transform is parent · child, each local one T · R · S (quaternion x, y, z, w) or a
    column-major matrix; checked on a vertex against the same maps applied step by step."""
    from scipy.spatial.transform import Rotation

    q = Rotation.from_euler("xyz", [30, -50, 80], degrees=True)
    gltf = Gltf()
    mesh = gltf.mesh([[1, 2, 3], [0, 0, 0], [1, 0, 0]])
    parent_matrix = np.eye(4)
    parent_matrix[:3, 3] = [5, -1, 2]
    parent_matrix[:3, :3] = np.diag([2, 2, 2])
    child = gltf.node(root=False, mesh=mesh, translation=[0, 1, 0], rotation=q.as_quat().tolist(), scale=[1, 3, 1])
    gltf.node(matrix=parent_matrix.T.reshape(-1).tolist(), children=[child])
    data, ctx = _data(tmp_path, gltf)
    (shape,) = data["shapes"]
    world = _world(shape["transform"])
    point = np.array([1.0, 2.0, 3.0])
    expected = parent_matrix[:3, :3] @ (q.apply(point * [1, 3, 1]) + [0, 1, 0]) + parent_matrix[:3, 3]
    np.testing.assert_allclose(world[:3, :3] @ point + world[:3, 3], expected, atol=1e-12)


def test_a_mesh_placed_by_several_nodes_is_one_object_with_instances(tmp_path):
    gltf = Gltf()
    mesh = gltf.quad(name="tile")
    for x in (0.0, 3.0, 6.0):
        gltf.node(mesh=mesh, translation=[x, 0, 0])
    data, _ = _data(tmp_path, gltf)
    assert "shapes" not in data
    assert list(data["objects"]) == ["tile"]
    offsets = [_world(instance.get("transform", []))[0, 3] for instance in data["instances"]]
    assert [instance["object"] for instance in data["instances"]] == ["tile"] * 3
    assert offsets == [0.0, 3.0, 6.0]


def test_an_emissive_mesh_placed_twice_is_two_emitting_shapes(tmp_path):
    """Objects hold no emitters (as Mitsuba's shape groups): each placement of an emitting mesh is a shape."""
    gltf = Gltf()
    glowing = gltf.material(emissiveFactor=[1, 1, 1])
    mesh = gltf.quad(material=glowing)
    gltf.node(mesh=mesh)
    gltf.node(mesh=mesh, translation=[0, 0, 2])
    data, _ = _data(tmp_path, gltf)
    assert "objects" not in data and len(data["shapes"]) == 2
    assert all("emitter" in shape for shape in data["shapes"])


def test_a_node_scaled_to_zero_is_left_out(tmp_path):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad(), scale=[0, 0, 0])
    gltf.node(mesh=gltf.quad())
    data, ctx = _data(tmp_path, gltf)
    assert len(data["shapes"]) == 1 and any("scaled to nothing" in note for note in ctx.notes)


# ---------------------------------------------------------------- cameras


def _two_cameras(gltf: Gltf) -> None:
    perspective = gltf.camera(
        type="perspective", name="wide", perspective={"yfov": 0.8, "aspectRatio": 2.0, "znear": 0.05, "zfar": 50}
    )
    ortho = gltf.camera(
        type="orthographic", name="plan", orthographic={"xmag": 3.0, "ymag": 1.5, "znear": 0.1, "zfar": 9}
    )
    # looking down: rotated -90° about x, so the camera's −z is the world's −y and its +y the world's −z
    half = math.sqrt(0.5)
    gltf.node(camera=perspective, translation=[0, 1, 5], name="front")
    gltf.node(camera=ortho, translation=[0, 4, 0], rotation=[-half, 0, 0, half], name="top")


def test_the_first_camera_is_imported_with_its_field_of_view_clip_and_aspect(tmp_path):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    _two_cameras(gltf)
    data, _ = _data(tmp_path, gltf)
    camera, film = data["camera"], data["film"]
    assert camera["type"] == "perspective" and camera["fov_axis"] == "y"
    assert camera["fov"] == pytest.approx(math.degrees(0.8))
    assert camera["origin"] == [0, 1, 5] and camera["target"] == [0, 1, 4] and camera["up"] == [0, 1, 0]
    assert (camera["near_clip"], camera["far_clip"]) == (0.05, 50)
    assert film["width"] / film["height"] == pytest.approx(2.0)


@pytest.mark.parametrize("choice", ["1", "plan", "top"])
def test_a_camera_chosen_by_index_or_name(tmp_path, choice):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    _two_cameras(gltf)
    data, _ = _data(tmp_path, gltf, camera=choice)
    camera, film = data["camera"], data["film"]
    assert camera["type"] == "orthographic" and camera["view_width"] == 6.0
    np.testing.assert_allclose(camera["origin"], [0, 4, 0])
    np.testing.assert_allclose(np.subtract(camera["target"], camera["origin"]), [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(camera["up"], [0, 0, -1], atol=1e-12)
    assert film["width"] / film["height"] == pytest.approx(2.0)


def test_an_unknown_camera_choice_names_the_cameras(tmp_path):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    _two_cameras(gltf)
    with pytest.raises(SpectraceError, match=r"no camera 'side'.*0 \(wide\), 1 \(plan\)"):
        _data(tmp_path, gltf, camera="side")


def test_without_a_camera_one_frames_the_bounds(tmp_path):
    """Every corner of the scene's bounding box projects inside the default camera's image."""
    gltf = Gltf()
    gltf.node(mesh=gltf.quad(size=3.0), translation=[10, -2, 1], rotation=[0.3, 0.2, 0.1, 0.927])
    data, ctx = _data(tmp_path, gltf)
    camera, film = data["camera"], data["film"]
    mesh = next(iter(ctx.meshes.values()))
    world = _world(data["shapes"][0]["transform"])
    points = mesh.vertices @ world[:3, :3].T + world[:3, 3]
    forward = np.subtract(camera["target"], camera["origin"])
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, camera["up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    tan_y = math.tan(math.radians(camera["fov"]) / 2)
    tan_x = tan_y * film["width"] / film["height"]
    relative = points - camera["origin"]
    depth = relative @ forward
    assert np.all(depth > 0)
    assert np.all(np.abs(relative @ right) / depth <= tan_x) and np.all(np.abs(relative @ up) / depth <= tan_y)


# ---------------------------------------------------------------- materials and textures


def _written_png(tmp_path, ctx, name: str) -> np.ndarray:
    ctx.files[name](tmp_path / "written.png")
    return np.asarray(Image.open(tmp_path / "written.png"))


def test_metallic_from_blue_and_roughness_from_green_times_their_factors(tmp_path):
    rng = np.random.default_rng(3)
    pixels = rng.integers(0, 256, (4, 5, 3))
    gltf = Gltf()
    texture = gltf.image_texture(pixels)
    material = gltf.material(
        pbrMetallicRoughness={
            "metallicFactor": 0.5,
            "roughnessFactor": 1.0,
            "metallicRoughnessTexture": {"index": texture},
            "baseColorFactor": [0.2, 0.4, 0.6, 1.0],
        }
    )
    gltf.node(mesh=gltf.quad(material=material))
    data, ctx = _data(tmp_path, gltf)
    table = data["materials"]["material0"]
    assert table["type"] == "principled" and table["base_color"] == {"rgb": [0.2, 0.4, 0.6]}
    assert table["metallic"]["raw"] and table["roughness"]["raw"]
    np.testing.assert_array_equal(_written_png(tmp_path, ctx, table["roughness"]["file"]), pixels[..., 1])
    np.testing.assert_array_equal(
        _written_png(tmp_path, ctx, table["metallic"]["file"]), np.round(pixels[..., 2] * 0.5)
    )


def test_constant_metallic_roughness_and_the_extensions(tmp_path):
    gltf = Gltf()
    material = gltf.material(
        pbrMetallicRoughness={"metallicFactor": 0.25, "roughnessFactor": 0.7},
        extensions={
            "KHR_materials_ior": {"ior": 1.33},
            "KHR_materials_transmission": {"transmissionFactor": 0.9},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.2},
        },
        doubleSided=True,
    )
    gltf.node(mesh=gltf.quad(material=material))
    data, ctx = _data(tmp_path, gltf)
    assert data["materials"]["material0"] == {
        "type": "principled",
        "base_color": {"rgb": [1.0, 1.0, 1.0]},
        "metallic": 0.25,
        "roughness": 0.7,
        "eta": 1.33,
        "spec_trans": 0.9,
        "clearcoat": 0.5,
        "clearcoat_gloss": pytest.approx(0.8),
    }
    assert ctx.warnings == []


def test_the_default_material_is_white_metal_fully_rough_and_one_sided(tmp_path):
    """glTF 2.0, 3.9.6: a primitive without a material."""
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    data, _ = _data(tmp_path, gltf)
    (material,) = data["materials"].values()
    assert material == {
        "type": "principled",
        "base_color": {"rgb": [1.0, 1.0, 1.0]},
        "metallic": 1.0,
        "roughness": 1.0,
        "two_sided": False,
    }


def test_base_colour_texture_with_factor_wrap_filter_and_transform(tmp_path):
    """The factor multiplies the decoded (linear) texel; the sampler's wrap and nearest filter and
    KHR_texture_transform's offset and scale become the bitmap's keys; a rotation is a warning."""
    pixels = np.array([[[255, 128, 0], [10, 200, 90]]])
    gltf = Gltf()
    texture = gltf.image_texture(pixels, sampler={"wrapS": 33071, "wrapT": 33071, "magFilter": 9728})
    transform = {"offset": [0.25, 0.5], "scale": [2, 3]}
    info = {"index": texture, "extensions": {"KHR_texture_transform": transform}}
    material = gltf.material(pbrMetallicRoughness={"baseColorTexture": info, "baseColorFactor": [0.5, 1, 1, 1]})
    rotated = gltf.material(
        pbrMetallicRoughness={
            "baseColorTexture": {"index": texture, "extensions": {"KHR_texture_transform": {"rotation": 0.3}}}
        }
    )
    gltf.node(mesh=gltf.quad(material=material))
    gltf.node(mesh=gltf.quad(material=rotated))
    data, ctx = _data(tmp_path, gltf, material_model="diffuse")
    table = data["materials"]["material0"]["reflectance"]
    assert table["wrap"] == "clamp" and table["filter"] == "nearest"
    assert table["uv_scale"] == [2, 3] and table["uv_offset"] == [0.25, 0.5]
    written = _written_png(tmp_path, ctx, table["file"]).astype(float)
    linear = np.where(pixels / 255 <= 0.04045, pixels / 255 / 12.92, ((pixels / 255 + 0.055) / 1.055) ** 2.4)
    halved_red = linear[..., 0] * 0.5
    encoded = np.where(halved_red <= 0.0031308, 12.92 * halved_red, 1.055 * halved_red ** (1 / 2.4) - 0.055)
    np.testing.assert_array_equal(written[..., 0], np.round(encoded * 255))
    np.testing.assert_array_equal(written[..., 1:], pixels[..., 1:])
    assert any("rotation" in warning for warning in ctx.warnings)


def test_alpha_modes_become_opacity(tmp_path):
    alpha = np.array([[0, 100, 130, 255]])
    pixels = np.dstack([np.full((1, 4, 3), 200), alpha[..., None]])
    gltf = Gltf()
    texture = gltf.image_texture(pixels)
    with_map = {"baseColorTexture": {"index": texture}, "baseColorFactor": [1, 1, 1, 0.8]}
    masked = gltf.material(pbrMetallicRoughness=with_map, alphaMode="MASK", alphaCutoff=0.4)
    blended = gltf.material(pbrMetallicRoughness=with_map, alphaMode="BLEND")
    constant = gltf.material(pbrMetallicRoughness={"baseColorFactor": [1, 1, 1, 0.3]}, alphaMode="BLEND")
    opaque = gltf.material(pbrMetallicRoughness={"baseColorFactor": [1, 1, 1, 0.3]}, alphaMode="OPAQUE")
    for material in (masked, blended, constant, opaque):
        gltf.node(mesh=gltf.quad(material=material))
    data, ctx = _data(tmp_path, gltf)
    tables = [data["materials"][f"material{i}"] for i in range(4)]
    mask = _written_png(tmp_path, ctx, tables[0]["opacity"]["file"])
    np.testing.assert_array_equal(mask, np.where(alpha * 0.8 >= 0.4 * 255, 255, 0))
    blend = _written_png(tmp_path, ctx, tables[1]["opacity"]["file"])
    np.testing.assert_array_equal(blend, np.round(alpha * 0.8))
    assert tables[2]["opacity"] == 0.3 and "opacity" not in tables[3]


def test_a_normal_map_is_raw_and_double_sided_is_two_sided(tmp_path):
    gltf = Gltf()
    texture = gltf.image_texture(np.full((2, 2, 3), 128))
    material = gltf.material(normalTexture={"index": texture}, doubleSided=True)
    gltf.node(mesh=gltf.quad(material=material))
    data, _ = _data(tmp_path, gltf)
    table = data["materials"]["material0"]
    assert table["normal_map"]["raw"] is True and "two_sided" not in table


# ---------------------------------------------------------------- refusals


def _draco(gltf: Gltf) -> None:
    gltf.node(mesh=gltf.quad())
    gltf.json["extensionsUsed"] = gltf.json["extensionsRequired"] = ["KHR_draco_mesh_compression"]


def _bad_accessor(gltf: Gltf) -> None:
    gltf.node(mesh=gltf.quad())
    gltf.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99


def _overrunning_accessor(gltf: Gltf) -> None:
    gltf.node(mesh=gltf.quad())
    gltf.json["accessors"][0]["count"] = 400


def _cycle(gltf: Gltf) -> None:
    gltf.node(children=[1])
    gltf.node(root=False, children=[0])


@pytest.mark.parametrize(
    ("build", "where", "message"),
    [
        (_draco, "/extensionsRequired/0", "KHR_draco_mesh_compression"),
        (_bad_accessor, "/meshes/0/primitives/0/attributes/POSITION", "accessors[99], which does not exist"),
        (_overrunning_accessor, "/accessors/0", "400 elements from byte 0 run past its buffer view"),
        (_cycle, "/nodes/1/children/0", "reached twice"),
    ],
)
def test_refusals_name_the_file_and_json_pointer(tmp_path, build, where, message):
    gltf = Gltf()
    build(gltf)
    with pytest.raises(SpectraceError) as raised:
        _data(tmp_path, gltf)
    assert raised.value.where == f"{tmp_path / 'model.glb'}: {where}"
    assert message in raised.value.message


def test_a_truncated_glb_and_a_bad_data_uri_are_refused(tmp_path):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    path = gltf.write(tmp_path / "model.glb")
    path.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(SpectraceError, match="truncated"):
        gltf_scene_data(path)
    document = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": "data:application/octet-stream;base64,@@", "byteLength": 4}],
    }
    document["accessors"] = [{"bufferView": 0, "componentType": FLOAT, "count": 1, "type": "VEC3"}]
    document["bufferViews"] = [{"buffer": 0, "byteLength": 4}]
    document["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0}}]}]
    document["nodes"] = [{"mesh": 0}]
    (tmp_path / "bad.gltf").write_text(json.dumps(document))
    with pytest.raises(SpectraceError, match="base64") as raised:
        gltf_scene_data(tmp_path / "bad.gltf")
    assert raised.value.where.endswith("bad.gltf: /buffers/0/uri")


def test_zeros_no_byte_backs_are_refused_before_they_are_made(tmp_path):
    """An accessor without a bufferView is zeros: a few bytes of JSON asking for 2²⁶ of them is refused, not
    allocated (1.5 GiB as the doubles they would become)."""
    gltf = Gltf()
    gltf.node(mesh=gltf.quad())
    accessor = gltf.json["accessors"][0]
    del accessor["bufferView"]
    accessor["count"] = 2**26
    with pytest.raises(SpectraceError, match="without a bufferView") as raised:
        _data(tmp_path, gltf)
    assert raised.value.where.endswith("model.glb: /accessors/0/count")


def test_extension_textures_read_their_channels(tmp_path):
    """KHR_materials_transmission's and _clearcoat's factors in R, the clearcoat's roughness in G, written as the
    principled clearcoat_gloss = 1 − roughness · factor."""
    rng = np.random.default_rng(5)
    pixels = rng.integers(0, 256, (3, 4, 3))
    gltf = Gltf()
    texture = gltf.image_texture(pixels)
    material = gltf.material(
        extensions={
            "KHR_materials_transmission": {"transmissionFactor": 0.5, "transmissionTexture": {"index": texture}},
            "KHR_materials_clearcoat": {
                "clearcoatFactor": 1.0,
                "clearcoatTexture": {"index": texture},
                "clearcoatRoughnessFactor": 0.5,
                "clearcoatRoughnessTexture": {"index": texture},
            },
        }
    )
    gltf.node(mesh=gltf.quad(material=material))
    data, ctx = _data(tmp_path, gltf)
    table = data["materials"]["material0"]
    written = {key: _written_png(tmp_path, ctx, table[key]["file"]) for key in ("spec_trans", "clearcoat")}
    np.testing.assert_array_equal(written["spec_trans"], np.round(pixels[..., 0] * 0.5))
    np.testing.assert_array_equal(written["clearcoat"], pixels[..., 0])
    gloss = _written_png(tmp_path, ctx, table["clearcoat_gloss"]["file"])
    np.testing.assert_array_equal(gloss, 255 - np.round(pixels[..., 1] * 0.5))


def test_spot_cones_in_degrees_and_what_is_not_imported_is_warned(tmp_path):
    gltf = Gltf()
    spot = gltf.light(type="spot", intensity=3.0, range=5.0, spot={"innerConeAngle": 0.1, "outerConeAngle": 0.7})
    gltf.node(extensions={"KHR_lights_punctual": {"light": spot}}, translation=[1, 2, 3])
    texture = gltf.image_texture(np.zeros((1, 1, 3)))
    second_set = gltf.material(pbrMetallicRoughness={"baseColorTexture": {"index": texture, "texCoord": 1}})
    glowing = gltf.material(emissiveFactor=[0.5, 0.5, 0.5], doubleSided=True)
    gltf.node(mesh=gltf.quad(material=second_set))
    gltf.node(mesh=gltf.quad(material=glowing))
    data, ctx = _data(tmp_path, gltf)
    (light,) = data["lights"]
    assert light["position"] == [1, 2, 3] and light["target"] == [1, 2, 2]
    assert light["falloff_start"] == pytest.approx(math.degrees(0.1))
    assert light["cutoff_angle"] == pytest.approx(math.degrees(0.7))
    # the texture on the second set is left out: the factor alone
    assert data["materials"]["material0"]["base_color"] == {"rgb": [1.0, 1.0, 1.0]}
    assert data["shapes"][1]["emitter"]["two_sided"] is True
    warned = " ".join(ctx.warnings)
    assert "range" in warned and "second set of texture coordinates" in warned


def test_mesh_names_become_short_distinct_file_names(tmp_path):
    gltf = Gltf()
    for name in ("a/b c", "a/b c", "x" * 400):
        gltf.node(mesh=gltf.quad(name=name))
    data, _ = _data(tmp_path, gltf)
    files = [shape["file"] for shape in data["shapes"]]
    assert files[:2] == ["out_assets/a_b_c.ply", "out_assets/a_b_c_2.ply"]
    assert len(set(files)) == 3 and all(len(name) < 100 for name in files)


def test_a_volume_s_attenuation_is_the_absorption_of_the_medium_inside(tmp_path):
    """KHR_materials_volume: light keeps the fraction c after the distance d, so σa = −ln(c) / d (Beer-Lambert);
    thin-walled (thickness 0) and unattenuated volumes have no medium."""
    gltf = Gltf()
    volume = {"thicknessFactor": 0.1, "attenuationDistance": 2.0, "attenuationColor": [0.5, 0.25, 1.0]}
    glass = {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_volume": volume}
    thin = {"KHR_materials_volume": {"thicknessFactor": 0.0, "attenuationDistance": 2.0}}
    mesh = gltf.quad(material=gltf.material(extensions=glass))
    gltf.node(mesh=mesh)
    gltf.node(mesh=mesh, translation=[3, 0, 0])
    gltf.node(mesh=gltf.quad(material=gltf.material(extensions=thin)))
    data, ctx = _data(tmp_path, gltf)
    ((name, table),) = data["objects"].items()
    sigma_a = table["shapes"][0]["interior"]["sigma_a"]["rgb"]
    np.testing.assert_allclose(np.exp(-np.array(sigma_a) * 2.0), [0.5, 0.25, 1.0])
    assert "interior" not in data["shapes"][0] and ctx.warnings == []
