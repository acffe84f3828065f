"""A loaded scene survives plain `pickle` whole: it travels to other processes (a cluster's workers, a sweep's
items), and anything that needs cloudpickle, such as a lambda or a closure in a spectrum, breaks the command line's
measure of what each worker receives. Every bundled scene and a few imported ones go through a round trip and come
back equal, field by field, with their spectra's continuations beyond the grid giving the same values."""

import math
import pickle
import types
from pathlib import Path

import numpy as np
import pytest

from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.interop.pbrt import load_pbrt_scene
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.spectral.spectrum import Extension

MITSUBA_DATA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"
PBRT_SCENE = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
LightSource "infinite" "blackbody L" 5500
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" "stdillum-F2" "float scale" 2
  Shape "sphere" "float radius" 0.2
AttributeEnd
Material "conductor" "spectrum eta" "metal-Cu-eta" "spectrum k" "metal-Cu-k"
Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]
Material "dielectric" "spectrum eta" "glass-BK7"
Shape "sphere" "float radius" 0.5
Material "diffuse" "rgb reflectance" [0.2 0.5 0.7]
Shape "bilinearmesh" "point3 P" [-1 -1 1  1 -1 1  -1 1 1  1 1 1]
"""


def _assert_same(original, copy, path: str, extensions: list) -> None:
    """`copy` equals `original` in every field, recursively; the Extensions met are collected for evaluation."""
    assert type(copy) is type(original), path
    if isinstance(original, np.ndarray):
        assert copy.dtype == original.dtype and copy.shape == original.shape, path
        assert np.array_equal(copy, original, equal_nan=original.dtype.kind in "fc"), path
    elif isinstance(original, float):
        assert copy == original or (math.isnan(copy) and math.isnan(original)), path
    elif isinstance(original, (str, bytes, int, type(None), Path, np.generic)):
        assert copy == original, path
    elif isinstance(original, (types.FunctionType, types.BuiltinFunctionType, type)):
        assert copy is original, path  # a module-level function or class unpickles to itself
    elif isinstance(original, dict):
        assert list(copy) == list(original), path
        for key, value in original.items():
            _assert_same(value, copy[key], f"{path}[{key!r}]", extensions)
    elif isinstance(original, (list, tuple)):
        assert len(copy) == len(original), path
        for index, (a, b) in enumerate(zip(original, copy)):
            _assert_same(a, b, f"{path}[{index}]", extensions)
    elif isinstance(original, (set, frozenset)):
        assert copy == original, path
    else:
        if isinstance(original, Extension):
            extensions.append((path, original, copy))
        names = list(getattr(original, "__dict__", {}))
        names += [slot for cls in type(original).__mro__ for slot in getattr(cls, "__slots__", ())]
        assert names, f"{path}: {type(original).__name__} has no fields to compare"
        for name in names:
            _assert_same(getattr(original, name), getattr(copy, name), f"{path}.{name}", extensions)


def _assert_round_trip(scene) -> None:
    copy = pickle.loads(pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL))
    extensions: list = []
    _assert_same(scene, copy, "scene", extensions)
    for path, original, restored in extensions:
        # The continuation's own formula or samples, evaluated where it is defined beyond the common grid.
        nm = np.linspace(max(original.lo_nm, 200.0), min(original.hi_nm, 1200.0), 7)
        assert np.array_equal(restored.evaluate(nm), original.evaluate(nm)), path


@pytest.mark.parametrize("name", sorted(p.name for p in scenes_dir().glob("*.toml")))
def test_a_bundled_scene_survives_plain_pickle(name):
    _assert_round_trip(load_scene(scenes_dir() / name))


@pytest.mark.parametrize("name", ["cornell_box.xml", "features.xml", "textures.xml"])
def test_an_imported_mitsuba_scene_survives_plain_pickle(name):
    _assert_round_trip(load_mitsuba_scene(MITSUBA_DATA / name))


def test_an_imported_pbrt_scene_survives_plain_pickle(tmp_path):
    """pbrt's named spectra (a CIE illuminant, a metal's optical constants, a glass), a black body and an RGB
    uplift: each continues beyond the grid by its own formula or samples."""
    path = tmp_path / "scene.pbrt"
    path.write_text(PBRT_SCENE)
    scene = load_pbrt_scene(path)
    _assert_round_trip(scene)


def test_a_spectrum_continuation_must_not_be_a_closure():
    level = 0.5
    with pytest.raises(TypeError, match="must pickle"):
        Extension(0.0, 1.0, lambda nm: np.full(np.shape(nm), level))
