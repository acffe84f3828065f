"""Hashes of small renders of every bundled scene, under every integrator that takes it, on each runtime: the check
that a restructuring left the renderer's bits alone. Not part of the suite (pytest collects only test_*.py files).

    python -m tests.tooling.render_hashes --out before.json        # on the old tree
    python -m tests.tooling.render_hashes --compare before.json    # on the new one: exit 1 when a hash differs

Each case renders a scene at 24 x 16 pixels and 2 samples per pixel, once with the general kernels and once with
the kernels specialised to the scene (SPECTRACE_GENERAL_KERNELS), and hashes the image's XYZ and every AOV. A hash
is a property of one runtime's compiler, so the runtimes are kept apart (--runtime, as SPECTRACE_DEVICE names one).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
from pathlib import Path

import numpy as np

REPOSITORY = Path(__file__).resolve().parents[2]
RUNTIMES = ("intel-cpu", "pocl-system")


def _cases() -> list[tuple[str, Path]]:
    return [(path.stem, path) for path in sorted((REPOSITORY / "scenes").glob("*.toml"))]


def _digest(image) -> str:
    digest = hashlib.sha256(np.ascontiguousarray(image.xyz, dtype=np.float32).tobytes())
    for name in sorted(getattr(image, "aovs", {}) or {}):
        digest.update(name.encode())
        digest.update(np.ascontiguousarray(image.aovs[name], dtype=np.float32).tobytes())
    return digest.hexdigest()[:16]


def _hashes(runtime: str, general: bool) -> dict[str, str]:
    os.environ["SPECTRACE_GENERAL_KERNELS"] = "1" if general else "0"
    import spectrace
    from spectrace.integrators import INTEGRATORS

    found: dict[str, str] = {}
    for name, path in _cases():
        scene = spectrace.load_scene(path)
        # Every registered integrator besides the scene's own; a refusal is part of the record, so a change in what
        # is refused shows too.
        for integrator in dict.fromkeys((scene.integrator, *INTEGRATORS)):
            small = scene.with_overrides(width=24, height=16, spp=2, integrator=integrator)
            key = f"{runtime}/{'general' if general else 'specialised'}/{name}/{integrator}"
            try:
                found[key] = _digest(spectrace.render(small, device=runtime, progress=False))
            except spectrace.SpectraceError as error:
                # Without the scene's path, so trees in different folders compare.
                found[key] = "refused: " + str(error).splitlines()[0].replace(str(path), path.name)[:120]
            print(key, found[key], flush=True)
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write the hashes to this JSON file")
    parser.add_argument("--compare", type=Path, help="compare with the hashes in this JSON file")
    parser.add_argument("--runtime", action="append", help="a runtime to render on (default: both CPU runtimes)")
    parser.add_argument("--general-only", action="store_true", help="only the general kernels")
    arguments = parser.parse_args()
    found: dict[str, str] = {}
    for runtime in arguments.runtime or RUNTIMES:
        for general in (True,) if arguments.general_only else (True, False):
            found |= _hashes(runtime, general)
    if arguments.out:
        arguments.out.write_text(json.dumps(found, indent=1, sort_keys=True) + "\n")
    if arguments.compare:
        before = json.loads(arguments.compare.read_text())
        differ = sorted(key for key in found if key in before and before[key] != found[key])
        # Only the runtimes and kernels rendered this time are expected.
        rendered = {key.rsplit("/", 2)[0] for key in found}
        missing = sorted(key for key in set(before) - set(found) if key.rsplit("/", 2)[0] in rendered)
        for key in differ:
            print(f"DIFFERS {key}: {before[key]} -> {found[key]}")
        for key in missing:
            print(f"MISSING {key}")
        same = sum(1 for key in found if before.get(key) == found[key])
        print(f"{same} of {len(found)} the same, {len(differ)} differ, {len(missing)} missing")
        return 1 if differ or missing else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
