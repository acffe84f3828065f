"""The wavefront render pass against the megakernel: both run the same per-segment function, so the wavefront
must estimate the same image (checked per region with independent seeds, within 4 standard errors) and keep the
megakernel's determinism and pass-split invariance. The subsurface scene takes paths through medium boundaries
and scattering points, whose state the wavefront carries between launches."""

from dataclasses import replace

import numpy as np
import pytest

from cli_runner import render_cornell_box, run_here
from cli_runner import run_spectrace as _cli
from spectrace.benchmarks.kernel_shapes import Variant, run_kernel_shape_bench
from spectrace.engine.launch import render_work_group
from spectrace.engine.renderer import Renderer
from spectrace.engine.wavefront import WavefrontRenderer, make_renderer
from spectrace.errors import SpectraceError
from spectrace.io.exr import read_exr
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

SIZE = 32
REGION = 8  # pixels per side of a compared region: 16 regions of 64 pixels


def _scene(name: str, **overrides):
    return load_scene(scenes_dir() / f"{name}.toml").with_overrides(width=SIZE, height=SIZE, **overrides)


def _instanced_cornell_box():
    """The Cornell box with an object (a cube under a smooth ball) placed three times, once mirrored."""
    import spectrace

    ball = spectrace.shape("sphere", spectrace.plastic(0.4), tessellated=True, transform=[{"translate": [0, 2, 0]}])
    obj = spectrace.instanced_object([spectrace.shape("cube", spectrace.diffuse(0.6)), ball])
    placements = [
        [{"scale": 0.04}, {"translate": [0.45, 0.04, 0.1]}],
        [
            {"scale": [0.05, 0.03, 0.04]},
            {"rotate": {"axis": [0, 1, 0], "angle": 30}},
            {"translate": [0.32, 0.03, 0.02]},
        ],
        [
            {"matrix": [[-0.035, 0, 0, 0], [0, 0.035, 0, 0], [0, 0, 0.035, 0], [0, 0, 0, 1]]},
            {"translate": [0.09, 0.035, 0.45]},
        ],
    ]
    scene = _scene("cornell_box", spp=16, max_depth=8)
    return replace(scene, instances=[spectrace.instance(obj, p) for p in placements])


def _measured_cornell_box():
    """The Cornell box with every other unlit surface a measured GGX reflector (tests/rgl_tensor.py)."""
    import spectrace
    from rgl_tensor import ggx_file

    scene = _scene("cornell_box", spp=16, max_depth=8)
    measured = spectrace.measured(ggx_file(0.3))
    shapes = [
        replace(shape, material=measured) if shape.emitter is None and i % 2 == 0 else shape
        for i, shape in enumerate(scene.shapes)
    ]
    return replace(scene, shapes=shapes)


SCENES = {
    "cornell_box": lambda: _scene("cornell_box", spp=16, max_depth=8),
    "measured": _measured_cornell_box,
    "subsurface": lambda: _scene("subsurface", spp=16, max_depth=16),
    "instances": _instanced_cornell_box,
}


def _region_differences(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per region and XYZ channel: the mean of the per-pixel differences and its standard error. The pixels'
    differences are independent with mean zero when both images estimate the same expectation."""
    d = a.astype(np.float64) - b.astype(np.float64)
    blocks = d.reshape(SIZE // REGION, REGION, SIZE // REGION, REGION, 3).transpose(0, 2, 1, 3, 4)
    blocks = blocks.reshape(-1, REGION * REGION, 3)
    return blocks.mean(axis=1), blocks.std(axis=1, ddof=1) / np.sqrt(REGION * REGION)


@pytest.mark.parametrize("name", SCENES)
def test_wavefront_estimates_the_megakernels_image(device, name):
    scene = SCENES[name]()
    megakernel = Renderer(scene.with_overrides(seed=11), device).render().xyz
    wavefront = WavefrontRenderer(scene.with_overrides(seed=12), device).render().xyz
    assert np.all(np.isfinite(wavefront)) and wavefront[..., 1].mean() > 0.01
    assert not np.array_equal(megakernel, wavefront)
    mean, standard_error = _region_differences(wavefront, megakernel)
    # A region seen only on the light has almost no noise; allow float rounding of its mean there.
    tolerance = 4 * standard_error + 1e-6 * np.abs(megakernel).max()
    assert np.all(np.abs(mean) < tolerance), np.argwhere(np.abs(mean) >= tolerance)


@pytest.mark.parametrize("name", SCENES)
def test_wavefront_is_deterministic_and_split_invariant(device, name):
    scene = SCENES[name]().with_overrides(spp=6)
    one_pass = WavefrontRenderer(scene, device)
    one_pass.run_pass(6)
    split = WavefrontRenderer(scene, device)
    for count in (1, 2, 3):
        split.run_pass(count)
    again = WavefrontRenderer(scene, device)
    again.run_pass(6)
    film, rays = one_pass.read_film()
    for other in (split, again):
        other_film, other_rays = other.read_film()
        assert np.array_equal(film.view(np.uint32), other_film.view(np.uint32))
        assert np.array_equal(rays, other_rays)
    assert rays.sum() > 0


def test_wavefront_counts_every_ray_once(device):
    """The rays traced are counted in the slots between launches; the megakernel counts the same paths' rays."""
    scene = SCENES["subsurface"]().with_overrides(spp=2)
    megakernel = Renderer(scene, device)
    megakernel.run_pass(2)
    wavefront = WavefrontRenderer(scene, device)
    wavefront.run_pass(2)
    (_, mega_rays), (_, wave_rays) = megakernel.read_film(), wavefront.read_film()
    # Same seed, same per-segment code: the same paths, unless a runtime rounds the two programs differently,
    # which may change a few paths' lengths but not the total by more than a fraction.
    assert abs(int(wave_rays.sum()) - int(mega_rays.sum())) <= 0.01 * mega_rays.sum()


def test_wavefront_refuses_the_direct_integrator(device):
    with pytest.raises(SpectraceError, match="path integrator only"):
        WavefrontRenderer(_scene("cornell_box").with_overrides(integrator="direct"), device)


def test_unknown_kernel_shape_is_refused(device):
    with pytest.raises(SpectraceError, match="unknown kernel shape"):
        make_renderer(_scene("cornell_box"), device, "persistent")


def test_render_command_runs_the_wavefront(tmp_path):
    out = tmp_path / "wavefront.exr"
    result = run_here(
        *render_cornell_box(out, 2, 16, 12),
        "--kernel",
        "wavefront",
        "-q",
    )
    assert result.returncode == 0, result.stderr
    channels, header = read_exr(out)
    assert header["spectrace:spp"] == "2"
    assert np.all(np.isfinite(channels["RGB"])) and channels["Y"].mean() > 0


@pytest.mark.subprocess
@pytest.mark.slow
def test_render_command_refuses_an_unknown_kernel_shape_in_one_line(tmp_path):
    result = _cli(
        "render", str(scenes_dir() / "cornell_box.toml"), "-o", str(tmp_path / "x.png"), "--kernel", "persistent"
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "unknown kernel shape 'persistent'" in result.stderr
    assert "Traceback" not in result.stderr


def test_kernel_shape_bench_reports_every_variant(device):
    variants = [Variant("megakernel", None), Variant("wavefront", 32)]  # the sizes the other tests compile
    rows = run_kernel_shape_bench(None, [SIZE], 1, 3, device.report.key, variants, repeats=2)
    generic = ("megakernel", render_work_group(device), False)  # added: the kernel built for every scene
    assert [(r["kernel"], r["work_group"], r["specialised"]) for r in rows] == [
        ("megakernel", None, True),
        ("wavefront", 32, True),
        generic,
    ]
    assert all(r["samples_per_second"] > 0 and r["repeats"] == 2 for r in rows)
