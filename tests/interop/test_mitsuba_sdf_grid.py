"""Mitsuba 3's sdfgrid imported as spectrace's SDF grid shape (geometry/sdf_grid.py): the volume file's samples and
placement as Mitsuba reads them, a lit scene with both kinds of shading normal rendered like Mitsuba 3 renders the
same XML and volume file, and the import's refusals in one line."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import vol_bytes
from spectrace.geometry.sdf_grid import SdfGridSurface
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data


def blob_samples(n: int = 24) -> np.ndarray:
    """A lumpy ball's signed distance (roughly: a sphere with bumps), sampled at the corners of an n³ grid."""
    x = np.linspace(0.0, 1.0, n)
    z, y, x = np.meshgrid(x, x, x, indexing="ij")
    r = np.sqrt((x - 0.5) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2)
    return r - 0.32 - 0.06 * np.sin(11.0 * x) * np.sin(9.0 * y + 1.0) * np.cos(7.0 * z)


def _instanced(text: str) -> str:
    """The XML with the grid in a shapegroup, turned by its instance (Mitsuba places rotated grids so: its sdfgrid
    warns that a rotating to_world is not supported)."""
    start = text.index('<shape type="sdfgrid"')
    end = text.index("</shape>", start) + len("</shape>")
    return (
        f'{text[:start]}<shape type="shapegroup" id="group">{text[start:end]}</shape>\n<shape type="instance">'
        '<ref id="group"/><transform name="to_world"><rotate x="1" y="0.3" angle="50"/></transform></shape>'
        f"{text[end:]}"
    )


def _xml(folder: Path, size: int, normals: str) -> Path:
    (folder / "blob.vol").write_bytes(vol_bytes(blob_samples()))
    path = folder / "sdf.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="4"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/>
  <transform name="to_world"><lookat origin="0.3, -3.4, 1.5" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
<shape type="sdfgrid" id="blob">
  <string name="filename" value="blob.vol"/><string name="normals" value="{normals}"/>
  <transform name="to_world"><translate value="-0.5, -0.5, -0.5"/><scale value="1.6, 1.6, 1.4"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.45, 0.3"/></bsdf>
</shape>
<shape type="rectangle" id="floor">
  <transform name="to_world"><scale value="3"/><translate z="-0.55"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
</shape>
<shape type="sphere" id="bulb">
  <point name="center" x="-0.8" y="-1.0" z="1.8"/><float name="radius" value="0.15"/>
  <emitter type="area"><rgb name="radiance" value="120, 110, 100"/></emitter>
</shape>
<emitter type="constant"><rgb name="radiance" value="0.15"/></emitter>
</scene>
"""
    )
    return path


def test_the_volume_file_is_the_grid_mitsuba_reads(tmp_path):
    """The samples as stored (x fastest), the unit cube placed by to_world, the normals key."""
    scene = load_mitsuba_scene(_xml(tmp_path, 8, "analytic"))
    (blob,) = [shape for shape in scene.shapes if shape.name == "blob"]
    surface = blob.analytic
    assert isinstance(surface, SdfGridSurface) and surface.normals == "analytic"
    np.testing.assert_array_equal(surface.values, blob_samples().astype(np.float32))
    expected = np.diag([1.6, 1.6, 1.4, 1.0])
    expected[:3, 3] = [-0.8, -0.8, -0.7]
    np.testing.assert_allclose(surface.to_world, expected, atol=1e-12)


@pytest.mark.peer
@pytest.mark.slow
@pytest.mark.parametrize("normals, instanced", [("smooth", False), ("analytic", False), ("smooth", True)])
def test_sdf_grid_scene_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral, normals, instanced):
    """Both renderers, spectral, 16 independent images each; 8 × 8-pixel block means and the image mean agree within
    5 standard errors (tests/replica_agreement.py); placed directly, and turned by an instance."""
    mi = mitsuba_scalar_spectral
    path = _xml(tmp_path, 32, normals)
    if instanced:
        path.write_text(_instanced(path.read_text()))
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, 16, 8, 8)
    assert by_mitsuba.mean() > 0.05  # the comparison saw a lit image


@pytest.mark.parametrize(
    "body, path, says",
    [
        (
            '<shape type="sdfgrid"><string name="filename" value="blob.vol"/>'
            '<string name="normals" value="falcao"/><bsdf type="diffuse"/></shape>',
            "shape/string",
            "unknown normals 'falcao'",
        ),
        (
            '<shape type="sdfgrid"><string name="filename" value="blob.vol"/><emitter type="area"/></shape>',
            "shape/emitter",
            "an sdfgrid cannot emit",
        ),
        ('<shape type="sdfgrid"><bsdf type="diffuse"/></shape>', "shape", "filename"),
    ],
)
def test_bad_sdf_grids_are_one_line_naming_the_element(tmp_path, body, path, says):
    (tmp_path / "blob.vol").write_bytes(vol_bytes(blob_samples(4)))
    xml = tmp_path / "bad.xml"
    xml.write_text(f'<scene version="3.0.0"><sensor type="perspective"/>{body}</scene>')
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(xml)
    assert path in str(error.value) and says in str(error.value) and "\n" not in str(error.value)
