"""Area lights: a shape's `emitter`, emitting from each of its triangles, optionally showing an image
(kernels/lights.cl)."""

from dataclasses import dataclass
from typing import Any

import numpy as np

from spectrace.engine.device_types import LIGHT_TRIANGLE
from spectrace.lights.base import LightRows, light_row
from spectrace.materials.parameters import REQUIRED, Parameter
from spectrace.spectral.spectrum import Spectrum

NAME = "area"
MITSUBA_PLUGINS = ("area",)  # on a shape only
PARAMETERS = (
    Parameter("radiance", "spectrum", "W/(m² sr nm)", REQUIRED, doc="times scale"),
    Parameter(
        "two_sided",
        "bool",
        "",
        False,
        doc="emit on both faces; by default only on the side the triangles' winding faces",
    ),
)


@dataclass(frozen=True, eq=False)
class EmitterImage:
    """An image shown by an area light (a picture on a screen): each texel emits r·R(λ) + g·G(λ) + b·B(λ) of the
    three primaries for its linear drive (r, g, b); texture coordinates place it (u right, v down)."""

    drive: np.ndarray  # (height, width, 3) linear drive per texel, row 0 at the top
    primaries: tuple[Spectrum, Spectrum, Spectrum]  # W/(m² sr nm) at full drive, scale applied


@dataclass(frozen=True)
class AreaEmitter:
    radiance: Spectrum  # W/(m² sr nm), scale applied; with an image, its mean emission
    two_sided: bool = False
    image: EmitterImage | None = None


MODEL = AreaEmitter


def write_rows(
    emitters: list[AreaEmitter], triangle_emitter: np.ndarray, areas: np.ndarray, out: LightRows
) -> np.ndarray:
    """One row per emitting triangle of non-zero area (triangle_emitter: each triangle's index into `emitters`,
    or -1); returns those triangles' indices, in row order."""
    emitting = np.flatnonzero((triangle_emitter >= 0) & (areas > 0))
    emitter_rows: list[dict[str, Any]] = []
    for e in emitters:
        if e.image is None:
            emitter_rows.append({"spectrum_offset": out.table.add(e.radiance)})
        else:
            basis = [out.table.add(p) for p in e.image.primaries]
            height, width = e.image.drive.shape[:2]
            emitter_rows.append(
                {
                    "spectrum_offset": basis[0],
                    "texel_offset": out.add_texels(e.image.drive),
                    "map_fields": (basis[1], basis[2], width, height),
                }
            )
    for t in emitting:
        e = emitters[triangle_emitter[t]]
        fields = emitter_rows[triangle_emitter[t]]
        out.add(
            light_row(
                LIGHT_TRIANGLE,
                fields["spectrum_offset"],
                triangle=int(t),
                area=areas[t],
                two_sided=e.two_sided,
                map_fields=fields.get("map_fields", (0, 0, 0, 0)),
                texel_offset=fields.get("texel_offset", 0),
            ),
            np.pi * areas[t] * e.radiance.mean() * (2.0 if e.two_sided else 1.0),
        )
    return emitting


def from_mitsuba(importer, emitter, properties) -> dict | None:
    """A shape's emitter table (one-sided toward the face normal, as Mitsuba's area light)."""
    radiance = importer.child(properties, "radiance", emitter)
    spectrum = importer.spectrum(radiance, "radiance")
    return None if spectrum is None else {"radiance": spectrum}


def to_mitsuba(emitter: AreaEmitter, exporter, owner: str) -> dict:
    """Mitsuba's area light has one spectrum and emits on the front face only; `owner` names the shape."""
    if emitter.image is not None:
        raise exporter.refuse(f"{owner} shows an image; Mitsuba's area light has one spectrum")
    if emitter.two_sided:
        raise exporter.refuse(f"{owner} emits on both faces; Mitsuba's area light is one-sided")
    return {"type": "area", "radiance": exporter.spectrum(emitter.radiance)}
