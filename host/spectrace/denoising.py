"""Denoising a rendered image with Intel Open Image Denoise (OIDN, its "RT" filter) through the `pyoidn` binding,
guided by the render's albedo and normal AOVs. An optional extra (`spectrace[denoise]`): rendering never needs it.

OIDN works on linear RGB: the film's XYZ goes to linear sRGB (negative, out-of-gamut values clipped to 0, which
OIDN's HDR mode requires), is denoised, and comes back to XYZ, so the denoised image keeps every output option
(colour space, white balance, exposure) of the noisy one. The albedo goes in as linear sRGB with white at
(1, 1, 1) (spectrace.film.aovs.albedo_in), clipped to [0, 1]; the normals as they are (world space), clipped to [-1, 1].
Both guides are noisy (the same paths made them), so OIDN prefilters them (cleanAux off).

Emitters seen directly: a short render knows the light a camera ray meets on an emitter poorly where an emitter's
edge crosses a pixel (at 4 spp, a quarter of the pixel's area per sample), and OIDN cannot tell that coverage noise
from detail. So `spectrace render --denoise` renders that light apart: `directly_seen_emission` traces camera rays
only (the same camera and pixel filter, max_depth 1: no next-event estimation, nothing beyond the first surface)
with max(32, 2 spp) samples per pixel, recording the emission AOV, the expected value over the wavelengths of the
emission each ray meets. `denoise(image, emission=...)` takes out of the image the part its own camera rays' emission
makes (the `emission_sampled` AOV, so render with aovs including "emission"), denoises the rest and adds the pass
back:  denoised = OIDN(image - emission_sampled; albedo, normal) + emission. Both the taken and the added part are
unbiased estimates of the same expectation, so the exchange adds no bias, and the added one is free of the colour
noise of four sampled wavelengths and has 8 times the samples or more. Without `emission`, the expected value over
the wavelengths of the image's own camera rays (the `emission` AOV) is added back instead (exchange_emission), which
removes the colour noise but not the coverage noise; without the AOVs the image goes in whole.
"""

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from spectrace.core.limits import MAX_SEED
from spectrace.errors import SpectraceError
from spectrace.film.aovs import albedo_in
from spectrace.film.colour_output import ColourSpace, xyz_to_rgb_matrix
from spectrace.film.image import Image
from spectrace.scene.model import Scene

DENOISE_AOVS = ("albedo", "normal")
RENDER_AOVS = (*DENOISE_AOVS, "emission")  # what `spectrace render --denoise` records for it
EMISSION_PASS_MIN_SPP = 32
# The pass's sampler seed is the scene's plus this (modulo MAX_SEED + 1): its samples are not the image's own.
EMISSION_PASS_SEED_OFFSET = 0x5EED_E1
INSTALL_HINT = "denoising needs Intel Open Image Denoise's binding: pip install 'spectrace[denoise]' (pyoidn)"


def _oidn():
    try:
        import pyoidn
    except ImportError:
        raise SpectraceError(INSTALL_HINT) from None
    return pyoidn


def denoise_available() -> bool:
    """Whether the denoiser's binding can be imported."""
    try:
        _oidn()
    except SpectraceError:
        return False
    return True


def noisy_path_for(path):
    """Where `spectrace render --denoise` keeps the noisy image beside the denoised `path`: `<stem>.noisy<suffix>`."""
    return path.with_name(f"{path.stem}.noisy{path.suffix}")


# The noisy image's metadata (`spectrace:noisy_image_of`): the name of the denoised image it was written beside.
NOISY_MARK = "noisy_image_of"


def noisy_image(image: Image, output: Path) -> Image:
    """The noisy image as `spectrace render --denoise -o output` writes it: marked as that output's noisy twin."""
    return replace(image, extra={**image.extra, NOISY_MARK: Path(output).name})


def _noisy_mark(path: Path) -> str | None:
    """The mark of a noisy twin in the image file `path`, if it has one."""
    try:
        if path.suffix.lower() == ".exr":
            from spectrace.io.exr import read_exr_header

            value = read_exr_header(path).get(f"spectrace:{NOISY_MARK}")
            return value.decode("utf-8", "replace") if isinstance(value, bytes) else value
        from spectrace.io.png import read_png_texts

        return read_png_texts(path).get(f"spectrace:{NOISY_MARK}")
    except (OSError, RuntimeError, ValueError):  # unreadable, or not an image at all: not ours
        return None


def check_noisy_path(noisy: Path, output: Path) -> None:
    """Refuse to replace, at the noisy image's place beside `output`, a file that is not the noisy twin an
    earlier `--denoise -o output` wrote: the user named `output` only, and that file may be anything (another
    render's image, a photo). The twin itself is replaced, as `output` is."""
    if os.path.lexists(noisy) and _noisy_mark(noisy) != Path(output).name:
        raise SpectraceError(
            f"--denoise keeps the noisy image in {noisy.name}, which exists and is not the noisy image of an "
            f"earlier --denoise render of {Path(output).name}; move it away or choose another --output",
            where=str(noisy),
        )


def emission_pass_spp(spp: int) -> int:
    """Samples per pixel of the directly seen emission pass for an image of `spp`: max(32, 2 spp)."""
    return max(EMISSION_PASS_MIN_SPP, 2 * spp)


def emission_pass_scene(scene: Scene, spp: int) -> Scene:
    """The scene set up for the directly seen emission pass of an image of `spp` samples per pixel (the path
    integrator at max_depth 1 recording the emission AOV, its own seed); camera, film and pixel filter unchanged."""
    return scene.with_overrides(
        integrator="path",
        max_depth=1,
        aovs=("emission",),
        spp=emission_pass_spp(spp),
        seed=(scene.seed + EMISSION_PASS_SEED_OFFSET) % (MAX_SEED + 1),
    )


def directly_seen_emission(scene: Scene, spp: int, device=None) -> Image:
    """The emission the camera rays of `scene` meet directly (area lights, the environment), for the denoiser
    (`denoise(image, emission=...)`) of an image of `spp` samples per pixel: an Image of max(32, 2 spp) samples
    whose `aovs["emission"]` is its film XYZ (height, width, 3), each sample's the expected value over the
    wavelengths. device: as render()'s."""
    from spectrace.engine.renderer import Renderer

    pass_scene = emission_pass_scene(scene, spp)
    return Renderer(pass_scene, device).render(spp=pass_scene.spp)


def denoise_with_emission_pass(scene: Scene, image: Image, device=None, log=print) -> Image:
    """What `spectrace render --denoise` does with its image of `scene`: the directly seen emission rendered apart
    (on `device`, said through `log`), then the image denoised with it."""
    emission = directly_seen_emission(scene, image.spp, device)
    log(f"emission pass: {emission.spp} spp of camera rays alone, {emission.render_seconds:.2f} s")
    return denoise(image, emission=emission)


def _emission_xyz(emission, shape) -> np.ndarray:
    values = emission.aovs.get("emission") if isinstance(emission, Image) else emission
    if values is None:
        raise SpectraceError("the emission image has no emission AOV (make it with spectrace.directly_seen_emission)")
    values = np.asarray(values, np.float64)
    if values.shape != shape:
        raise SpectraceError(f"the emission is {values.shape[1::-1]} pixels, the image {shape[1::-1]}")
    return values


def denoise(image: Image, exchange_emission: bool = True, emission: Image | np.ndarray | None = None) -> Image:
    """The image denoised by OIDN with its albedo and normal AOVs (render with aovs=("albedo", "normal"), and
    "emission" for the directly seen emitters' exchange, which exchange_emission=False turns off); the AOVs and
    every other field are kept, and `extra["denoised"]` says how it was made.

    emission: the directly seen emission rendered apart (`directly_seen_emission(scene, image.spp)`, or its film
    XYZ as an array (height, width, 3)), which then replaces the image's own (the module's docstring); it needs
    the image's emission AOV."""
    missing = [name for name in DENOISE_AOVS if name not in image.aovs]
    if missing:
        raise SpectraceError(
            f"denoising needs the {' and '.join(missing)} AOV{'s' if len(missing) > 1 else ''}; render with "
            f"aovs=('albedo', 'normal') (or --denoise, which asks for them)"
        )
    if emission is not None and "emission_sampled" not in image.aovs:
        raise SpectraceError(
            "denoising with the emission pass needs the image's emission AOV; render with aovs including 'emission'"
        )
    added = _emission_xyz(emission, np.shape(image.xyz)) if emission is not None else None
    pyoidn = _oidn()
    to_srgb = xyz_to_rgb_matrix(ColourSpace.SRGB)
    xyz_in = np.asarray(image.xyz, np.float64)
    exchange = added is not None or (
        exchange_emission and "emission" in image.aovs and "emission_sampled" in image.aovs
    )
    if exchange:
        xyz_in = xyz_in - image.aovs["emission_sampled"]
    colour = np.maximum(xyz_in @ to_srgb.T, 0.0).astype(np.float32)
    albedo = np.clip(albedo_in(image.aovs["albedo"], ColourSpace.SRGB), 0.0, 1.0).astype(np.float32)
    normal = np.clip(np.nan_to_num(image.aovs["normal"]), -1.0, 1.0).astype(np.float32)
    try:
        denoised = pyoidn.denoise(colour, albedo, normal, hdr=True)
    except (RuntimeError, ValueError, TypeError) as error:
        raise SpectraceError(f"Open Image Denoise failed: {' '.join(str(error).split())}") from None
    xyz = np.asarray(denoised, np.float64) @ np.linalg.inv(to_srgb).T
    how = "Open Image Denoise RT (albedo, normal)"
    if added is not None:
        xyz = xyz + added
        spp = f" at {emission.spp} spp" if isinstance(emission, Image) else ""
        how += f"; directly seen emission rendered apart{spp}"
    elif exchange:
        xyz = xyz + image.aovs["emission"]
        how += "; directly seen emission exchanged for its expected value"
    return replace(image, xyz=xyz.astype(np.float32), extra={**image.extra, "denoised": how})
