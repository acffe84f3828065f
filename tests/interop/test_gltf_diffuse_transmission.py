"""glTF's KHR_materials_diffuse_transmission as the thin principled material: the values the importer writes,
against the extension's definitions (a thin-walled surface whose diffuse part transmits the factor's share, which
principledthin's diff_trans holds on its 0–2 scale), and what it names as left out."""

from __future__ import annotations

import pytest
from tests.interop.gltf_builder import Gltf

from spectrace.interop.gltf import gltf_scene_data


def _material(tmp_path, **material):
    gltf = Gltf()
    gltf.node(mesh=gltf.quad(material=gltf.material(**material)))
    data, ctx = gltf_scene_data(gltf.write(tmp_path / "model.glb"), tmp_path / "out.toml")
    (table,) = data["materials"].values()
    return table, ctx, data


def test_diffuse_transmission_is_a_thin_sheet(tmp_path):
    table, ctx, data = _material(
        tmp_path,
        pbrMetallicRoughness={"baseColorFactor": [0.2, 0.6, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4},
        extensions={
            "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 0.4},
            "KHR_materials_transmission": {"transmissionFactor": 0.3},
            "KHR_materials_ior": {"ior": 1.4},
            "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationDistance": 2.0, "attenuationColor": [0.5] * 3},
        },
        doubleSided=True,
    )
    assert table == {
        "type": "principledthin",
        "base_color": {"rgb": [0.2, 0.6, 0.1]},
        "roughness": 0.4,
        "eta": 1.4,
        "spec_trans": 0.3,
        "diff_trans": pytest.approx(0.8),
    }
    assert ctx.warnings == []
    assert all("interior" not in shape for shape in data["shapes"])  # a sheet has no inside


def test_what_a_thin_sheet_leaves_out_is_named(tmp_path):
    """glTF's default metallicFactor is 1; the sheet has no metal, no coat, and takes the base colour for the
    transmission's colour; a factor of 0 leaves the principled material as it was."""
    table, ctx, _ = _material(
        tmp_path,
        extensions={
            "KHR_materials_diffuse_transmission": {
                "diffuseTransmissionFactor": 1.0,
                "diffuseTransmissionColorFactor": [1.0, 0.5, 0.5],
            },
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.5},
        },
    )
    assert table["type"] == "principledthin" and table["diff_trans"] == 2.0
    assert not {"metallic", "clearcoat", "clearcoat_gloss"} & set(table)
    text = "\n".join(ctx.warnings)
    assert "no metallic" in text and "no clearcoat" in text and "colour is approximated" in text
    table, _, _ = _material(tmp_path, extensions={"KHR_materials_diffuse_transmission": {}})
    assert table["type"] == "principled"
