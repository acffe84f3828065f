"""`envmap`: an environment from a latitude-longitude image, importance-sampled by luminance
(kernels/environment.cl)."""

from dataclasses import dataclass

import numpy as np

from spectrace.engine.device_types import LIGHT_ENVIRONMENT_MAP
from spectrace.io.images import read_environment_map
from spectrace.lights.base import Light, LightRows, light_row
from spectrace.materials.parameters import REQUIRED, Parameter, Range
from spectrace.spectral.colorimetry import LINEAR_SRGB_TO_XYZ
from spectrace.spectral.uplift import uplift_illuminant

NAME = "envmap"
MITSUBA_PLUGINS = ()
MITSUBA_NONE = "not mapped yet: the importer refuses Mitsuba 3's envmap and the export this light"
IS_ENVIRONMENT = True
PARAMETERS = (
    Parameter("file", "string", "", REQUIRED, doc="latitude-longitude OpenEXR image, linear sRGB"),
    Parameter("scale", "float", "", 1.0, Range(0.0), doc="multiplies every texel's radiance"),
)


@dataclass(frozen=True, eq=False)
class EnvironmentMap(Light):
    """Light from a latitude-longitude image at infinity: `rgb` (height, width, 3) linear sRGB, times `scale`;
    each texel's radiance is the D65-based emission uplift of its colour (RGB (1,1,1) = D65 at Y = 1), in
    W/(m² sr nm). +y is up; the image centre looks along −z (see kernels/environment.cl)."""

    rgb: np.ndarray
    scale: float = 1.0


MODEL = EnvironmentMap


def from_spec(spec, resolver, key: str) -> EnvironmentMap:
    return EnvironmentMap(read_environment_map(resolver.folder / spec.file, resolver.where(f"{key}.file")), spec.scale)


def environment_map_tables(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Texels, sampling CDFs and mean luminance of a latitude-longitude map: the sampling density is ∝ luminance ×
    sin θ of the row's centre, so directions are drawn where light arrives and the poles' small texels are not
    oversampled."""
    height, width = rgb.shape[:2]
    texels = np.zeros((height * width, 4), np.float32)
    texels[:, :3] = np.maximum(rgb.reshape(-1, 3), 0.0)
    luminance = (texels[:, :3] @ LINEAR_SRGB_TO_XYZ[1]).reshape(height, width).astype(np.float64)
    sin_theta = np.sin(np.pi * (np.arange(height) + 0.5) / height)[:, None]
    weights = luminance * sin_theta
    if weights.sum() <= 0:
        weights = np.broadcast_to(sin_theta, (height, width)).copy()
    row_mass = weights.sum(axis=1)
    row_cdf = np.zeros((height, width + 1))
    row_cdf[:, 1:] = np.cumsum(weights, axis=1)
    row_cdf = np.divide(
        row_cdf, row_cdf[:, -1:], out=np.tile(np.linspace(0, 1, width + 1), (height, 1)), where=row_cdf[:, -1:] > 0
    )
    marginal = np.concatenate([[0.0], np.cumsum(row_mass)]) / row_mass.sum()
    marginal[-1] = 1.0
    row_cdf[:, -1] = 1.0
    return texels, np.concatenate([marginal, row_cdf.ravel()]).astype(np.float32), float(luminance.mean())


def write_rows(light: EnvironmentMap, out: LightRows) -> None:
    map_texels, out.map_cdf, mean_luminance = environment_map_tables(light.rgb)
    basis = [out.table.add(uplift_illuminant(primary)) for primary in np.eye(3)]
    height, width = light.rgb.shape[:2]
    out.add(
        light_row(
            LIGHT_ENVIRONMENT_MAP,
            basis[0],
            map_fields=(basis[1], basis[2], width, height),
            texel_offset=out.add_texels(map_texels[:, :3].reshape(height, width, 3)),
            scale=light.scale,
        ),
        4.0 * np.pi**2 * out.scene_radius**2 * light.scale * mean_luminance,
        environment=True,
    )
