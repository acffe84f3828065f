"""Heterogeneous (grid) media (docs/media.md): the free flights and the ratio-tracked transmittance of
kernels/medium_grid.cl against closed forms and an independent quadrature of the trilinear density, whole
renders of grid media against the homogeneous medium and Beer–Lambert, and the scene keys and their errors."""

import numpy as np
import pytest
from scipy import ndimage

import spectrace
from scene_text import CAMERA_FILM_GREY
from spectrace.core.contract import MEDIUM_DTYPE
from spectrace.engine.meters import RadianceMeter, measure
from spectrace.errors import SpectraceError
from spectrace.geometry import primitives
from spectrace.geometry.grid_volume import box_matrix, majorant_grid, make_grid, medium_row, read_vol, vol_bytes
from spectrace.geometry.transforms import apply_transform, transform_matrix
from spectrace.scene import load_scene
from spectrace.scene.model import Camera, ConstantEnvironment, Medium, Scene, Shape
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.table import SpectrumTable
from stats_toolkit import assert_within_standard_errors, mean_and_standard_error

LANES_NM = np.array([420.0, 500.0, 580.0, 680.0])


def _wavy(mean: float, phase: float = 0.0) -> Spectrum:
    return Spectrum(mean * (1.0 + 0.7 * np.sin((GRID_NM - 360.0) / 40.0 + phase)))


def _two_valued(low: float, high: float, n: int = 16) -> np.ndarray:
    """A grid whose lower half in z holds `low`, its upper half `high` (shape (n, 2, 2))."""
    density = np.full((n, 2, 2), low, np.float32)
    density[n // 2 :] = high
    return density


def _device_medium(medium: Medium) -> tuple[np.ndarray, np.ndarray]:
    table = SpectrumTable()
    table.add(Spectrum.zeros())  # a non-zero offset exercises the indexing
    row = np.array([medium_row(medium, table)], MEDIUM_DTYPE)
    return table.data, row


def _density_along(grid, origin, direction, t):
    """The trilinear density at origin + t·direction, computed apart from the kernels: scipy's linear
    interpolation of the voxel centres, clamped at the faces, 0 outside the box."""
    points = origin + t[:, None] * direction
    unit = (np.c_[points, np.ones(len(t))] @ np.linalg.inv(grid.to_world).T)[:, :3]
    nz, ny, nx = grid.density.shape
    coords = np.stack([unit[:, 2] * nz - 0.5, unit[:, 1] * ny - 0.5, unit[:, 0] * nx - 0.5])
    values = ndimage.map_coordinates(grid.density.astype(np.float64), coords, order=1, mode="nearest")
    inside = np.all((unit >= 0.0) & (unit <= 1.0), axis=1)
    return np.where(inside, values, 0.0)


def _random_grid():
    rng = np.random.default_rng(7)
    density = rng.uniform(0.0, 2.0, (5, 6, 7)).astype(np.float32)
    density[2, 3] = 0.0  # empty voxels: cells whose majorant is low
    matrix = transform_matrix([{"rotate": {"axis": [1, 2, 0.5], "angle": 35}}], where="t") @ box_matrix(
        (-1.0, -0.5, -0.8), (1.2, 0.6, 0.9)
    )
    return make_grid(density, matrix)


CASES = {
    # a ray along z through the middle of a two-valued slab: the closed form exp(−σt (ρ1 d1 + ρ2 d2))
    "two-valued-slab": (
        lambda: make_grid(_two_valued(0.4, 1.5), box_matrix((-1, -1, -1), (1, 1, 1))),
        np.array([0.1, -0.2, -3.0]),
        np.array([0.0, 0.0, 1.0]),
    ),
    # an oblique ray through a rotated random grid: quadrature of the trilinear density
    "random-rotated-grid": (
        _random_grid,
        np.array([-2.0, -1.5, -1.0]),
        np.array([2.0, 1.6, 1.9]) / np.linalg.norm([2.0, 1.6, 1.9]),
    ),
}


def _optical_depth(case, t_end, points=40_001):
    make, origin, direction = CASES[case]
    t = np.linspace(0.0, t_end, points)
    return t, _density_along(make(), origin, direction, t)


@pytest.mark.parametrize("case", CASES)
def test_ratio_tracking_gives_the_transmittance(kernel_runner, case):
    """The mean of the ratio-tracking estimates is exp(−σt(λ) ∫ρ dt) for each lane; for the two-valued slab the
    integral is ρ1 d1 + ρ2 d2 = 0.4 + 1.5 (the trilinear ramp between the halves integrates to the step's value)."""
    make, origin, direction = CASES[case]
    sigma_a, sigma_s = _wavy(0.5, 1.0), _wavy(0.4)
    spectra, medium = _device_medium(Medium(sigma_a, sigma_s, density=make()))
    runner = kernel_runner("testing/medium_grid_sampling.cl")
    n, length = 100_000, 6.0
    out = np.empty((n, 4), np.float32)
    args = [
        runner.buffer(spectra),
        runner.buffer(medium),
        LANES_NM.astype(np.float32),
        np.array([*origin, 0.0], np.float32),
        np.array([*direction, 0.0], np.float32),
        np.float32(length),
        np.uint32(11),
        runner.buffer(out, True),
    ]
    runner.run("grid_transmittances", n, args, {7: out})
    sigma_t = sigma_a.evaluate(LANES_NM) + sigma_s.evaluate(LANES_NM)
    if case == "two-valued-slab":
        depth = 0.4 * 1.0 + 1.5 * 1.0
    else:
        t, rho = _optical_depth(case, length)
        depth = np.trapezoid(rho, t)
        assert depth > 0.5  # the ray crosses the grid
    expected = np.exp(-sigma_t * depth)
    assert np.all(out >= 0.0) and np.all(out <= 1.0 + 1e-6)
    mean, se = mean_and_standard_error(out)
    assert_within_standard_errors(mean, expected, se, slack=2e-4 * expected, what=case, power=0.05)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("hero_only", [0, 1])
def test_grid_free_flights_are_unbiased_for_every_lane(kernel_runner, case, hero_only):
    """Delta tracking against the majorant: each lane's expected weight for reaching the surface is its
    transmittance, and for scattering within each stretch [a, b] of the ray ∫_a^b σs(λ) ρ(t) T_λ(t) dt (the
    density of the free flight, bin by bin), with T_λ from a quadrature of the trilinear density."""
    make, origin, direction = CASES[case]
    sigma_a, sigma_s = _wavy(0.5, 1.0), _wavy(0.6)
    spectra, medium = _device_medium(Medium(sigma_a, sigma_s, density=make()))
    runner = kernel_runner("testing/medium_grid_sampling.cl")
    n, t_surface = 200_000, 4.5  # the surface inside the grid for the oblique ray
    scattered = np.empty((n, 4), np.float32)
    surface = np.empty((n, 4), np.float32)
    distance = np.empty(n, np.float32)
    args = [
        runner.buffer(spectra),
        runner.buffer(medium),
        LANES_NM.astype(np.float32),
        np.array([*origin, 0.0], np.float32),
        np.array([*direction, 0.0], np.float32),
        np.float32(t_surface),
        np.int32(hero_only),
        np.uint32(5),
        runner.buffer(scattered, True),
        runner.buffer(surface, True),
        runner.buffer(distance, True),
    ]
    runner.run("grid_flights", n, args, {8: scattered, 9: surface, 10: distance})
    alive = np.array([1.0, 0.0, 0.0, 0.0]) if hero_only else np.ones(4)
    sigma_t = sigma_a.evaluate(LANES_NM) + sigma_s.evaluate(LANES_NM)
    t, rho = _optical_depth(case, t_surface)
    depth = np.concatenate([[0.0], np.cumsum((rho[1:] + rho[:-1]) / 2 * np.diff(t))])
    transmittance = np.exp(-np.outer(depth, sigma_t))
    mean, se = mean_and_standard_error(surface)
    assert_within_standard_errors(mean, alive * transmittance[-1], se, slack=1e-4, what="reached the surface")
    integrand = sigma_s.evaluate(LANES_NM) * rho[:, None] * transmittance
    steps = (integrand[1:] + integrand[:-1]) / 2 * np.diff(t)[:, None]
    cumulative = np.concatenate([np.zeros((1, 4)), np.cumsum(steps, 0)])
    edges = np.linspace(0.0, t_surface, 10)
    expected_bins = np.diff(np.array([np.interp(edges, t, cumulative[:, lane]) for lane in range(4)]).T, axis=0)
    which = np.digitize(distance, edges) - 1
    for b in range(len(edges) - 1):
        in_bin = np.where((which == b)[:, None], scattered, 0.0)
        mean, se = mean_and_standard_error(in_bin)
        assert_within_standard_errors(mean, alive * expected_bins[b], se, slack=1e-4, what=f"{case} bin {b}")
    assert np.all(scattered[distance < 0] == 0.0) and np.all(distance < t_surface)
    assert expected_bins.sum() > 0.2  # the flights scatter often enough to test the density


def test_the_majorant_bounds_the_trilinear_density_everywhere():
    """Every cell's majorant is at least the density anywhere in it (a dense sampling of points), and at most the
    grid's largest voxel."""
    grid = _random_grid()
    majorant = majorant_grid(grid.density)
    rng = np.random.default_rng(3)
    unit = rng.uniform(0.0, 1.0, (200_000, 3))
    world = (np.c_[unit, np.ones(len(unit))] @ grid.to_world.T)[:, :3]
    origin = np.zeros(3)
    rho = _density_along(grid, origin, world, np.ones(len(world)))
    cells = np.minimum((unit * np.array(majorant.shape[::-1])).astype(int), np.array(majorant.shape[::-1]) - 1)
    bound = majorant[cells[:, 2], cells[:, 1], cells[:, 0]]
    assert np.all(rho <= bound + 1e-6)
    assert majorant.max() == grid.density.max()


# ---------------------------------------------------------------- whole renders


def _scene(shapes, max_depth=-1, k=1.0):
    return Scene(
        camera=Camera((0.0, 0.0, -1.0), (0.0, 0.0, 0.0)),
        width=1,
        height=1,
        shapes=list(shapes),
        lights=[ConstantEnvironment(Spectrum.constant(k))],
        max_depth=max_depth,
    )


def _cube(medium: Medium) -> Shape:
    return Shape(mesh=primitives.cube(), material=None, interior=medium)


@pytest.mark.parametrize(
    ("sigma_s", "max_depth"), [(0.0, -1), (0.5, 1)], ids=["pure-absorber", "scattering-slab-unscattered-part"]
)
def test_light_through_a_two_valued_slab_follows_the_closed_form(device, sigma_s, max_depth):
    """A meter looking along z through an index-matched cube [-1, 1]³ whose density is 0.4 in its lower half and 1.5
    in its upper, at an environment of radiance k: L = k exp(−σt(λ) (0.4 · 1 + 1.5 · 1)) (with emitters-only depth
    for the scattering slab: its unscattered part)."""
    sigma_a = _wavy(0.4)
    medium = Medium(
        sigma_a,
        _wavy(sigma_s, 2.0) if sigma_s else Spectrum.zeros(),
        density=make_grid(_two_valued(0.4, 1.5), box_matrix((-1, -1, -1), (1, 1, 1))),
    )
    reading = measure(
        _scene([_cube(medium)], max_depth=max_depth),
        RadianceMeter((0.1, 0.05, -3.0), (0.0, 0.0, 1.0)),
        wavelengths_nm=LANES_NM,
        streams=32,
        samples_per_item=8192,
        device=device,
    )
    sigma_t = medium.sigma_a.evaluate(LANES_NM) + medium.sigma_s.evaluate(LANES_NM)
    expected = np.exp(-sigma_t * (0.4 + 1.5))
    assert_within_standard_errors(
        reading.spectral, expected, reading.spectral_standard_error, slack=1e-4, what=sigma_s, power=0.05
    )


def test_a_scattering_grid_in_a_uniform_environment_is_a_furnace(device):
    """A cube of a random, rotated density grid that scatters without absorbing (σs varying over the spectrum,
    g = 0.6) in an environment of radiance k: every path leaves with all its light, so the meter reads k at each
    lane, all bounces (the white furnace of the delta-tracking weights, albedo grid 1 by default)."""
    grid = _random_grid()
    medium = Medium(Spectrum.zeros(), _wavy(3.0, 0.5), g=0.6, density=grid)
    k = 0.7
    reading = measure(
        _scene([_cube(medium)], k=k),
        RadianceMeter((0.2, 0.1, -3.0), (0.0, 0.0, 1.0)),
        wavelengths_nm=LANES_NM,
        streams=32,
        samples_per_item=512,
        device=device,
    )
    assert_within_standard_errors(
        reading.spectral, np.full(4, k), reading.spectral_standard_error, slack=1e-4, what="furnace", power=0.05
    )


def test_light_inside_a_medium_seen_through_a_grid_slab_is_attenuated_by_both(device):
    """A diffuse floor lit by a lamp standing inside an absorbing homogeneous cube, with an absorbing slab between
    them, seen from just above the floor and below the slab (one bounce): a slab of a constant grid gives what the
    same homogeneous slab gives. Next-event estimation's shadow rays from the floor cross the grid, then end inside
    the other medium, and must carry both transmittances."""
    from spectrace.scene.model import AreaEmitter, DiffuseMaterial

    def placed(mesh, steps):
        return apply_transform(mesh, transform_matrix(steps, where="test"))

    lamp = Shape(
        mesh=placed(
            primitives.rectangle(),
            [{"rotate": {"axis": [1, 0, 0], "angle": 90}}, {"scale": 0.4}, {"translate": [0.0, 1.0, 0.0]}],
        ),
        material=DiffuseMaterial(Spectrum.zeros()),
        emitter=AreaEmitter(Spectrum.constant(2.0)),
    )
    around = Shape(
        mesh=placed(primitives.cube(), [{"scale": 0.7}, {"translate": [0.0, 1.0, 0.0]}]),
        material=None,
        interior=Medium(_wavy(0.6), Spectrum.zeros()),
    )
    floor = Shape(
        mesh=placed(primitives.rectangle(), [{"rotate": {"axis": [1, 0, 0], "angle": -90}}, {"scale": 2.0}]),
        material=DiffuseMaterial(Spectrum.constant(0.8)),
    )
    slab_mesh = placed(primitives.cube(), [{"scale": [1.5, 0.05, 1.5]}, {"translate": [0.0, 0.15, 0.0]}])
    grid = make_grid(np.ones((2, 3, 4), np.float32), box_matrix((-1.5, 0.1, -1.5), (1.5, 0.2, 1.5)))
    eye = np.array([0.0, 0.05, -0.4])
    readings = [
        measure(
            _scene([lamp, around, floor, Shape(slab_mesh, None, interior=slab)], max_depth=2, k=0.0),
            RadianceMeter(tuple(eye), tuple(-eye / np.linalg.norm(eye))),
            wavelengths_nm=LANES_NM,
            streams=32,
            samples_per_item=1024,
            device=device,
        )
        for slab in (Medium(_wavy(5.0, 2.0), Spectrum.zeros()), Medium(_wavy(5.0, 2.0), Spectrum.zeros(), density=grid))
    ]
    homogeneous, gridded = readings
    se = np.hypot(homogeneous.spectral_standard_error, gridded.spectral_standard_error)
    assert_within_standard_errors(gridded.spectral, homogeneous.spectral, se, power=0.05, what="slab under a lamp")


def test_a_constant_grid_renders_as_the_homogeneous_medium(device):
    """A scattering cube whose grid holds 0.5 everywhere (its box the cube's) with coefficients 2σ gives the same
    radiance, all bounces, as the homogeneous medium of σ (within 4 standard errors of their difference)."""
    sigma_a, sigma_s = _wavy(0.3, 1.0), _wavy(1.2)
    grid = make_grid(np.full((4, 5, 6), 0.5, np.float32), box_matrix((-1, -1, -1), (1, 1, 1)))
    readings = [
        measure(
            _scene([_cube(medium)], max_depth=16),
            RadianceMeter((0.3, 0.2, -3.0), (0.0, 0.0, 1.0)),
            wavelengths_nm=LANES_NM,
            streams=32,
            samples_per_item=512,
            device=device,
        )
        for medium in (
            Medium(sigma_a, sigma_s, g=0.4),
            Medium(sigma_a.scaled(2.0), sigma_s.scaled(2.0), g=0.4, density=grid),
        )
    ]
    homogeneous, gridded = readings
    se = np.hypot(homogeneous.spectral_standard_error, gridded.spectral_standard_error)
    assert_within_standard_errors(gridded.spectral, homogeneous.spectral, se, power=0.05, what="constant grid")
    assert np.all(homogeneous.spectral < 0.9)  # the medium dims the environment: the comparison sees it


# ---------------------------------------------------------------- scene keys, the API and the .vol reader


def _scene_text(interior: str) -> str:
    return (
        CAMERA_FILM_GREY
        + f"""
[[shapes]]
type = "cube"
interior = {interior}
"""
    )


def test_scene_file_reads_a_vol_file_and_inline_values(tmp_path):
    values = np.arange(24, dtype=np.float32).reshape(2, 3, 4) / 24
    (tmp_path / "smoke.vol").write_bytes(vol_bytes(values, (-1, -1, -1), (1, 1, 1)))
    inline = ", ".join(repr(float(v)) for v in values.ravel())
    for density in (
        '{ file = "smoke.vol", box = [[-1, -1, -1], [1, 1, 1]] }',
        f"{{ values = [{inline}], resolution = [4, 3, 2], box = [[-1, -1, -1], [1, 1, 1]] }}",
    ):
        path = tmp_path / "scene.toml"
        path.write_text(_scene_text(f"{{ sigma_s = {{ value = 2.0 }}, density = {density} }}"))
        grid = load_scene(path).shapes[0].interior.density
        assert np.array_equal(grid.density, values)
        assert np.allclose(grid.to_world, box_matrix((-1, -1, -1), (1, 1, 1)))
    decoded, p0, p1 = read_vol(tmp_path / "smoke.vol", where="w")
    assert decoded.shape == (2, 3, 4, 1) and list(p0) == [-1, -1, -1] and list(p1) == [1, 1, 1]


@pytest.mark.parametrize(
    ("density", "files", "message"),
    [
        ('{ file = "cut.vol" }', {"cut.vol": vol_bytes(np.ones((2, 2, 2)))[:-3]}, "the volume file 'cut.vol' has"),
        ('{ file = "bad.vol" }', {"bad.vol": b"NOTAVOLUME" * 10}, "file: 'bad.vol' is not a Mitsuba volume file"),
        ('{ file = "none.vol" }', {}, "density.file: cannot read the volume file 'none.vol'"),
        ("{ values = [1, 2, 3], resolution = [2, 2, 1] }", {}, "density.values: 3 values for resolution 2×2×1"),
        ("{ values = [1, -2], resolution = [2, 1, 1] }", {}, "density: the density holds negative values"),
        ("{ values = [1, 2] }", {}, "values need resolution"),
        (
            "{ values = [1, 2], resolution = [2, 1, 1], albedo_values = [0.5, 1.5] }",
            {},
            "density: the albedo holds values above 1",
        ),
        ("{ values = [1], resolution = [1, 1, 1], box = [[0, 0, 0], [1, 0, 1]] }", {}, "invertible"),
    ],
)
def test_bad_grids_are_refused_in_one_line_naming_the_key(tmp_path, density, files, message):
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    path = tmp_path / "scene.toml"
    path.write_text(_scene_text(f"{{ sigma_s = {{ value = 1.0 }}, density = {density} }}"))
    with pytest.raises(SpectraceError) as caught:
        load_scene(path)
    text = str(caught.value)
    assert "\n" not in text and "shapes[0].interior" in text and message in text, text


def test_api_density_grid_matches_the_scene_file(tmp_path):
    values = np.random.default_rng(1).uniform(0, 1, (3, 2, 4)).astype(np.float32)
    albedo = np.full_like(values, 0.25)
    steps = [{"rotate": {"axis": [0, 1, 0], "angle": 30}}, {"translate": [0.5, 0, 0]}]
    grid = spectrace.density_grid(values, albedo=albedo, box=((-1, -2, -1), (1, 2, 3)), transform=steps)
    medium = spectrace.medium(sigma_s=1.0, density=grid)
    assert medium.density is grid
    (tmp_path / "d.vol").write_bytes(vol_bytes(values))
    (tmp_path / "a.vol").write_bytes(vol_bytes(albedo))
    path = tmp_path / "scene.toml"
    path.write_text(
        _scene_text(
            '{ sigma_s = { value = 1.0 }, density = { file = "d.vol", albedo_file = "a.vol", '
            "box = [[-1, -2, -1], [1, 2, 3]], transform = [{ rotate = { axis = [0, 1, 0], angle = 30 } }, "
            "{ translate = [0.5, 0, 0] }] } }"
        )
    )
    assert load_scene(path).shapes[0].interior.density == grid
    with pytest.raises(SpectraceError, match="density must be a grid"):
        spectrace.medium(sigma_s=1.0, density=values)
    with pytest.raises(SpectraceError, match="albedo grid's shape"):
        spectrace.density_grid(values, albedo=albedo[:2])


def test_an_instanced_grid_medium_is_refused():
    grid = make_grid(np.ones((2, 2, 2), np.float32), np.eye(4))
    cube = Shape(
        mesh=apply_transform(primitives.cube(), np.eye(4)),
        material=None,
        interior=Medium(Spectrum.zeros(), Spectrum.constant(1.0), density=grid),
    )
    obj = spectrace.instanced_object([cube], name="puff")
    scene = Scene(
        camera=Camera((0.0, 0.0, -4.0), (0.0, 0.0, 0.0)),
        width=4,
        height=4,
        shapes=[],
        instances=[spectrace.instance(obj)],
        lights=[ConstantEnvironment(Spectrum.constant(1.0))],
    )
    from spectrace.engine.scene_buffers import build_scene_buffers

    with pytest.raises(SpectraceError, match="density grid cannot be instanced"):
        build_scene_buffers(scene)


@pytest.mark.subprocess
@pytest.mark.parametrize("suffix", ["toml", "xml"])
@pytest.mark.slow
def test_render_of_a_truncated_vol_file_is_one_line_and_keeps_the_output(tmp_path, suffix):
    """`spectrace render` of a scene file or a Mitsuba XML whose volume file is cut short: exit status 2 (bad
    input), one line naming the scene file and the volume file, no traceback, and the image already at the output
    path untouched."""
    from cli_runner import run_spectrace

    (tmp_path / "density.vol").write_bytes(vol_bytes(np.ones((3, 3, 3)))[:-4])
    if suffix == "toml":
        scene = tmp_path / "scene.toml"
        scene.write_text(_scene_text('{ sigma_s = { value = 1.0 }, density = { file = "density.vol" } }'))
    else:
        scene = tmp_path / "scene.xml"
        scene.write_text(
            """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
<integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
<shape type="cube"><bsdf type="null"/><medium type="heterogeneous" name="interior">
<volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/></volume></medium></shape>
</scene>"""
        )
    out = tmp_path / "out.png"
    out.write_bytes(b"an earlier image")
    result = run_spectrace("render", str(scene), "-o", str(out), "--spp", "1")
    assert result.returncode == 2, result.stderr  # the status of bad input
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert scene.name in lines[0] and "'density.vol' has" in lines[0], lines[0]
    assert out.read_bytes() == b"an earlier image"


def test_a_grid_medium_render_split_into_passes_keeps_its_bits(device):
    """The delta-tracking numbers after a flight's first come from a hash of the sampler's draws, so a render of a
    scattering grid split into passes is the one-pass render, bit for bit."""
    from spectrace.engine.renderer import Renderer

    medium = Medium(_wavy(0.2), _wavy(2.0, 1.0), g=0.3, density=_random_grid())
    scene = Scene(
        camera=Camera((0.5, 0.3, -4.0), (0.0, 0.0, 0.0)),
        width=8,
        height=8,
        shapes=[_cube(medium)],
        lights=[ConstantEnvironment(Spectrum.constant(1.0))],
        max_depth=8,
    )
    whole = Renderer(scene, device)
    whole.render(spp=8)
    split = Renderer(scene, device)
    split.render(spp=8, pass_spp=3)
    a, b = whole.image().xyz, split.image().xyz
    assert np.all(np.isfinite(a)) and a[..., 1].mean() > 0
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_a_session_edits_a_grid_in_place(tmp_path):
    """A live session re-packs a grid medium's rows when its density values change, and then renders what a
    session opened on the edited file renders, bit for bit."""
    values = [0.5, 2, 1, 0, 3, 1, 0.2, 1]
    edited = [2, 0, 0, 1, 0.5, 0.5, 3, 0]

    def scene_file(name, density):
        path = tmp_path / name
        text = _scene_text(
            f"{{ sigma_s = {{ value = 2.0 }}, density = {{ values = {density}, resolution = [2, 2, 2], "
            "box = [[-1, -1, -1], [1, 1, 1]] } }"
        )
        light = '[[lights]]\ntype = "constant"\nradiance = { value = 1.0 }\n'
        path.write_text(text.replace('type = "cube"', 'type = "cube"\nname = "cloud"') + light)
        return path

    session = spectrace.Session(load_scene(scene_file("a.toml", values)))
    session.step()
    before = session.image().xyz.copy()
    session.update({"shapes.cloud.interior.density.values": edited})
    session.step()
    fresh = spectrace.Session(load_scene(scene_file("b.toml", edited)))
    fresh.step()
    after, expected = session.image().xyz, fresh.image().xyz
    assert after[..., 1].mean() > 0 and not np.array_equal(before, after)
    assert np.array_equal(after.view(np.uint32), expected.view(np.uint32))
