"""pbrt-v4's `coatedconductor` and `coateddiffuse` imported as spectrace's stochastic layered materials
(docs/materials.md#coatedconductor): every parameter under its name, pbrt-v4's defaults, the roughness remapped, a
conductor given by its reflectance, and a coated gold sphere from a pbrt file rendering as the same material built
in Python (the import changes nothing the walk reads), the same bits however the render is split."""

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import Renderer
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" 4
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
"""


def _materials(tmp_path, body: str) -> list[dict]:
    path = tmp_path / "scene.pbrt"
    path.write_text(HEADER + body)
    data, _ = pbrt_scene_data(path)
    return list(data["materials"].values())


def test_pbrt_coatedconductor_defaults_and_parameters(tmp_path):
    (defaults,) = _materials(tmp_path, 'Material "coatedconductor"\nShape "sphere"\n')
    assert defaults == {
        "type": "coatedconductor",
        "metal": "Cu",
        "ior": 1.5,
        "thickness": 0.01,
        "g": 0.0,
        "max_depth": 10,
        "samples": 1,
    }
    (given,) = _materials(
        tmp_path,
        'Material "coatedconductor" "spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k"\n'
        '  "float conductor.roughness" 0.09 "float interface.roughness" 0.04 "float interface.eta" 1.33\n'
        '  "float thickness" 0.2 "rgb albedo" [0.5 0.6 0.7] "float g" 0.3 "integer maxdepth" 20 "integer nsamples" 4\n'
        'Shape "sphere"\n',
    )
    assert given == {
        "type": "coatedconductor",
        "metal": "Au",
        "conductor_roughness": pytest.approx(0.3),
        "ior": 1.33,
        "thickness": 0.2,
        "albedo": {"rgb": [0.5, 0.6, 0.7]},
        "g": 0.3,
        "max_depth": 20,
        "samples": 4,
        "roughness": pytest.approx(0.2),
    }
    (by_colour,) = _materials(
        tmp_path,
        'Material "coatedconductor" "rgb reflectance" [0.9 0.6 0.3] "bool remaproughness" false '
        '"float conductor.uroughness" 0.1 "float conductor.vroughness" 0.3\nShape "sphere"\n',
    )
    assert by_colour["reflectance"] == {"rgb": [0.9, 0.6, 0.3]} and "metal" not in by_colour
    assert by_colour["conductor_roughness"] == pytest.approx(0.2)  # the mean of u and v, not remapped


def test_pbrt_coateddiffuse_defaults(tmp_path):
    (table,) = _materials(tmp_path, 'Material "coateddiffuse"\nShape "sphere"\n')
    assert table == {
        "type": "coateddiffuse",
        "reflectance": {"value": 0.5},
        "ior": 1.5,
        "thickness": 0.01,
        "g": 0.0,
        "max_depth": 10,
        "samples": 1,
    }


def test_a_named_glass_coat_takes_its_index_at_550_nm(tmp_path):
    """The coat takes one index: N-BK7's at 550 nm (SCHOTT's n_e = 1.51872 at 546.07 nm, n_d = 1.5168 at 587.56)."""
    (table,) = _materials(tmp_path, 'Material "coateddiffuse" "spectrum eta" "glass-BK7"\nShape "sphere"\n')
    assert 1.5168 < table["ior"] < 1.51872


def test_a_conductor_by_reflectance_reflects_that_reflectance_at_normal_incidence():
    """pbrt's mapping η = 1, k = 2√r/√(1 − r) gives ((η − 1)² + k²)/((η + 1)² + k²) = r in air."""
    material = spectrace.coatedconductor(reflectance=0.64)
    eta, k = material.eta.values, material.k.values
    np.testing.assert_allclose(((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2), 0.64, rtol=1e-6)


def test_an_imported_coated_conductor_renders_as_the_same_material_built_in_python(tmp_path, device):
    path = tmp_path / "scene.pbrt"
    path.write_text(
        HEADER + 'Material "coatedconductor" "spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" '
        '"metal-Au-k" "float interface.roughness" 0.04 "float thickness" 0.1\nShape "sphere"\n'
    )
    scene = load_pbrt_scene(path)
    built = spectrace.coatedconductor("Au", roughness=0.2, thickness=0.1)
    assert scene.shapes[0].material == built
    image = Renderer(scene, device).render(4, pass_spp=4)
    assert np.all(np.isfinite(image.xyz)) and image.xyz[..., 1].mean() > 0.05
    # The walks' random numbers come from hashes of their directions and the sampler's numbers: a render split
    # into passes of one sample is the same, bit for bit.
    assert np.array_equal(Renderer(scene, device).render(4, pass_spp=1).xyz, image.xyz)
