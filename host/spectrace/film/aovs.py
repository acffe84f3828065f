"""AOVs (arbitrary output variables): the images a render keeps beside its colour, recorded by the same camera
paths (kernels/aov.cl defines them), and how they reach files. Pure numpy: the scene loader and the API name
them without the device layer.

albedo is kept as XYZ, each channel the reflectance's x̄-, ȳ- or z̄-weighted mean (a perfect white reflector has
(1, 1, 1)); files and the denoiser get it in the output colour space, adapted from the equal-energy white to the
space's white, so that white stays (1, 1, 1). variance is the standard error of the pixel's mean Y.

emission is the film XYZ of the emission the camera rays meet directly (area lights, the environment), as its
expected value over the wavelengths: free of the colour noise four sampled wavelengths give it. Asking for it also
keeps `emission_sampled`, the same emission as the image's own estimate holds it, which the denoiser exchanges for
the expected value (spectrace.denoising).
"""

from collections.abc import Sequence

import numpy as np

from spectrace.errors import SpectraceError

AOV_NAMES = ("albedo", "normal", "depth", "position", "variance", "emission")
# Images an AOV brings along besides its own (kept with it, written beside it).
AOV_COMPANIONS = {"emission": ("emission_sampled",)}
AOV_FLOATS_PER_PIXEL = 20  # kernels/aov.cl: AOV_FLOAT4S_PER_PIXEL float4s
# EXR channels of each AOV but the albedo, whose channel names follow the colour space (aov_channels).
AOV_CHANNELS = {
    "normal": ("normal.X", "normal.Y", "normal.Z"),
    "depth": ("depth.Z",),
    "position": ("position.X", "position.Y", "position.Z"),
    "variance": ("Y.stderr",),
    "emission": ("emission.X", "emission.Y", "emission.Z"),
    "emission_sampled": ("emission_sampled.X", "emission_sampled.Y", "emission_sampled.Z"),
}


def parse_aovs(names: str | Sequence[str] | None, where: str | None = None) -> tuple[str, ...]:
    """The AOVs named (a comma-separated string or a sequence), without repeats, in AOV_NAMES' order; an unknown
    name raises SpectraceError at `where`."""
    if names is None:
        return ()
    if not isinstance(names, str | Sequence):
        raise SpectraceError(
            f"expected AOV names as a comma-separated string or a sequence, got {names!r}", where=where
        )
    items = [n.strip() for n in names.split(",") if n.strip()] if isinstance(names, str) else list(names)
    for name in items:
        if not isinstance(name, str) or name not in AOV_NAMES:
            raise SpectraceError(f"unknown AOV {name!r} (choose from {', '.join(AOV_NAMES)})", where=where)
    return tuple(n for n in AOV_NAMES if n in items)


def aov_defines(aovs: Sequence[str]) -> dict[str, int]:
    """Kernel defines that make the render kernels record the AOVs (kernels/aov.cl records all of them at once)."""
    return {"FILM_AOVS": 1} if aovs else {}


def albedo_channel_scale(cmf: np.ndarray) -> np.ndarray:
    """Factors turning the albedo's film-XYZ sums (the CMF table divided by ∫ȳ) into the reflectance's
    x̄-, ȳ- and z̄-weighted means, so that a perfect white reflector has albedo XYZ (1, 1, 1): ∫ȳ/∫x̄, 1, ∫ȳ/∫z̄,
    the integrals as the kernels' linear interpolation of the table takes them (the trapezoid rule)."""
    table = np.asarray(cmf, np.float64)[:, :3]
    integrals = table.sum(axis=0) - 0.5 * (table[0] + table[-1])
    return (integrals[1] / integrals).astype(np.float32)


def aov_images(sums: np.ndarray, film: np.ndarray, samples: int, albedo_scale: np.ndarray, shape: tuple[int, int]):
    """The AOV images (by name, AOV_NAMES and their companions) of `sums` ((pixels, AOV_FLOATS_PER_PIXEL) sums),
    `film` ((pixels, 4) film sums) after `samples` samples per pixel. variance: the standard error of the pixel's
    mean Y (inf below 2 samples)."""
    n = max(samples, 1)
    height, width = shape
    per = sums.astype(np.float64).reshape(-1, AOV_FLOATS_PER_PIXEL // 4, 4) / n

    def image(values: np.ndarray) -> np.ndarray:
        return values.reshape(height, width, *values.shape[1:]).astype(np.float32)

    mean_y = film[:, 1].astype(np.float64) / n
    if samples >= 2:
        variance = np.maximum(per[:, 0, 3] - mean_y**2, 0.0) * n / (n - 1)
        stderr = np.sqrt(variance / n)
    else:
        stderr = np.full(mean_y.shape, np.inf)
    return {
        "albedo": image(per[:, 0, :3] * albedo_scale),
        "normal": image(per[:, 1, :3]),
        "depth": image(per[:, 2, 3]),
        "position": image(per[:, 2, :3]),
        "variance": image(stderr),
        "emission": image(per[:, 4, :3]),
        "emission_sampled": image(per[:, 3, :3]),
    }


def with_companions(aovs: Sequence[str]) -> tuple[str, ...]:
    """The images an image keeps for the AOVs asked: each, then its companions."""
    return tuple(name for aov in aovs for name in (aov, *AOV_COMPANIONS.get(aov, ())))


def albedo_in(albedo_xyz: np.ndarray, space) -> np.ndarray:
    """The albedo in linear `space` (a ColourSpace): Bradford-adapted from the equal-energy white (XYZ (1, 1, 1),
    the albedo of a perfect white reflector) to the space's white, so white is (1, 1, 1); XYZ unchanged."""
    from spectrace.film.colour_output import ColourSpace, WhiteBalance, xyz_to_output

    space = ColourSpace(space)
    if space is ColourSpace.XYZ:
        return np.asarray(albedo_xyz, np.float32)
    return xyz_to_output(albedo_xyz, space, WhiteBalance("E", np.ones(3)))


def aov_channels(aovs: dict[str, np.ndarray], space) -> dict[str, np.ndarray]:
    """EXR channels (name: (height, width) float32) of an image's AOVs, albedo in the output colour space."""
    from spectrace.film.colour_output import ColourSpace

    channels = {}
    for name, values in aovs.items():
        if name == "albedo":
            rgb = albedo_in(values, space)
            letters = "XYZ" if ColourSpace(space) is ColourSpace.XYZ else "RGB"
            names = tuple(f"albedo.{c}" for c in letters)
            values = rgb
        else:
            names = AOV_CHANNELS[name]
        planes = [values] if values.ndim == 2 else [values[..., i] for i in range(values.shape[-1])]
        for channel, plane in zip(names, planes, strict=True):
            channels[channel] = np.ascontiguousarray(plane, np.float32)
    return channels
