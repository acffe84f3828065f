"""`spectrace bench` modes run as a user runs them, on tiny sizes, with --json: the object parses and its figures
are consistent with what was asked (triangle counts, ray counts, spp). Speed is never asserted. Where Mitsuba or
Embree is installed (the `bench` extra) the comparisons they feed run too and must agree with spectrace."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run_spectrace

SCENES = Path(__file__).resolve().parents[2] / "scenes"

pytestmark = pytest.mark.subprocess


def _bench(mode: str, *args, environment: dict[str, str] | None = None) -> dict:
    result = subprocess.run(
        [sys.executable, "-m", "spectrace", "bench", mode, "--json", *args],
        capture_output=True,
        text=True,
        env=os.environ | (environment or {}),
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.fixture(scope="module")
def modes() -> dict:
    """The scaling, rays and quality modes, each its own run: the checks below read their parts."""
    return {
        **_bench("scaling", "--size", "8", "--spp", "1", "--triangles", "100"),
        **_bench("rays", "--triangles", "100", "--ray-count", "3000", "--rounds", "3"),
        **_bench("quality", "--size", "8", "--seconds", "0.05"),
    }


def _llvm_variant_or_skip() -> None:
    """Skips, with the probe's reason, where Mitsuba's LLVM variant cannot run (no libLLVM Dr.Jit accepts)."""
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    from spectrace.benchmarks.mitsuba_runtime import LLVM_VARIANT, probe_variant

    probe = probe_variant(LLVM_VARIANT)  # in a child process, and cached: the bench below reuses the answer
    if not probe.ok:
        pytest.skip(f"{LLVM_VARIANT}: variant unavailable: {probe.reason}")


@pytest.mark.slow
def test_scaling_rays_and_quality_modes(modes):
    out = modes
    scaling = out["scaling"]
    assert [r["width"] for r in scaling["resolution"]] == [8]
    assert [r["max_depth"] for r in scaling["depth"]] == [1, 2, 4, 8, 16]
    # The box alone, then the box plus an icosphere of 20 * 4**2 triangles (the smallest with >= 100).
    box, with_sphere = (r["triangles"] for r in scaling["triangles"])
    assert with_sphere - box == 320
    assert all(r["spp"] == 1 and r["samples_per_second"] > 0 for r in scaling["resolution"] + scaling["depth"])

    rays = out["rays"]
    assert rays["triangles"] == 320 and rays["rays"] == 3000
    assert rays["bvh"]["sah_cost"] > 0 and rays["bvh"]["nodes"] >= 1
    # The tree the kernel walks: wide nodes, and leaves of up to 8 triangles in blocks of four or eight, so at least
    # ceil(320 / 8) leaves' worth of blocks and at most one block per triangle.
    assert 1 <= rays["bvh"]["nodes_wide"] < rays["bvh"]["nodes"] and rays["bvh"]["depth_wide"] <= rays["bvh"]["depth"]
    assert 320 // 8 <= rays["bvh"]["leaf_blocks"] <= 320
    assert len(rays["spectrace"]) == 1 and rays["spectrace"][0]["rays_per_second"] > 0
    # Three timed traces, whose median the figures are.
    ours = rays["spectrace"][0]
    assert rays["rounds"] == 3 and len(ours["round_seconds"]) == len(ours["round_cores"]) == 3
    assert ours["seconds"] == np.median(ours["round_seconds"]) and ours["rays_per_second"] == 3000 / ours["seconds"]
    # The load judged as `bench peer` judges it: a pause before each trace and after the last.
    load = rays["load"]
    assert set(load) == {"before", "after", "cores", "others", "pauses", "limit", "busy", "steal"}
    traces = 3 * (1 + (rays["embree"] is not None))
    assert load["pauses"] == (traces + 1 if os.path.exists("/proc/loadavg") else 0)
    assert any(note.startswith("machine busy") for note in rays["notes"]) is load["busy"]

    quality = out["quality"]
    assert quality["reference"]["spp"] == 1024
    ours = quality["renderers"][0]
    assert ours["renderer"] == "spectrace" and ours["spp"] >= 1 and ours["rmse"] > 0
    assert ours["spp"] & (ours["spp"] - 1) == 0  # the default Sobol sampler renders a power of two
    assert ours["above"]["spp"] == 2 * ours["spp"]  # and the next, bracketing the budget
    # The load judged as `bench peer` judges it: a pause before each timed render (spectrace's two and its equal-spp
    # render, each Mitsuba variant's timed and equal-spp renders) and after the last.
    load = quality["load"]
    assert set(load) == {"before", "after", "cores", "others", "pauses", "limit", "busy", "steal"}
    peers = sum(row["renderer"] == "mitsuba" for row in quality["renderers"])
    assert load["pauses"] == (3 + 2 * peers + 1 if os.path.exists("/proc/loadavg") else 0)
    assert any(note.startswith("machine busy") for note in quality["notes"]) is load["busy"]


@pytest.mark.slow
def test_the_rays_and_quality_tables_print_the_load_line(modes):
    from rich.console import Console

    from spectrace.benchmarks.bench_rounds import load_text
    from spectrace.benchmarks.quality import quality_tables
    from spectrace.benchmarks.rays import rays_tables

    for tables, result in ((rays_tables, modes["rays"]), (quality_tables, modes["quality"])):
        console = Console(width=400, record=True, markup=False)
        for table in tables(result):
            console.print(table)
        text = " ".join(console.export_text().split())  # captions wrap at their table's width
        assert " ".join(load_text(result["load"]).split()) in text


@pytest.mark.slow
@pytest.mark.peer
def test_rays_agree_with_embree(modes):
    pytest.importorskip("embreex", reason="the Embree comparison needs `pip install spectrace[bench]`")
    agreement = modes["rays"]["agreement"][0]
    assert agreement["rays"] == 3000
    # Same rays, same mesh: a ray may disagree only where it grazes an edge.
    assert agreement["same_hit_or_miss"] >= 0.998 and agreement["within_1e-4"] >= 0.998
    # The per-core ratio is the median of the rounds' ratios, inside their range.
    ours, theirs = modes["rays"]["spectrace"][0], modes["rays"]["embree"]
    ratios = np.divide(ours["round_rays_per_second_per_core"], theirs["round_rays_per_second_per_core"])
    assert agreement["per_core_ratio"] == np.median(ratios)
    assert agreement["per_core_ratio_range"] == [ratios.min(), ratios.max()]


@pytest.mark.slow
@pytest.mark.peer
def test_quality_reference_agrees_with_mitsuba(modes):
    pytest.importorskip("mitsuba", reason="the Mitsuba cross-check needs `pip install spectrace[bench]`")
    quality = modes["quality"]
    # scalar_spectral needs no LLVM, so some variant always runs; a variant that cannot is a note, not a crash.
    assert quality["cross_check"] is not None, quality["notes"]
    assert quality["cross_check"]["agrees"], quality["cross_check"]
    assert {row["runtime"] for row in quality["renderers"] if row["renderer"] == "mitsuba"}


@pytest.mark.slow
def test_cold_mode_builds_without_caches():
    # The scene's own kernels: a build from source of those takes 3-9 s on PoCL, of the general ones 30-45 s.
    out = _bench("cold", "--size", "8", "--spp", "1", environment={"SPECTRACE_GENERAL_KERNELS": "0"})
    cold, warm = out["cold"]["cold"][0], out["cold"]["warm"][0]
    assert cold["kernel_build_cached"] is False  # empty caches: a real build from source
    assert warm["kernel_build_cached"] is True  # the cold run's binary or an earlier one answers now
    assert cold["spp"] == warm["spp"] == 1


@pytest.mark.slow
@pytest.mark.peer
def test_peer_mitsuba_mode_agrees():
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    out = _bench("peer", "--size", "32", "--spp", "16", "--max-depth", "4")
    peer = out["peer"]
    assert peer["width"] == 32 and peer["spp"] == 16 and peer["max_depth"] == 4
    assert peer["mitsuba"], peer["notes"]  # scalar_spectral needs no LLVM, so at least it runs
    assert len(peer["ratios"]) == len(peer["spectrace"]) * len(peer["mitsuba"])
    assert peer["rounds"] == 5 and {"before", "after", "cores", "busy"} <= peer["load"].keys()
    assert all(row["rounds"] == 5 for row in peer["mitsuba"])
    for pair in peer["agreement"]:
        assert pair["agrees"], pair


@pytest.mark.slow
@pytest.mark.peer
def test_peer_sampler_that_rounds_its_count_keeps_stdout_json_and_counts_what_it_rendered():
    """Mitsuba's multi-jittered sampler rounds 5 spp up to 6 and logs a warning: the warning must not reach stdout
    (one JSON object there), and Mitsuba's samples/s must count the 6 samples it rendered."""
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    out = _bench("peer", "--size", "8", "--spp", "5", "--max-depth", "2", "--peer-sampler", "multijitter")
    peer = out["peer"]
    assert [row["spp"] for row in peer["spectrace"]] == [5]
    assert peer["mitsuba"] and all(row["spp"] == 6 for row in peer["mitsuba"])
    for row in peer["mitsuba"]:
        assert row["samples_per_second"] == pytest.approx(8 * 8 * 6 / row["seconds"]["median"])


@pytest.mark.slow
@pytest.mark.peer
def test_peer_uses_mitsubas_llvm_variant_where_a_libllvm_works():
    """Where a libLLVM that Dr.Jit accepts is installed (found in the usual folders or DRJIT_LIBLLVM_PATH), the
    peer bench picks it up by itself and Mitsuba's fast variant runs and agrees."""
    _llvm_variant_or_skip()
    out = _bench("peer", "--size", "8", "--spp", "16", "--max-depth", "2")
    peer = out["peer"]
    assert "llvm_ad_spectral" in [row["runtime"] for row in peer["mitsuba"]], peer["notes"]
    for pair in peer["agreement"]:
        assert pair["agrees"], pair


@pytest.mark.parametrize(
    "argv, says",
    [
        (["--peer", "mitsuba"], "error: No such option: --peer"),  # the modes were flags once
        (["--quality"], "error: No such option: --quality"),
        (["--size", "8", "rays"], "error: --size: belongs to the plain render bench"),  # read by nothing: refused
        (["rays", "--size", "8"], "error: No such option: --size"),  # each mode takes only its own options
    ],
)
def test_options_outside_their_mode_are_one_line_errors(argv, says):
    result = run_spectrace("bench", *argv)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith(says) and result.stderr.count("\n") == 1, result.stderr


@pytest.mark.slow
def test_quality_mode_compares_the_integrators_asked_for():
    """One row per --integrator at equal time and at equal spp, against a reference of the integrator asked for."""
    quality = _bench(
        "quality", "--size", "8", "--seconds", "0.05", "--spp", "4", "--no-mitsuba",
        "--integrator", "path", "--integrator", "light", "--reference-integrator", "light",
    )["quality"]  # fmt: skip
    assert quality["reference"]["integrator"] == "light"
    for rows in (quality["renderers"], quality["equal_spp"]["renderers"]):
        assert [(row["renderer"], row["integrator"]) for row in rows] == [("spectrace", "path"), ("spectrace", "light")]
        assert all(row["rmse"] > 0 and row["spp"] >= 1 for row in rows)
    assert [row["spp"] for row in quality["equal_spp"]["renderers"]] == [4, 4]


@pytest.mark.parametrize("option", ["--integrator", "--reference-integrator"])
def test_quality_mode_refuses_an_unknown_integrator_in_one_line(option):
    result = run_spectrace("bench", "quality", option, "photon")
    assert result.returncode != 0
    assert "unknown integrator 'photon'" in result.stderr and result.stderr.count("\n") == 1, result.stderr


def test_the_quality_references_seed_stays_a_valid_seed_other_than_the_scenes():
    """The reference renders with the scene's seed offset: wrapped into 0..MAX_SEED for any scene seed, even the
    largest (the kernels take a 32-bit signed seed), and never equal to it."""
    from spectrace.benchmarks.quality import REFERENCE_SEED_OFFSET
    from spectrace.core.limits import MAX_SEED, offset_seed, seed_problem

    for seed in (0, 12345, MAX_SEED - REFERENCE_SEED_OFFSET, MAX_SEED - REFERENCE_SEED_OFFSET + 1, MAX_SEED):
        reference = offset_seed(seed, REFERENCE_SEED_OFFSET)
        assert seed_problem(reference) is None and reference != seed
    assert offset_seed(MAX_SEED, REFERENCE_SEED_OFFSET) == REFERENCE_SEED_OFFSET - 1  # 2^31 - 1 + k wraps to k - 1


@pytest.fixture(scope="module")
def build_mode() -> dict:
    return _bench("build", "--triangles", "100", "--rounds", "1")["build"]


@pytest.mark.slow
def test_build_mode_reports_the_build_of_the_asked_mesh(build_mode):
    assert build_mode["triangles"] == 320  # the smallest icosphere of at least 100 triangles: 20 * 4**2
    ours = build_mode["best"]["spectrace"]
    assert ours["seconds"] > 0 and ours["cpu_seconds"] > 0 and ours["peak_traced_bytes"] > 0
    assert ours["nodes"] >= 2 * 320 // 16 - 1 and ours["sah_cost"] > 0  # leaves hold at most 16 triangles
    assert ours["node_buffer_bytes"] > 0


@pytest.mark.peer
@pytest.mark.slow
def test_build_mode_times_mitsuba_loading_the_same_mesh(build_mode):
    pytest.importorskip("mitsuba", reason="the comparison needs `pip install spectrace[bench]`")
    assert not build_mode["notes"], build_mode["notes"]
    peer = build_mode["best"]["mitsuba"]
    assert peer["triangles"] == build_mode["triangles"]  # it read the same triangles from the PLY written for it
    assert peer["seconds"] > 0 and build_mode["ratio_wall"] > 0


@pytest.mark.slow
def test_instances_mode_stores_the_object_once():
    out = _bench("instances", "--count", "4", "--triangles", "200", "--size", "8", "--spp", "1")["instances"]
    instanced, copies = out["instanced"], out["expanded"]
    # 2 n² triangles with n = round(√100) = 10: 200 stored once, placed four times; the copies store all four.
    assert instanced["stored_triangles"] == 200 and copies["stored_triangles"] == instanced["placed_triangles"] == 800
    assert instanced["scene_device_bytes"] < copies["scene_device_bytes"]
    assert instanced["samples_per_second"] > 0 and copies["samples_per_second"] > 0
    assert instanced["mean_y"] == pytest.approx(copies["mean_y"], rel=0.05)


@pytest.mark.slow
@pytest.mark.peer
def test_peer_mode_renders_the_living_room_scene():
    """The benchmark's larger scene (295,000 triangles) exports to Mitsuba 3 whole, and the two images agree."""
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    out = _bench("peer", "--scene", "living_room", "--size", "16", "--spp", "16", "--max-depth", "4")
    peer = out["peer"]
    assert peer["scene"].endswith("living_room.toml") and peer["width"] == 16
    assert peer["mitsuba"], peer["notes"]
    for pair in peer["agreement"]:
        assert pair["agrees"], pair


@pytest.mark.slow
def test_denoise_mode_reports_what_it_rendered():
    """Tiny sizes, figures not judged: the emission pass has max(32, 2 spp) samples, the equal-time render at least
    the asked spp, and each ratio is the noisy RMSE over that column's."""
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    result = _bench("denoise", "--size", "16", "--spp", "2", "--reference-spp", "8", "--seeds", "1")["denoise"]
    assert result["spp"] == 2 and result["emission_pass_spp"] == 32 and result["equal_time_spp"] >= 2
    assert [row["metric"] for row in result["rows"]] == ["xyz", "xyz_away", "display"]
    for row in result["rows"]:
        for label in ("equal_time", "whole", "exchanged", "denoised"):
            assert row[f"ratio_{label}"] == pytest.approx(row["noisy"] / row[label])


@pytest.mark.slow
def test_session_mode_times_each_kind_of_edit_done_in_place():
    out = _bench(
        "session", "--scene", str(SCENES / "cornell_box.toml"), "--width", "12", "--repeats", "2", "--no-mitsuba"
    )["session"]
    box, instanced = out["rows"]
    assert box["scene"] == "cornell_box.toml" and (box["width"], box["height"]) == (12, 12)
    assert {kind: cost["how"] for kind, cost in box["kinds"].items()} == {
        "camera move": "in place",
        "one reflectance": "in place",
        "one light's power": "in place",
        "exposure": "image only",
    }
    assert instanced["kinds"]["instance transform"]["how"] == "in place"
    assert all(cost["rebuild_beyond_pass_seconds"] > 0 for row in out["rows"] for cost in row["kinds"].values())


@pytest.mark.slow
@pytest.mark.peer
def test_session_mode_times_mitsubas_traverse_and_update():
    _llvm_variant_or_skip()
    out = _bench("session", "--scene", str(SCENES / "cornell_box.toml"), "--width", "8", "--repeats", "1")["session"]
    mitsuba = out["rows"][-1]
    assert mitsuba["scene"].startswith("Mitsuba 3 cornell_box")
    assert set(mitsuba["kinds"]) == {"camera move", "one reflectance", "one light's power", "instance transform"}
