"""Measurement sensors: irradiance, radiance and flux meters, spectral, in SI units.

A meter measures chosen wavelengths (default every 5 nm over 360–830 nm) instead of sampling them, so every
wavelength gets an estimate with its own standard error; totals are trapezoid integrals over those wavelengths,
and photometric values use 683 lm/W × ȳ (CIE 1931 2°), so Y of the XYZ is lx, cd/m² or lm.
"""

from dataclasses import dataclass, field

import numpy as np
import pyopencl as cl

from spectrace.core.contract import METER_FLUX, METER_IRRADIANCE, METER_PARAMS_DTYPE, METER_RADIANCE
from spectrace.device import Device, open_device
from spectrace.engine.launch import meter_work_group
from spectrace.engine.renderer import upload_scene
from spectrace.engine.scene_buffers import build_scene_buffers, render_params
from spectrace.engine.scene_features import is_polarized
from spectrace.errors import SpectraceError
from spectrace.film.response import FilmResponse
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.plugins import generated_sources
from spectrace.scene.model import Scene
from spectrace.spectral.colorimetry import CIE_1931_CMFS
from spectrace.spectral.grid import GRID_NM

LUMINOUS_EFFICACY_LM_PER_W = 683.0
DEFAULT_WAVELENGTHS_NM = np.arange(360.0, 831.0, 5.0)


@dataclass(frozen=True)
class IrradianceMeter:
    """E at `point` on a one-sided surface facing `normal` (light arriving from the normal's side)."""

    point: tuple[float, float, float]
    normal: tuple[float, float, float]


@dataclass(frozen=True)
class RadianceMeter:
    """L arriving at `origin` from the direction `-direction`, i.e. the radiance seen looking along `direction`."""

    origin: tuple[float, float, float]
    direction: tuple[float, float, float]


@dataclass(frozen=True)
class FluxMeter:
    """Φ leaving, from inside, the sphere of `radius` about `centre` (an integrating sphere around a light)."""

    centre: tuple[float, float, float]
    radius: float


Meter = IrradianceMeter | RadianceMeter | FluxMeter

_QUANTITIES = {
    IrradianceMeter: ("irradiance", "W/(m² nm)", "W/m²", "lx"),
    RadianceMeter: ("radiance", "W/(m² sr nm)", "W/(m² sr)", "cd/m²"),
    FluxMeter: ("flux", "W/nm", "W", "lm"),
}


@dataclass
class MeterReading:
    quantity: str
    spectral_unit: str
    total_unit: str
    photometric_unit: str
    wavelengths_nm: np.ndarray
    spectral: np.ndarray  # per wavelength, in spectral_unit
    spectral_standard_error: np.ndarray
    total: float  # ∫ spectral dλ over the wavelengths measured, in total_unit
    total_standard_error: float
    xyz: np.ndarray  # 683 ∫ spectral (x̄, ȳ, z̄) dλ: Y is the photometric value
    xyz_standard_error: np.ndarray
    extra: dict = field(default_factory=dict)

    @property
    def photometric(self) -> float:
        return float(self.xyz[1])


def _trapezoid_weights(x: np.ndarray) -> np.ndarray:
    weights = np.zeros_like(x)
    if len(x) > 1:
        dx = np.diff(x)
        weights[:-1] += dx / 2
        weights[1:] += dx / 2
    return weights


def _meter_params(meter: Meter, samples_per_item: int, seed: int) -> np.ndarray:
    params = np.zeros(1, METER_PARAMS_DTYPE)
    if isinstance(meter, IrradianceMeter):
        params["type"], point, direction, w = METER_IRRADIANCE, meter.point, meter.normal, 0.0
    elif isinstance(meter, RadianceMeter):
        params["type"], point, direction, w = METER_RADIANCE, meter.origin, meter.direction, 0.0
    else:
        params["type"], point, direction, w = METER_FLUX, meter.centre, (0.0, 0.0, 1.0), meter.radius
    if not np.linalg.norm(direction) > 0:
        raise ValueError("a meter's direction must not be zero")
    params["point"][0] = (*point, w)
    params["direction"][0] = (*np.asarray(direction, float) / np.linalg.norm(direction), 0.0)
    params["samples_per_item"] = samples_per_item
    params["seed"] = seed
    return params


def measure(
    scene: Scene,
    meter: Meter,
    wavelengths_nm=DEFAULT_WAVELENGTHS_NM,
    streams: int = 64,
    samples_per_item: int = 32,
    seed: int = 0,
    device: Device | str | None = None,
) -> MeterReading:
    """Measure with `streams` independent estimates of `samples_per_item` samples per wavelength (the global
    model, `scene.max_depth` segments from the meter). The standard errors come from the spread of the streams."""
    device = device if isinstance(device, Device) else open_device(device)
    wavelengths = np.asarray(wavelengths_nm, np.float32)
    if scene.film_response.has_own_grid:  # meters read spectra on the common grid, whatever the film's range
        scene = scene.with_overrides(film_response=FilmResponse())
    buffers = build_scene_buffers(scene)
    if is_polarized(scene, buffers):
        # A meter has no basis to measure Stokes vectors in: its paths would treat polarisers as grey filters.
        raise SpectraceError(
            "meters measure unpolarised transport: this scene is polarised (integrator.polarized, a polarizer or "
            "retarder, a Stokes AOV or camera.polarizer_angle); render it with the path integrator instead",
            where=str(scene.source) if scene.source else None,
        )
    program = device.build_program("meters.cl", defines=traversal_defines() or None, generated=generated_sources())
    ctx, queue = device.context, device.queue
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    params, meter_params, wavelength_buffer = (
        cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(a))
        for a in (render_params(scene, buffers, 0, 0), _meter_params(meter, samples_per_item, seed), wavelengths)
    )
    inputs = [params, *upload_scene(ctx, buffers), meter_params, wavelength_buffer]
    items = streams * len(wavelengths)
    means = np.empty(items, np.float32)
    out = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, means.nbytes)
    # Groups of one on Intel's CPU runtime (its 16-wide build of this kernel is wrong); on PoCL, groups that divide
    # the count (spectrace.engine.launch).
    local = meter_work_group(device, items)
    cl.Kernel(program, "measure")(
        queue, (items,), (local,) if local else None, *inputs, np.int32(len(wavelengths)), out
    )
    cl.enqueue_copy(queue, means, out)
    queue.finish()

    per_stream = means.astype(np.float64).reshape(streams, len(wavelengths))
    spectral = per_stream.mean(axis=0)
    spectral_se = per_stream.std(axis=0, ddof=1) / np.sqrt(streams) if streams > 1 else np.zeros_like(spectral)
    weights = _trapezoid_weights(wavelengths.astype(np.float64))
    cmfs = np.stack([np.interp(wavelengths, GRID_NM, CIE_1931_CMFS[:, i]) for i in range(3)], axis=1)
    xyz_weights = LUMINOUS_EFFICACY_LM_PER_W * weights[:, None] * cmfs
    quantity, spectral_unit, total_unit, photometric_unit = _QUANTITIES[type(meter)]
    return MeterReading(
        quantity=quantity,
        spectral_unit=spectral_unit,
        total_unit=total_unit,
        photometric_unit=photometric_unit,
        wavelengths_nm=wavelengths.astype(np.float64),
        spectral=spectral,
        spectral_standard_error=spectral_se,
        total=float(weights @ spectral),
        total_standard_error=float(np.sqrt(np.sum((weights * spectral_se) ** 2))),
        xyz=spectral @ xyz_weights,
        xyz_standard_error=np.sqrt((spectral_se**2) @ xyz_weights**2),
        extra={"device": device.report.key, "streams": streams, "samples_per_item": samples_per_item},
    )
