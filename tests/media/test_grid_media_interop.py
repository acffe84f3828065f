"""Grid media imported from Mitsuba 3 (`heterogeneous` with `gridvolume` sigma_t and albedo) and pbrt-v4
(`uniformgrid`), and a grid medium rendered like Mitsuba 3's volpath renders the same XML."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.geometry.grid_volume import vol_bytes
from spectrace.interop.mitsuba import mitsuba_scene_data

DENSITY = np.random.default_rng(12).uniform(0.0, 2.0, (5, 7, 6)).astype(np.float32)
DENSITY[:, :3] *= 0.1  # a thin region and a dense one: the majorant cells differ

GRID_TO_WORLD = '<transform name="to_world"><translate value="-0.5, -0.5, -0.5"/><scale value="2"/></transform>'


def _medium(albedo: str = '<float name="albedo" value="0.8"/>', extra: str = "") -> str:
    return f"""<medium type="heterogeneous" name="interior">
    <volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/>
      {GRID_TO_WORLD}{extra}</volume>
    {albedo}<float name="scale" value="2"/>
    <phase type="hg"><float name="g" value="0.5"/></phase>
  </medium>"""


# Mitsuba 3 bounds a heterogeneous medium by its sigma_t volume's box: a constvolume's unit box, moved here onto
# [-0.5, 0.5]³ inside the cube [-1, 1]³ that holds the medium.
CONSTANT_BOX = """<medium type="heterogeneous" name="interior">
    <volume type="constvolume" name="sigma_t"><float name="value" value="0.45"/>
      <transform name="to_world"><translate value="-0.5, -0.5, -0.5"/></transform></volume>
    <float name="albedo" value="0.6"/><float name="scale" value="4"/>
  </medium>"""


# sigma_t of three channels: each voxel's colour uplifted (σt varies with λ voxel by voxel), reddish so it does.
COLOUR_DENSITY = (DENSITY[..., None] * np.random.default_rng(5).uniform(0.2, 1.0, (*DENSITY.shape, 3))).astype(
    np.float32
) * np.array([1.0, 0.6, 0.25], np.float32)
COLOUR_SIGMA_T = _medium('<rgb name="albedo" value="0.9, 0.7, 0.8"/>').replace("density.vol", "colour.vol")

# A homogeneous medium whose albedo is a colour gridvolume of 0.6 units a side, repeated through the cube.
ALBEDO = np.random.default_rng(9).uniform(0.1, 1.0, (3, 4, 2, 3)).astype(np.float32)
ALBEDO_GRID = """<medium type="homogeneous" name="interior">
    <volume type="gridvolume" name="albedo"><string name="filename" value="albedo_grid.vol"/>
      <string name="wrap_mode" value="repeat"/>
      <transform name="to_world"><scale value="0.6"/><translate value="0.1, -0.2, 0"/></transform></volume>
    <rgb name="sigma_t" value="0.9, 0.6, 0.7"/><float name="scale" value="2"/>
    <phase type="hg"><float name="g" value="0.3"/></phase>
  </medium>"""


def _xml(folder: Path, size: int, medium: str, integrator: str = "volpath", environment: bool = True) -> Path:
    """The cube holding `medium` under a point light, and a constant environment unless told otherwise."""
    (folder / "density.vol").write_bytes(vol_bytes(DENSITY, (-3, -3, -3), (3, 3, 3)))
    (folder / "colour.vol").write_bytes(vol_bytes(COLOUR_DENSITY, (-3, -3, -3), (3, 3, 3)))
    (folder / "albedo_grid.vol").write_bytes(vol_bytes(ALBEDO))
    path = folder / f"grid_{integrator}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="{integrator}"><integer name="max_depth" value="16"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/>
  <transform name="to_world"><lookat origin="1, -4, 1.5" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
  <rfilter type="box"/></film></sensor>
{'<emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>' if environment else ""}
<emitter type="point"><point name="position" value="2, -1, 3"/><spectrum name="intensity" value="10"/></emitter>
<shape type="cube"><bsdf type="null"/>{medium}</shape>
</scene>
"""
    )
    return path


def test_heterogeneous_medium_maps_to_a_density_grid(tmp_path):
    """sigma_t's grid is the density (its file, to_world as a matrix, the unit box), scale·albedo·σt and
    scale·(1 − albedo)·σt the coefficients, as for the homogeneous medium; an albedo grid becomes albedo_file."""
    (tmp_path / "albedo.vol").write_bytes(vol_bytes(np.full(DENSITY.shape, 0.5)))
    for albedo, expected in (
        ('<float name="albedo" value="0.8"/>', {"sigma_a": {"value": 2 * 0.2}, "sigma_s": {"value": 2 * 0.8}}),
        (
            f'<volume type="gridvolume" name="albedo"><string name="filename" value="albedo.vol"/>{GRID_TO_WORLD}'
            "</volume>",
            {"sigma_a": {"value": 0.0}, "sigma_s": {"value": 2.0}},
        ),
    ):
        data = mitsuba_scene_data(_xml(tmp_path, 8, _medium(albedo)), tmp_path)[0]
        interior = data["shapes"][0]["interior"]
        density = interior.pop("density")
        assert interior["sigma_a"]["value"] == pytest.approx(expected["sigma_a"]["value"])
        assert interior["sigma_s"]["value"] == pytest.approx(expected["sigma_s"]["value"])
        assert interior["g"] == 0.5
        assert density["file"] == "density.vol" and "box" not in density
        matrix = np.array(density["transform"][0]["matrix"])
        assert np.allclose(matrix, [[2, 0, 0, -1], [0, 2, 0, -1], [0, 0, 2, -1], [0, 0, 0, 1]])
        assert density.get("albedo_file") == ("albedo.vol" if "albedo.vol" in albedo else None)


def test_a_constant_heterogeneous_medium_fills_its_volumes_box(tmp_path):
    """Mitsuba 3's heterogeneous medium of a constvolume (or a spectrum written in place, whose box is the unit
    box) scatters only inside that volume's box: a grid of one voxel of density 1 placed there."""
    interior = mitsuba_scene_data(_xml(tmp_path, 8, CONSTANT_BOX), tmp_path)[0]["shapes"][0]["interior"]
    density = interior.pop("density")
    assert density["values"] == [1.0] and density["resolution"] == [1, 1, 1]
    assert np.allclose(np.array(density["transform"][0]["matrix"])[:3, 3], -0.5)
    assert interior["sigma_s"]["value"] == pytest.approx(0.45 * 0.6 * 4)
    plain = CONSTANT_BOX.split("<volume")[0] + '<float name="sigma_t" value="2"/>' + CONSTANT_BOX.split("</volume>")[1]
    density = mitsuba_scene_data(_xml(tmp_path, 8, plain), tmp_path)[0]["shapes"][0]["interior"]["density"]
    assert density == {"values": [1.0], "resolution": [1, 1, 1]}


def test_use_grid_bbox_places_the_grid_in_the_files_box(tmp_path):
    medium = _medium(extra='<boolean name="use_grid_bbox" value="true"/>')
    density = mitsuba_scene_data(_xml(tmp_path, 8, medium), tmp_path)[0]["shapes"][0]["interior"]["density"]
    assert density["box"] == [[-3.0, -3.0, -3.0], [3.0, 3.0, 3.0]]


def test_a_truncated_vol_file_is_one_line_naming_the_file(tmp_path):
    path = _xml(tmp_path, 8, _medium())
    (tmp_path / "density.vol").write_bytes(vol_bytes(DENSITY)[:-5])  # after _xml wrote the whole file
    with pytest.raises(SpectraceError) as caught:
        mitsuba_scene_data(path, tmp_path)
    text = str(caught.value)
    assert "\n" not in text and "grid_volpath.xml" in text and "the volume file 'density.vol' has" in text, text


def test_a_homogeneous_mediums_albedo_grid_fills_space_over_a_density_of_1(tmp_path):
    """Mitsuba 3's homogeneous medium looks its albedo volume up everywhere (wrap_mode: clamped or repeated):
    scale·sigma_t all scattering, the albedo grid alone (over a density of 1) moving part of it to absorption."""
    interior = mitsuba_scene_data(_xml(tmp_path, 8, ALBEDO_GRID), tmp_path)[0]["shapes"][0]["interior"]
    density = interior["density"]
    assert density["albedo_file"] == "albedo_grid.vol" and density["outside"] == "repeat"
    assert "file" not in density and "values" not in density
    assert np.allclose(np.array(density["transform"][0]["matrix"])[:3, :3], 0.6 * np.eye(3))
    assert all(a == 0.0 for _, a in interior["sigma_a"]["values"])
    clamped = mitsuba_scene_data(_xml(tmp_path, 8, ALBEDO_GRID.replace("repeat", "clamp")), tmp_path)[0]
    assert clamped["shapes"][0]["interior"]["density"]["outside"] == "clamp"


def test_unsupported_grid_forms_are_reported(tmp_path):
    (tmp_path / "six.vol").write_bytes(vol_bytes(np.ones((2, 2, 2, 6))))
    six = _medium().replace("density.vol", "six.vol")
    nearest = _medium(extra='<string name="filter_type" value="nearest"/>')
    mirror = ALBEDO_GRID.replace("repeat", "mirror")
    repeat = _medium(extra='<string name="wrap_mode" value="repeat"/>')
    for medium, words in (
        (six, "6 channels"),
        (nearest, "filter_type nearest"),
        (mirror, "wrap_mode mirror"),
        (repeat, "wrap_mode repeat in a heterogeneous medium"),
    ):
        with pytest.raises(SpectraceError, match=words) as caught:
            mitsuba_scene_data(_xml(tmp_path, 8, medium), tmp_path)
        assert "\n" not in str(caught.value)


@pytest.mark.peer
@pytest.mark.slow
@pytest.mark.parametrize(
    ("integrator", "medium"),
    [
        ("volpath", "grid"),
        ("bdpt", "grid"),
        ("ptracer", "grid"),
        ("volpath", "constant-box"),
        ("volpath", "colour-sigma-t"),
        ("volpath", "albedo-grid"),
        ("bdpt", "colour-sigma-t"),
        ("ptracer", "albedo-grid"),
    ],
)
def test_grid_medium_cube_renders_like_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral, integrator, medium):
    """Both renderers, spectral, 16 independent images each of a cube holding a random density grid (thin and
    dense parts) under an environment and a point light (next-event estimation through the grid); 8 x 8-pixel
    block means and the image mean agree within 5 standard errors (tests/replica_agreement.py). spectrace renders
    the XML with volpath (its path tracer), bdpt and ptracer (its light tracer), Mitsuba always with volpath.
    constant-box: a heterogeneous medium of constant sigma_t, which fills only its constvolume's box, lit by the
    point light alone (an environment seen directly differs between the renderers' colour pipelines by about
    0.1 % in green, which this case's low noise would resolve). colour-sigma-t: a three-channel sigma_t grid,
    each voxel uplifted; albedo-grid: a homogeneous medium whose colour albedo grid repeats through the cube."""
    mi = mitsuba_scalar_spectral
    text, lit = {
        "grid": (_medium(), True),
        "constant-box": (CONSTANT_BOX, False),
        "colour-sigma-t": (COLOUR_SIGMA_T, True),
        "albedo-grid": (ALBEDO_GRID, True),
    }[medium]
    replicas, replica_spp, size, block = 16, 8 if lit else 24, 32, 8
    path, ours = _xml(tmp_path, size, text, environment=lit), _xml(tmp_path, size, text, integrator, lit)
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block, ours=ours)
    centre = by_mitsuba[:, 12:20, 12:20].mean()
    assert abs(centre - by_mitsuba[:, :4, :4].mean()) > 0.1 * centre  # the medium is seen


# ---------------------------------------------------------------- pbrt-v4's uniformgrid

PBRT_HEADER = """LookAt 0.1 0.05 -5  0.1 0.05 0  0 1 0
Camera "perspective" "float fov" 1
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" true
Shape "bilinearmesh" "point3 P" [-5 -5 3  5 -5 3  -5 5 3  5 5 3]
AttributeEnd
"""


def _pbrt_slab(tmp_path: Path, values: list[float], nz: int = 16) -> Path:
    """A uniformgrid of σa = 0.5 (σs = 0) whose box, [-6, -4] × [-1, 1] × [-1, 1] in its own space, the CTM at
    MakeNamedMedium moves onto the cube [-1, 1]³, which holds it behind an index-matched boundary."""
    density = " ".join(f"{v:g}" for v in values)
    corners = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    indices = " ".join(str(i) for a, b, c, d in quads for i in (a, b, c, a, c, d))
    body = f"""AttributeBegin
Translate 5 0 0
MakeNamedMedium "slab" "string type" "uniformgrid" "float density" [{density}]
  "integer nx" 2 "integer ny" 2 "integer nz" {nz} "point3 p0" [-6 -1 -1] "point3 p1" [-4 1 1]
  "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [0 0 0]
AttributeEnd
MediumInterface "slab" ""
Material "interface"
Shape "trianglemesh" "point3 P" [{" ".join(f"{v:g}" for v in corners.ravel())}] "integer indices" [{indices}]
"""
    path = tmp_path / "slab.pbrt"
    path.write_text(PBRT_HEADER + body)
    return path


def _slab_values(low: float, high: float, nz: int = 16) -> list[float]:
    return [low if z < nz // 2 else high for z in range(nz) for _ in range(4)]


def test_uniformgrid_imports_as_an_inline_grid_placed_by_the_ctm(tmp_path, device):
    """The density list, its resolution and box, and the CTM at MakeNamedMedium: looking through the cube along z,
    the light shows exp(−σa (ρ1 d1 + ρ2 d2)) = exp(−0.5 (0.4 · 1 + 1.5 · 1)), which only the grid placed on the cube
    gives."""
    from spectrace.engine.renderer import Renderer
    from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

    path = _pbrt_slab(tmp_path, _slab_values(0.4, 1.5))
    density = pbrt_scene_data(path)[0]["shapes"][1]["interior"]["density"]
    assert density["resolution"] == [2, 2, 16] and len(density["values"]) == 64
    assert density["box"] == [[-6.0, -1.0, -1.0], [-4.0, 1.0, 1.0]]
    renderer = Renderer(load_pbrt_scene(path), device)
    renderer.render(spp=256)
    y = renderer.image().xyz[..., 1].astype(np.float64)
    expected = np.exp(-0.5 * (0.4 + 1.5))
    standard_error = y.std(ddof=1) / np.sqrt(y.size)
    assert abs(y.mean() - expected) <= 4 * standard_error + 2e-3, (y.mean(), expected, standard_error)


def test_a_uniformgrid_of_the_wrong_size_is_one_line_naming_the_parameter(tmp_path):
    from spectrace.interop.pbrt import pbrt_scene_data

    path = _pbrt_slab(tmp_path, _slab_values(0.4, 1.5)[:-3])
    with pytest.raises(SpectraceError) as caught:
        pbrt_scene_data(path)
    text = str(caught.value)
    assert "\n" not in text and "slab.pbrt:" in text and "61 values; nx·ny·nz = 64" in text, text


def test_a_colour_albedo_gridvolume_imports_as_a_colour_albedo_grid(tmp_path):
    """A 3-channel gridvolume is accepted as the albedo (an RGB grid the loader uplifts per voxel), still refused
    as sigma_t (test_unsupported_grid_forms_are_reported) and as raw colour data."""
    from spectrace.interop.mitsuba import load_mitsuba_scene

    (tmp_path / "albedo.vol").write_bytes(vol_bytes(COLOUR_ALBEDO))
    path = _xml(tmp_path, 8, _medium(_colour_albedo()))
    grid = load_mitsuba_scene(path).shapes[0].interior.density
    assert grid.albedo.shape == (*DENSITY.shape, 3) and np.array_equal(grid.albedo, COLOUR_ALBEDO)
    raw = _medium(_colour_albedo('<boolean name="raw" value="true"/>'))
    with pytest.raises(SpectraceError, match="raw colour") as caught:
        mitsuba_scene_data(_xml(tmp_path, 8, raw), tmp_path)
    assert "\n" not in str(caught.value)


COLOUR_ALBEDO = np.random.default_rng(5).uniform(0.2, 1.0, (*DENSITY.shape, 3)).astype(np.float32)
COLOUR_ALBEDO[..., :3, 1] *= 0.3  # a magenta region and a paler one


def _colour_albedo(extra: str = "") -> str:
    return (
        f'<volume type="gridvolume" name="albedo"><string name="filename" value="albedo.vol"/>{GRID_TO_WORLD}'
        f"{extra}</volume>"
    )


@pytest.mark.peer
@pytest.mark.slow
def test_a_colour_albedo_grid_renders_like_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral):
    """The random density cube with a random RGB albedo grid (Mitsuba 3 uplifts each voxel and interpolates the
    spectra): 16 images each, 8 x 8-pixel block means and the image mean within 5 standard errors."""
    (tmp_path / "albedo.vol").write_bytes(vol_bytes(COLOUR_ALBEDO))
    path = _xml(tmp_path, 32, _medium(_colour_albedo()))
    by_mitsuba = assert_renders_like_mitsuba(mitsuba_scalar_spectral, path, device, 16, 8, 8)
    centre = by_mitsuba[:, 12:20, 12:20].mean(axis=(0, 1, 2))
    assert np.ptp(centre) > 0.1 * centre.mean()  # the medium's colour is seen
