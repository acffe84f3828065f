"""A mutation check of the suite: small, realistic errors put into the renderer one at a time, each run against the
non-slow tests that should catch it. Not part of the suite (pytest collects only test_*.py files) and not run in CI:
run it by hand after changing the tests or the code the table names.

    python -m tests.tooling.mutants                  # every mutant, a table at the end
    python -m tests.tooling.mutants --only rr_under_compensated --only lambert_one_over_pi
    python -m tests.tooling.mutants --runtime pocl   # the runtime, as SPECTRACE_DEVICE picks it
    python -m tests.tooling.mutants --check          # only that every original text occurs exactly once

Each mutant is an exact text substitution in one file. Its original text must occur exactly once in that file, and
the tool stops before running anything when one does not, so the table keeps naming real code as the code changes.
The mutants are applied to a copy of the working tree in a temporary folder, never to the tree itself. The copy's
kernels differ from the real ones, so they are built into a temporary kernel cache (SPECTRACE_CACHE_DIR) seeded
from the user's cache by hard links: unmutated programs are found there, and no mutated binary reaches the shared
cache. The errors are of the size a real slip has (a factor 1.02 to 1.1, a wrong exponent, a swapped digit), not
gross breaks: a mutant a test lets through is a gap in the suite, not in the mutant.

Exit status: 0 when every mutant was caught, 1 when one survived or its tests could not run, 2 when the table no
longer matches the code.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Mutant:
    name: str
    path: str  # relative to the repository root
    original: str  # must occur exactly once in `path`
    mutated: str
    description: str
    tests: tuple[str, ...]  # pytest node ids or paths, run with -m "not slow"
    keyword: str = ""  # an optional -k expression narrowing `tests`


MUTANTS: tuple[Mutant, ...] = (
    # Whole-render light transport.
    Mutant(
        "spot_falloff_linear",
        "kernels/light_spot.cl",
        "return t * t * (3.0f - 2.0f * t);",
        "return t;",
        "spot light's smoothstep falloff replaced by one linear in cos θ",
        (
            "tests/lights/test_light_harness.py::test_spot_profile_across_its_whole_transition",
            "tests/render/test_validation.py::test_law_holds[spot]",
            "tests/render/test_sppm.py::test_spot_light_through_a_glass_slab",
        ),
    ),
    Mutant(
        "environment_pdf_x1.05",
        "kernels/light_environment_map.cl",
        "return light->pmf * density_uv / (2.0f * PI_F * PI_F * sin_theta);",
        "return 1.05f * light->pmf * density_uv / (2.0f * PI_F * PI_F * sin_theta);",
        "environment map's solid-angle pdf 5 % high",
        (
            "tests/lights/test_light_harness.py::test_pdf_at_a_hit_is_the_pdf_the_sampler_returned",
            "tests/lights/test_environment_map.py",
            "tests/render/test_bdpt.py::test_environment_seen_directly",
        ),
    ),
    Mutant(
        "emitter_hit_pdf_x1.1",
        "kernels/light_triangle.cl",
        "return area_light_pdf(light, distance(from, p), fabs(dot(n, wo)));",
        "return 1.1f * area_light_pdf(light, distance(from, p), fabs(dot(n, wo)));",
        "pdf of reaching an emitting triangle by light sampling, as the MIS weight of a BSDF hit sees it, 10 % high",
        (
            "tests/lights/test_light_harness.py::test_pdf_at_a_hit_is_the_pdf_the_sampler_returned",
            "tests/render/test_path_integrator.py",
            "tests/render/test_cornell_box.py",
            "tests/interop/test_veach_mis.py",
        ),
    ),
    Mutant(
        "area_light_pdf_x1.05",
        "kernels/light_area.cl",
        "return light->pmf * distance * distance / (light->area * abs_cos_light);",
        "return 1.05f * light->pmf * distance * distance / (light->area * abs_cos_light);",
        "emitting triangle's solid-angle pdf 5 % high (next-event estimation and MIS both)",
        (
            "tests/lights/test_light_harness.py::test_sampler_follows_the_hit_pdf_chi_square_and_the_pdf_integrates_to_one",
            "tests/render/test_path_integrator.py",
            "tests/render/test_cornell_box.py",
            "tests/interop/test_veach_mis.py",
        ),
    ),
    Mutant(
        "rr_under_compensated",
        "kernels/path_tracer.cl",
        "    s->throughput /= q;\n",
        "    s->throughput /= fmin(1.05f * q, 1.0f);\n",
        "Russian roulette's survivors divided by 1.05 q instead of q",
        (
            "tests/render/test_path_estimators.py",
            "tests/render/test_path_integrator.py",
            "tests/render/test_validation.py::test_law_holds[furnace]",
        ),
    ),
    Mutant(
        "thin_lens_aperture_x1.2",
        "host/spectrace/cameras/thinlens.py",
        "return camera.aperture_radius, camera.focus_distance",
        "return 1.2 * camera.aperture_radius, camera.focus_distance",
        "thin lens's aperture 1.2 times too large",
        ("tests/cameras/test_camera_optics.py", "tests/render/test_light_traced_cameras.py"),
    ),
    Mutant(
        "nee_x1.02",
        "kernels/direct_lighting.cl",
        "return f_cos * ls.arriving * transmittance * (weight / ls.pdf);",
        "return f_cos * ls.arriving * transmittance * (1.02f * weight / ls.pdf);",
        "next-event estimation's contribution at a surface 2 % high",
        (
            "tests/render/test_path_estimators.py",
            "tests/render/test_path_integrator.py",
            "tests/render/test_validation.py::test_law_holds[inverse-square]",
            "tests/render/test_cornell_box.py",
        ),
    ),
    Mutant(
        "mis_exponent",
        "kernels/sampling.cl",
        "float b = pdf_b * pdf_b;",
        "float b = pdf_b;",
        "power heuristic squares one pdf but not the other (weights no longer sum to one)",
        (
            "tests/render/test_path_estimators.py",
            "tests/render/test_path_integrator.py",
            "tests/render/test_cornell_box.py",
            "tests/interop/test_veach_mis.py",
        ),
    ),
    Mutant(
        "point_light_inverse_square",
        "kernels/light_point.cl",
        "s->arriving = light_spectrum(light, buffers->spectra, w) * (1.0f / d2);",
        "s->arriving = light_spectrum(light, buffers->spectra, w) * (1.0f / pow(d2, 1.02f));",
        "point lights fall off as 1/r^2.04 instead of 1/r²",
        (
            "tests/render/test_validation.py::test_law_holds[inverse-square]",
            "tests/render/test_light_tracer.py::test_point_light_over_a_diffuse_floor",
        ),
    ),
    Mutant(
        "camera_importance_cos",
        "kernels/camera_importance.cl",
        "c.importance = 1.0f / (area * cos_theta * cos_theta * cos_theta * dist * dist);",
        "c.importance = 1.0f / (area * cos_theta * cos_theta * dist * dist);",
        "light tracer's perspective camera importance with cos²θ where cos³θ belongs",
        (
            "tests/render/test_light_tracer.py::test_point_light_over_a_diffuse_floor",
            "tests/render/test_light_tracer.py::test_enclosure_radiance",
            "tests/render/test_light_traced_cameras.py",
        ),
    ),
    Mutant(
        "shadow_ray_not_offset",
        "kernels/direct_lighting.cl",
        "float3 from = offset_ray_origin(p, n_geometric, ls.wi);",
        "float3 from = p;",
        "next-event shadow ray leaves from the surface point itself, not offset along the normal",
        ("tests/render/test_path_integrator.py", "tests/render/test_validation.py::test_law_holds[inverse-square]"),
    ),
    Mutant(
        "bdpt_mis_sum_x1.05",
        "kernels/bdpt.cl",
        "return 1.0f / (1.0f + sum);",
        "return 1.0f / (1.0f + 1.05f * sum);",
        "BDPT's MIS weight with the other strategies' sum 5 % high (the weights of a path add up to less than one)",
        ("tests/render/test_bdpt.py",),
    ),
    Mutant(
        "sppm_radius_update",
        "kernels/sppm.cl",
        "float shrink = (r_new / r) * (r_new / r);",
        "float shrink = r_new / r;",
        "SPPM's flux rescaled by the radius ratio where the area ratio (its square) belongs",
        ("tests/render/test_sppm.py",),
    ),
    Mutant(
        "camera_fov_x1.05",
        "host/spectrace/cameras/shared.py",
        "tan_half = np.tan(np.radians(camera.fov_degrees) / 2.0)",
        "tan_half = np.tan(np.radians(1.05 * camera.fov_degrees) / 2.0)",
        "perspective cameras' field of view 5 % wide",
        (
            "tests/cameras/test_field_of_view.py",
            "tests/cameras/test_camera_optics.py",
            "tests/cameras/test_camera_peers.py",
            "tests/cameras/test_pbrt_cameras.py",
        ),
    ),
    # BSDFs, Fresnel, microfacets.
    Mutant(
        "lambert_one_over_pi",
        "kernels/bsdf_diffuse.cl",
        "return wi.z > 0.0f ? p->reflectance * (INV_PI * wi.z) : (float4)(0.0f);",
        "return wi.z > 0.0f ? p->reflectance * (wi.z / 3.0f) : (float4)(0.0f);",
        "Lambert's 1/π written as 1/3 in the diffuse BSDF's value (4.7 % high)",
        ("tests/materials/test_bsdfs.py",),
        keyword="diffuse",
    ),
    Mutant(
        "ggx_d_alpha",
        "kernels/microfacet.cl",
        "return a2 / (M_PI_F * t * t);",
        "return alpha / (M_PI_F * t * t);",
        "GGX D with α where α² belongs in its numerator",
        ("tests/materials/test_microfacet.py",),
    ),
    Mutant(
        "smith_g2_masking_dropped",
        "kernels/microfacet.cl",
        "return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));",
        "return 1.0f / (1.0f + ggx_lambda(wi, alpha));",
        "Smith G2 keeps shadowing but drops masking",
        ("tests/materials/test_microfacet.py", "tests/materials/test_bsdfs.py"),
        keyword="conductor or rough or microfacet or white",
    ),
    Mutant(
        "fresnel_conductor_rp",
        "kernels/fresnel.cl",
        "float4 r_p = r_s * (c2 * a2_plus_b2 - 2.0f * a * c * s2 + s2 * s2)",
        "float4 r_p = r_s * (c2 * a2_plus_b2 - 2.0f * a * s2 + s2 * s2)",
        "conductor Fresnel's R_p numerator loses a factor cos θ",
        ("tests/materials/test_bsdfs.py",),
        keyword="conductor",
    ),
    Mutant(
        "fresnel_dielectric_cos_t",
        "kernels/fresnel.cl",
        "float cos2_t = (cos_i * cos_i + (eta - 1.0f) * (eta + 1.0f)) / (eta * eta);",
        "float cos2_t = (cos_i * cos_i + (eta - 1.0f) * (eta + 1.0f)) / eta;",
        "dielectric Fresnel's cos²θt divided by η instead of η²",
        ("tests/materials/test_bsdf_dielectric.py",),
        keyword="fresnel or snell",
    ),
    # Wavelengths, colour, textures, emission spectra.
    Mutant(
        "wavelength_pdf_x1.02",
        "kernels/wavelengths.cl",
        "*pdf = (VISIBLE_PDF_SHARPNESS / VISIBLE_CDF_SPAN) * one_minus_t * one_plus_t;",
        "*pdf = 1.02f * (VISIBLE_PDF_SHARPNESS / VISIBLE_CDF_SPAN) * one_minus_t * one_plus_t;",
        "sampled wavelengths' pdf 2 % high",
        ("tests/spectral/test_wavelength_estimator.py",),
    ),
    Mutant(
        "cmf_lookup_off_by_one",
        "kernels/film.cl",
        "float4 a = cmf[index];\n    return mad((float4)(frac), cmf[index + 1] - a, a);",
        "float4 a = cmf[index + 1];\n    return mad((float4)(frac), cmf[min(index + 2, GRID_SAMPLES - 1)] - a, a);",
        "CMF table read one 1 nm node late (off by one in the index: every wavelength weighted as λ + 1 nm)",
        ("tests/spectral/test_wavelength_estimator.py",),
    ),
    Mutant(
        "srgb_matrix_entry",
        "host/spectrace/spectral/colorimetry.py",
        "[[3.240479, -1.537150, -0.498535]",
        "[[3.240479, -1.573150, -0.498535]",
        "XYZ to linear sRGB matrix with two digits of one entry swapped",
        ("tests/spectral/test_colorimetry.py", "tests/render/test_colour_output.py"),
    ),
    Mutant(
        "srgb_decode_exponent",
        "host/spectrace/spectral/colorimetry.py",
        "np.power(base, _SRGB_GAMMA))",
        "np.power(base, 2.2))",
        "texture decoding's sRGB transfer with the exponent 2.2 instead of 2.4",
        ("tests/spectral/test_rgb_texture.py", "tests/spectral/test_colorimetry.py"),
        keyword="decode or transfer",
    ),
    Mutant(
        "planck_constant",
        "host/spectrace/spectral/blackbody.py",
        "PLANCK_CONSTANT = 6.62607015e-34",
        "PLANCK_CONSTANT = 6.26607015e-34",
        "Planck's constant with two digits swapped (5.4 % low)",
        (
            "tests/render/test_colour_output.py",
            "tests/render/test_light_tracer.py::test_spectral_bands_of_a_lit_floor",
            "tests/render/test_film_response.py",
        ),
    ),
)


def find_mutant(name: str) -> Mutant:
    for mutant in MUTANTS:
        if mutant.name == name:
            return mutant
    raise SystemExit(f"--only {name}: no such mutant (known: {', '.join(m.name for m in MUTANTS)})")


def table_problems(root: Path, mutants: tuple[Mutant, ...]) -> list[str]:
    """Why a mutant no longer names real code: its file is gone, or its original text is not there exactly once."""
    problems = []
    for mutant in mutants:
        path = root / mutant.path
        if not path.is_file():
            problems.append(f"{mutant.name}: {mutant.path} does not exist")
            continue
        count = path.read_text(encoding="utf-8").count(mutant.original)
        if count != 1:
            problems.append(f"{mutant.name}: {mutant.path} holds its original text {count} times, not once")
        if mutant.original == mutant.mutated:
            problems.append(f"{mutant.name}: the mutated text is the original")
    return problems


def copy_tree(destination: Path) -> None:
    """The tracked and untracked-but-not-ignored files of the working tree: what a commit of it would hold."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=REPOSITORY,
        check=True,
        capture_output=True,
    ).stdout.decode()
    for relative in filter(None, listed.split("\0")):
        source = REPOSITORY / relative
        if not source.is_file():  # deleted in the working tree but still in the index
            continue
        target = destination / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)


def seed_cache(destination: Path) -> None:
    """A kernel cache the mutated runs may fill: the user's cache linked in (kernels by hard link, which the
    program cache replaces atomically rather than rewriting, so the originals are never changed), the rest copied
    (the RGB uplift table, device probes), so that unmutated programs and tables are not rebuilt."""
    from spectrace.cache_folder import cache_root

    destination.mkdir(parents=True)
    source = cache_root()
    if not source.is_dir():
        return
    for entry in source.iterdir():
        target = destination / entry.name
        try:
            if entry.name == "kernels" and entry.is_dir():
                try:
                    shutil.copytree(entry, target, copy_function=os.link)
                except OSError:  # another file system: copies, slower but the same
                    shutil.rmtree(target, ignore_errors=True)
                    shutil.copytree(entry, target)
            elif entry.is_dir():
                shutil.copytree(entry, target)
            else:
                shutil.copy2(entry, target)
        except OSError:
            pass  # a cache entry that cannot be read is rebuilt by the run that needs it


@dataclass
class Outcome:
    mutant: Mutant
    verdict: str  # caught, SURVIVED, timeout, error
    tests_run: int
    caught_by: str
    seconds: float
    detail: str = ""


_COUNTS = re.compile(r"(\d+) (passed|failed|error|errors)\b")


def run_tests(tree: Path, env: dict[str, str], mutant: Mutant, limit_s: float) -> tuple[int, str, float]:
    """pytest's exit status (or -1 on timeout), its output and the seconds taken."""
    command = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-n", "0", "-m", "not slow", "-x", "-q"]
    command += ["-rfE", "--no-header", *mutant.tests]
    if mutant.keyword:
        command += ["-k", mutant.keyword]
    start = time.monotonic()
    process = subprocess.Popen(
        command, cwd=tree, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    try:
        output, _ = process.communicate(timeout=limit_s)
        status = process.returncode
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)  # the whole session: pytest and any renderer it started
        output, _ = process.communicate()
        status = -1
    except BaseException:  # interrupted: no pytest left running on a mutated tree about to be deleted
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        raise
    return status, output.decode(errors="replace"), time.monotonic() - start


def judge(mutant: Mutant, status: int, output: str, seconds: float) -> Outcome:
    counts = {kind: int(n) for n, kind in _COUNTS.findall(output.splitlines()[-1] if output.strip() else "")}
    tests_run = counts.get("passed", 0) + counts.get("failed", 0)
    failed = [line.split(" ", 2)[1] for line in output.splitlines() if line.startswith(("FAILED ", "ERROR "))]
    if status == -1:
        return Outcome(mutant, "timeout", tests_run, "", seconds, output[-2000:])
    if status == 1 and failed:
        return Outcome(mutant, "caught", tests_run, failed[0], seconds)
    if status == 0:
        return Outcome(mutant, "SURVIVED", tests_run, "", seconds)
    # 2: interrupted or collection errors, 4: usage, 5: nothing collected: the tests did not judge the mutant.
    return Outcome(mutant, "error", tests_run, "", seconds, output[-2000:])


def print_table(outcomes: list[Outcome]) -> None:
    headers = ("mutant", "file", "tests run", "result", "caught by", "seconds")
    rows = [
        (o.mutant.name, o.mutant.path, str(o.tests_run), o.verdict, o.caught_by or "-", f"{o.seconds:.0f}")
        for o in outcomes
    ]
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
    print(" | ".join(h.ljust(w) for h, w in zip(headers, widths)))
    print("-+-".join("-" * w for w in widths))
    for row in rows:
        print(" | ".join(c.ljust(w) for c, w in zip(row, widths)))
    caught = sum(o.verdict == "caught" for o in outcomes)
    print(f"\n{caught} of {len(outcomes)} mutants caught")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.tooling.mutants", description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", action="append", metavar="NAME", help="run this mutant (repeatable)")
    parser.add_argument("--runtime", help="the OpenCL runtime, as SPECTRACE_DEVICE takes it (e.g. pocl)")
    parser.add_argument("--limit", type=float, default=300.0, metavar="S", help="seconds per mutant (300)")
    parser.add_argument("--list", action="store_true", help="list the mutants and their tests, run nothing")
    parser.add_argument("--check", action="store_true", help="only check that the table matches the code")
    parser.add_argument("--baseline", action="store_true", help="first run every mutant's tests unmutated")
    parser.add_argument("--verbose", action="store_true", help="print pytest's output of each run")
    args = parser.parse_args(argv)

    mutants = tuple(find_mutant(name) for name in args.only) if args.only else MUTANTS
    if args.list:
        for m in mutants:
            narrowed = f" -k {m.keyword!r}" if m.keyword else ""
            print(f"{m.name}: {m.path}: {m.description}\n    {' '.join(m.tests)}{narrowed}")
        return 0
    problems = table_problems(REPOSITORY, mutants)
    if problems:
        print("the mutant table no longer matches the code:\n  " + "\n  ".join(problems), file=sys.stderr)
        return 2
    if args.check:
        print(f"{len(mutants)} mutants, each original text found exactly once")
        return 0

    # A plain kill ends the run as Ctrl-C does, so the temporary tree and cache are removed.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    with tempfile.TemporaryDirectory(prefix="spectrace-mutants-") as scratch:
        tree, cache = Path(scratch) / "tree", Path(scratch) / "cache"
        copy_tree(tree)
        seed_cache(cache)
        env = dict(os.environ, PYTHONPATH=str(tree / "host"), SPECTRACE_CACHE_DIR=str(cache))
        env.pop("PYTEST_ADDOPTS", None)
        if args.runtime:
            env["SPECTRACE_DEVICE"] = args.runtime

        if args.baseline:
            for mutant in mutants:
                status, output, seconds = run_tests(tree, env, mutant, args.limit)
                if status != 0:
                    print(f"baseline: {mutant.name}'s tests do not pass unmutated:\n{output[-3000:]}", file=sys.stderr)
                    return 1
                print(f"baseline: {mutant.name}'s tests pass unmutated ({seconds:.0f} s)", flush=True)

        outcomes = []
        for mutant in mutants:
            path = tree / mutant.path
            original = path.read_bytes()
            try:
                path.write_text(original.decode("utf-8").replace(mutant.original, mutant.mutated), encoding="utf-8")
                status, output, seconds = run_tests(tree, env, mutant, args.limit)
            finally:
                path.write_bytes(original)
            outcome = judge(mutant, status, output, seconds)
            outcomes.append(outcome)
            print(f"{mutant.name}: {outcome.verdict} {outcome.caught_by} ({seconds:.0f} s)", flush=True)
            if args.verbose or outcome.verdict in ("error", "timeout"):
                print(output[-3000:] if args.verbose else outcome.detail, flush=True)
    print()
    print_table(outcomes)
    return 0 if all(o.verdict == "caught" for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
