"""Denoising a rendered image with Intel Open Image Denoise (OIDN, its "RT" filter) through the `pyoidn` binding,
guided by the render's albedo and normal AOVs. An optional extra (`spectrace[denoise]`): rendering never needs it.

OIDN works on linear RGB: the film's XYZ goes to linear sRGB (negative, out-of-gamut values clipped to 0, which
OIDN's HDR mode requires), is denoised, and comes back to XYZ, so the denoised image keeps every output option
(colour space, white balance, exposure) of the noisy one. The albedo goes in as linear sRGB with white at
(1, 1, 1) (spectrace.aovs.albedo_in), clipped to [0, 1]; the normals as they are (world space), clipped to [-1, 1].
Both guides are noisy (the same paths made them), so OIDN prefilters them (cleanAux off).

Emitters seen directly: with the emission AOV (render with aovs including "emission"; --denoise asks for it), the
part of the image the camera rays' own emission makes, as the image's four-wavelength estimate holds it
(`emission_sampled`), is taken out before denoising and its expected value over the wavelengths (`emission`) is
added back after. The expected value is exact where the sampled one carries the colour noise of four wavelengths
at the emitter's full brightness, which OIDN (trained on RGB renders) spreads rather than removes; the exchange is
a conditional expectation of that part of the estimator, so it adds no bias. Without the AOV the image goes in
whole.
"""

from dataclasses import replace

import numpy as np

from spectrace.aovs import albedo_in
from spectrace.colour_output import ColourSpace, xyz_to_rgb_matrix
from spectrace.errors import SpectraceError
from spectrace.image import Image

DENOISE_AOVS = ("albedo", "normal")
RENDER_AOVS = (*DENOISE_AOVS, "emission")  # what `spectrace render --denoise` records for it
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


def denoise(image: Image, exchange_emission: bool = True) -> Image:
    """The image denoised by OIDN with its albedo and normal AOVs (render with aovs=("albedo", "normal"), and
    "emission" for the directly seen emitters' exchange, which exchange_emission=False turns off); the AOVs and
    every other field are kept, and `extra["denoised"]` says how it was made."""
    missing = [name for name in DENOISE_AOVS if name not in image.aovs]
    if missing:
        raise SpectraceError(
            f"denoising needs the {' and '.join(missing)} AOV{'s' if len(missing) > 1 else ''}; render with "
            f"aovs=('albedo', 'normal') (or --denoise, which asks for them)"
        )
    pyoidn = _oidn()
    to_srgb = xyz_to_rgb_matrix(ColourSpace.SRGB)
    xyz_in = np.asarray(image.xyz, np.float64)
    exchange = exchange_emission and "emission" in image.aovs and "emission_sampled" in image.aovs
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
    if exchange:
        xyz = xyz + image.aovs["emission"]
        how += "; directly seen emission exchanged for its expected value"
    return replace(image, xyz=xyz.astype(np.float32), extra={**image.extra, "denoised": how})
