"""AOVs (arbitrary output variables): the images a render keeps beside its colour, recorded by the same camera
paths (kernels/aov.cl defines them), and how they reach files. Pure numpy: the scene loader and the API name
them without the device layer.

albedo is kept as XYZ, each channel the reflectance's x̄-, ȳ- or z̄-weighted mean (a perfect white reflector has
(1, 1, 1)); files and the denoiser get it in the output colour space, adapted from the equal-energy white to the
space's white, so that white stays (1, 1, 1). variance is the standard error of the pixel's mean Y.

stokes, dolp and aolp belong to a polarised render (docs/polarization.md): `stokes` the Stokes images S0..S3 of
the light reaching the camera (before its polariser, when it has one), each as film XYZ, in the camera's basis (S1 >
0: polarised along the image's right; S2 > 0: along the diagonal between its right and up); `dolp` the degree of
linear polarisation √(S1² + S2²) / S0 and `aolp` its angle ½ atan2(S2, S1) (radians from the image's right toward
its up), both of the Y channels.

emission is the film XYZ of the emission the camera rays meet directly (area lights, the environment), as its
expected value over the wavelengths: free of the colour noise four sampled wavelengths give it. Asking for it also
keeps `emission_sampled`, the same emission as the image's own estimate holds it, which the denoiser exchanges for
the expected value (spectrace.denoising).
"""

from collections.abc import Sequence

import numpy as np

from spectrace.errors import SpectraceError

AOV_NAMES = ("albedo", "normal", "depth", "position", "variance", "emission", "stokes", "dolp", "aolp")
# The AOVs of a polarised render: kernels/aov.cl keeps four more float4 sums for them (FILM_STOKES).
POLARIZATION_AOVS = ("stokes", "dolp", "aolp")
# Images an AOV brings along besides its own (kept with it, written beside it).
AOV_COMPANIONS = {"emission": ("emission_sampled",)}
AOV_FLOATS_PER_PIXEL = 20  # kernels/aov.cl: AOV_FLOAT4S_PER_PIXEL float4s
STOKES_AOV_FLOATS_PER_PIXEL = 36  # the same with FILM_STOKES
# EXR channels of each AOV but the albedo, whose channel names follow the colour space (aov_channels).
AOV_CHANNELS = {
    "normal": ("normal.X", "normal.Y", "normal.Z"),
    "depth": ("depth.Z",),
    "position": ("position.X", "position.Y", "position.Z"),
    "variance": ("Y.stderr",),
    "emission": ("emission.X", "emission.Y", "emission.Z"),
    "emission_sampled": ("emission_sampled.X", "emission_sampled.Y", "emission_sampled.Z"),
    "stokes": tuple(f"S{i}.{c}" for i in range(4) for c in "XYZ"),
    "dolp": ("dolp",),
    "aolp": ("aolp",),
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


def aov_floats_per_pixel(aovs: Sequence[str]) -> int:
    """Floats per pixel of the AOV film that records `aovs` (none asked: 0)."""
    if not aovs:
        return 0
    return STOKES_AOV_FLOATS_PER_PIXEL if any(a in POLARIZATION_AOVS for a in aovs) else AOV_FLOATS_PER_PIXEL


def aov_defines(aovs: Sequence[str]) -> dict[str, int]:
    """Kernel defines that make the render kernels record the AOVs (kernels/aov.cl records all of them at once;
    the Stokes sums only when a polarisation AOV is asked)."""
    if not aovs:
        return {}
    return {"FILM_AOVS": 1} | ({"FILM_STOKES": 1} if any(a in POLARIZATION_AOVS for a in aovs) else {})


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
    per = sums.astype(np.float64).reshape(height * width, -1, 4) / n

    def image(values: np.ndarray) -> np.ndarray:
        return values.reshape(height, width, *values.shape[1:]).astype(np.float32)

    mean_y = film[:, 1].astype(np.float64) / n
    if samples >= 2:
        variance = np.maximum(per[:, 0, 3] - mean_y**2, 0.0) * n / (n - 1)
        stderr = np.sqrt(variance / n)
    else:
        stderr = np.full(mean_y.shape, np.inf)
    images = {
        "albedo": image(per[:, 0, :3] * albedo_scale),
        "normal": image(per[:, 1, :3]),
        "depth": image(per[:, 2, 3]),
        "position": image(per[:, 2, :3]),
        "variance": image(stderr),
        "emission": image(per[:, 4, :3]),
        "emission_sampled": image(per[:, 3, :3]),
    }
    if per.shape[1] * 4 == STOKES_AOV_FLOATS_PER_PIXEL:
        stokes = per[:, 5:9, :3]  # (pixels, S0..S3, XYZ)
        images["stokes"] = image(stokes.reshape(-1, 12))
        s0, s1, s2 = stokes[:, 0, 1], stokes[:, 1, 1], stokes[:, 2, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            images["dolp"] = image(np.where(s0 > 0.0, np.hypot(s1, s2) / s0, 0.0))
        images["aolp"] = image(0.5 * np.arctan2(s2, s1))
    return images


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
