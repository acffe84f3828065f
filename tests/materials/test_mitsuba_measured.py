"""Measured BRDFs imported from Mitsuba 3 render as Mitsuba 3 renders them (Mitsuba's scalar_spectral `measured`
reading the same file): small scenes written here, rendered from the XML by both, independent replicas compared
block by block and over the whole image within 5 standard errors of the difference (replica_agreement).

The files are written by tests/rgl_tensor.py from GGX (a reflectance rising from 0.5 to 0.9 over 360–830 nm, so
the wavelengths' interpolation shows in the colour); a file of the RGL database itself is rendered the same way when
SPECTRACE_RGL_BSDF names one (a `*_spec.bsdf`; the database's files are not in the repository), and the test skips
saying so otherwise."""

import os
from pathlib import Path

import pytest

from materials.test_mitsuba_materials import AREA_LIGHT, FLOOR, _compare, _scene
from rgl_tensor import ggx_file

pytestmark = pytest.mark.peer

SKY = '<emitter type="constant"><spectrum name="radiance" value="0.2"/></emitter>'


def _measured(path: Path) -> str:
    return f'<bsdf type="measured"><string name="filename" value="{path}"/></bsdf>'


def _floor_and_sphere(path: Path) -> str:
    """A measured floor (one-sided, as Mitsuba's measured is outside `twosided`) with a measured sphere on it
    (`twosided`), the highlight of a small area light on both and light between them, under a dim sky."""
    sphere = f"""<shape type="sphere"><float name="radius" value="0.5"/><point name="center" value="0.4, 0.2, 0.5"/>
        <bsdf type="twosided">{_measured(path)}</bsdf></shape>"""
    return FLOOR.format(bsdf=_measured(path)) + sphere + AREA_LIGHT + SKY


@pytest.mark.slow
@pytest.mark.parametrize("alpha", (0.2, 0.5))
def test_measured_ggx_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, alpha):
    """Measured (Intel's CPU runtime): blocks within 2.0 σ (α 0.2; mean 0.75 σ) and 1.8 σ (α 0.5; mean 0.67 σ), the
    whole image within 2.0 σ and 1.1 σ; spectrace rendering the α = 0.5 file where Mitsuba renders the α = 0.2 one
    fails at 78 σ (whole image 54 σ)."""
    _compare(tmp_path, device, mitsuba_scalar_spectral, _scene(_floor_and_sphere(ggx_file(alpha))), 12, 16)


def test_a_database_file_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """A file of the RGL database (SPECTRACE_RGL_BSDF), where one is at hand."""
    name = os.environ.get("SPECTRACE_RGL_BSDF")
    if not name:
        pytest.skip("SPECTRACE_RGL_BSDF names no RGL database file (rgl.epfl.ch/materials, a *_spec.bsdf)")
    path = Path(name).resolve()
    if not path.is_file():
        pytest.skip(f"SPECTRACE_RGL_BSDF names {path}, which is no file")
    _compare(tmp_path, device, mitsuba_scalar_spectral, _scene(_floor_and_sphere(path)), 12, 16)
