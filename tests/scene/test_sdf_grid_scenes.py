"""SDF grids in the scene format (type = "sdfgrid": a volume file or an inline grid, normals), written back by
save_scene and exported to Mitsuba 3; bad grids are one line naming the file and key path."""

import numpy as np
import pytest

import spectrace
from cli_runner import run_spectrace
from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import vol_bytes
from spectrace.geometry.sdf_grid import SdfGridSurface

SAMPLES = np.sqrt(np.sum(np.stack(np.meshgrid(*[np.linspace(-0.5, 0.5, 5)] * 3, indexing="ij")) ** 2, axis=0)) - 0.3


def _toml(shape: str) -> str:
    return f"""
[camera]
origin = [0, -3, 1]
target = [0, 0, 0]
fov = 40
[film]
width = 8
height = 8
[sampler]
spp = 1
[materials.grey]
type = "diffuse"
reflectance = {{ value = 0.5 }}
[[lights]]
type = "point"
position = [0, -2, 2]
power = 10
[[shapes]]
material = "grey"
transform = [{{translate = [-0.5, -0.5, -0.5]}}, {{scale = 2}}]
{shape}
"""


def _grid_text(values: np.ndarray) -> str:
    return "[" + ", ".join("[" + ", ".join(str(list(map(float, row))) for row in plane) + "]" for plane in values) + "]"


def test_a_volume_file_and_an_inline_grid_are_the_same_shape(tmp_path):
    (tmp_path / "ball.vol").write_bytes(vol_bytes(SAMPLES))
    (tmp_path / "file.toml").write_text(_toml('type = "sdfgrid"\nfile = "ball.vol"\nnormals = "analytic"'))
    (tmp_path / "inline.toml").write_text(
        _toml(f'type = "sdfgrid"\ngrid = {_grid_text(SAMPLES.astype(np.float32))}\nnormals = "analytic"')
    )
    from_file, inline = (spectrace.load_scene(tmp_path / f"{n}.toml").shapes[0].analytic for n in ("file", "inline"))
    assert isinstance(from_file, SdfGridSurface) and from_file == inline
    assert from_file.normals == "analytic"
    np.testing.assert_array_equal(from_file.values, SAMPLES.astype(np.float32))
    expected = np.diag([2.0, 2.0, 2.0, 1.0])
    expected[:3, 3] = -1.0  # x → 2 (x − 0.5)
    np.testing.assert_allclose(from_file.to_world, expected)
    # The default shading normal is Mitsuba's default, "smooth".
    (tmp_path / "plain.toml").write_text(_toml('type = "sdfgrid"\nfile = "ball.vol"'))
    assert spectrace.load_scene(tmp_path / "plain.toml").shapes[0].analytic.normals == "smooth"


def test_save_scene_writes_the_grid_back(tmp_path):
    grid = spectrace.sdf_grid(SAMPLES, spectrace.diffuse(0.5), transform=[{"scale": [1, 2, 1]}], normals="analytic")
    obj = spectrace.instanced_object([spectrace.sdf_grid(SAMPLES[::-1], spectrace.diffuse(0.3))])
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0, -3, 1), target=(0, 0, 0)),
        width=8,
        height=8,
        spp=1,
        shapes=[grid],
        instances=[spectrace.instance(obj, [{"translate": [1, 0, 0]}])],
        lights=[spectrace.point_light((0, -2, 2), 10.0)],
    )
    loaded = spectrace.load_scene(spectrace.save_scene(scene, tmp_path / "saved.toml"))
    assert loaded.shapes[0].analytic == grid.analytic
    assert loaded.instances[0].object.shapes[0].analytic == obj.shapes[0].analytic


@pytest.mark.peer
def test_the_mitsuba_export_is_mitsubas_sdfgrid_of_the_same_samples(tmp_path, mitsuba_scalar_spectral):
    """Mitsuba 3 loads the exported grid and meets a ray where the sampled sphere is (radius 0.3 at the origin: a ray
    along x from x = −3 meets it near t = 2.7, within the interpolation error)."""
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    mi = mitsuba_scalar_spectral
    grid = spectrace.sdf_grid(SAMPLES, spectrace.diffuse(0.5), transform=[{"translate": [-0.5, -0.5, -0.5]}])
    scene = spectrace.Scene(
        camera=spectrace.Camera(origin=(0, -3, 1), target=(0, 0, 0)), width=8, height=8, spp=1, shapes=[grid]
    )
    exported = mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path))
    (shape,) = exported.shapes()
    assert str(shape).startswith("SDFgrid")
    si = exported.ray_intersect(mi.Ray3f([-3.0, 0.0, 0.0], [1.0, 0.0, 0.0]))
    assert si.is_valid() and float(si.t) == pytest.approx(3.0 - 0.3, abs=0.02)


BAD = [
    ('type = "sdfgrid"\ngrid = [[[1.0, 2.0], [1.0, 2.0]], [[1.0, 2.0]]]', "shapes[0].grid", "a box of numbers"),
    ('type = "sdfgrid"\ngrid = [[[1.0, 2.0]]]', "shapes[0].grid", "at least 2 samples along each axis"),
    ('type = "sdfgrid"\ngrid = [[[1.0, 2.0], [1.0, 2.0]], [[1.0, 2.0], [1.0, 2.0]]]', "shapes[0].grid", "no surface"),
    ('type = "sdfgrid"\nfile = "ball.vol"\ngrid = [[[1.0]]]', "shapes[0]", "either file"),
    ('type = "sdfgrid"\nfile = "colour.vol"', "shapes[0].file", "one channel"),
    ('type = "sdfgrid"\nfile = "missing.vol"', "shapes[0].file", "missing.vol"),
    ('type = "sdfgrid"\nfile = "ball.vol"\nnormals = "falcao"', "shapes[0].normals", "smooth"),
    ('type = "sphere"\nnormals = "smooth"', "shapes[0]", "an sdfgrid's"),
]


@pytest.mark.parametrize("shape, where, says", BAD)
def test_bad_grids_are_one_line_naming_the_key(tmp_path, shape, where, says):
    (tmp_path / "ball.vol").write_bytes(vol_bytes(SAMPLES))
    (tmp_path / "colour.vol").write_bytes(vol_bytes(np.stack([SAMPLES] * 3, axis=-1)))
    (tmp_path / "bad.toml").write_text(_toml(shape))
    with pytest.raises(SpectraceError) as error:
        spectrace.load_scene(tmp_path / "bad.toml")
    message = str(error.value)
    assert "bad.toml" in message and where in message and says in message and "\n" not in message, message


@pytest.mark.subprocess
@pytest.mark.slow
def test_a_bad_grid_ends_a_real_process_with_one_line(tmp_path):
    (tmp_path / "bad.toml").write_text(_toml('type = "sdfgrid"\ngrid = [[[1.0, 2.0]]]'))
    result = run_spectrace("render", str(tmp_path / "bad.toml"), "-o", str(tmp_path / "out.png"), timeout=300)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: "), result.stderr
    assert "shapes[0].grid" in result.stderr and not (tmp_path / "out.png").exists()
