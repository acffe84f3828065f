"""Mitsuba 3's named conductors (`metal` = any of its `material` names): the shipped η and k against Mitsuba's own
data files, and the normal-incidence reflectance against Mitsuba's conductor BSDF at the same wavelengths."""

from pathlib import Path

import numpy as np
import pytest

from materials.test_bsdfs import HARNESS, LAMBDA_NM, Bsdf
from spectrace.errors import SpectraceError
from spectrace.materials.conductor import ConductorMaterial
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.metals import METALS, MITSUBA_MEASURED, metal_ior

# Metals of several kinds (a carbon, transition metals, an oxide, a crystal's extraordinary axis, a
# semiconductor, a Palik-only table); every one's data cover LAMBDA_NM.
SOME_METALS = ("a-C", "Cr", "W", "Cu2O_palik", "TiO2-e", "HgTe", "Ni_palik")


def _mitsuba_ior_folder() -> Path:
    mitsuba = pytest.importorskip("mitsuba", reason="the comparison needs Mitsuba 3 (`pip install spectrace[test]`)")
    folder = Path(mitsuba.__file__).parent / "data" / "ior"
    if not folder.is_dir():
        pytest.skip("this mitsuba build ships no data/ior folder")
    return folder


def _spd(path: Path) -> np.ndarray:
    """Rows (wavelength nm, value) of a Mitsuba .spd file."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return np.array([line.split() for line in lines if line.strip() and not line.startswith("#")], float)


def test_every_mitsuba_conductor_name_is_a_metal():
    folder = _mitsuba_ior_folder()
    names = {p.name.removesuffix(".eta.spd") for p in folder.glob("*.eta.spd")}
    assert names == set(MITSUBA_MEASURED)
    assert set(METALS) == names | {"none"}


@pytest.mark.parametrize("metal", SOME_METALS + ("Se-e", "d-C", "Li"))
def test_eta_and_k_are_mitsubas_data(metal):
    """On the renderer's grid, η and k are Mitsuba's .spd rows joined linearly (the end values held beyond them)."""
    folder = _mitsuba_ior_folder()
    eta, k = metal_ior(metal)
    for spectrum, part in ((eta, "eta"), (k, "k")):
        rows = _spd(folder / f"{metal}.{part}.spd")
        expected = np.interp(GRID_NM, rows[:, 0], rows[:, 1])
        np.testing.assert_allclose(spectrum.values, expected, rtol=1e-6, atol=1e-9)


@pytest.fixture(scope="module")
def bsdf(kernel_runner):
    runner = kernel_runner(HARNESS)
    return lambda material: Bsdf(runner, material)


@pytest.mark.parametrize("metal", SOME_METALS)
def test_normal_incidence_reflectance_matches_mitsuba(bsdf, mitsuba_scalar_spectral, metal):
    mi = mitsuba_scalar_spectral
    reference = mi.load_dict({"type": "conductor", "material": metal})
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.wavelengths = [float(x) for x in LAMBDA_NM]
    _, weight = reference.sample(mi.BSDFContext(), si, 0.5, [0.5, 0.5])
    expected = np.array([weight[i] for i in range(4)])
    assert np.all(np.isfinite(expected)) and np.all(expected > 0.0)
    s = bsdf(ConductorMaterial(*metal_ior(metal))).sample(np.array([0.0, 0.0, 1.0]), 1, seed=9)
    assert s.ok[0] and s.is_delta[0]
    np.testing.assert_allclose(s.weight[0], expected, rtol=1e-3)


def test_none_is_a_perfect_mirror(bsdf):
    """Mitsuba's "none" (η = 0, k = 1) reflects everything at every angle."""
    material = ConductorMaterial(*metal_ior("none"))
    for cos_theta in (1.0, 0.5, 0.1):
        wo = np.array([np.sqrt(1.0 - cos_theta**2), 0.0, cos_theta])
        np.testing.assert_allclose(bsdf(material).sample(wo, 1, seed=3).weight[0], 1.0, rtol=1e-5)


def test_an_unknown_metal_is_named():
    with pytest.raises(SpectraceError, match="unknown metal 'Pt'"):
        metal_ior("Pt", where="materials.m.metal")
