"""Stand-ins for a pbrt-v4 scene's missing asset files, for surveys of public scene collections whose meshes,
images and data files are fetched apart from (or without) their scene text: `missing_assets="placeholder"`
(`spectrace import-pbrt --missing-assets placeholder`) imports such a file on what it states (its plugins and
parameters) rather than refusing it at the first missing file.

Each stand-in is reported as a warning naming the file:line and the missing file (so `strict` still refuses the
scene), and counted in `Context.placeholders`:

- an Include or Import of a missing file: skipped (what it would have stated is not judged);
- a `plymesh`: one small triangle (a unit right triangle in the shape's object space, with uvs);
- an `imagemap` texture: the constant 0.5 (spectrum or float);
- an image infinite light: a constant grey map (each texel 0.5 before the light's `scale`);
- a `measured` material's `.bsdf`: a diffuse material of reflectance 0.5;
- a `nanovdb` medium: the homogeneous medium its coefficients give;
- a goniometric light's image: none (an isotropic light, as without "filename");
- a spectrum file (`.spd`): the constant 1;
- a realistic camera's lens file: the lens spectrace bundles (spectrace.cameras.realistic.PLACEHOLDER_LENS).

A projection light's image has no stand-in: a missing one is refused as by default. Without the option, a missing
file is one error naming it (the default, unchanged)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from spectrace.interop.pbrt.meshes import MeshData

MISSING_ASSETS = ("refuse", "placeholder")
GREY = 0.5


def check_policy(policy: str) -> str:
    """The policy, or a one-line error naming what is accepted (the caller says where)."""
    if policy not in MISSING_ASSETS:
        from spectrace.errors import SpectraceError

        raise SpectraceError(f"missing assets '{policy}': give one of {', '.join(MISSING_ASSETS)}")
    return policy


def triangle() -> MeshData:
    """The stand-in for a missing mesh: a unit right triangle in the z = 0 plane, facing +z."""
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    uvs = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return MeshData(vertices, np.array([[0, 1, 2]]), None, uvs)


def grey_square(size: int = 8) -> np.ndarray:
    """The stand-in for a missing environment map: pbrt's equal-area square, grey."""
    return np.full((size, size, 3), GREY, np.float32)


def is_missing(name: str, folder: Path) -> bool:
    """Whether a file named in a scene (relative to `folder`, the naming file's) is absent."""
    path = Path(name)
    return not (path if path.is_absolute() else folder / path).is_file()
