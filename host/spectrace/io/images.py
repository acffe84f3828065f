"""Reading images named in scenes (pictures on screens, environment maps): only regular files, and the size in the
file's header checked against the image limit before anything is decoded, so a small file claiming a huge image
costs nothing."""

from pathlib import Path

import numpy as np

from spectrace.core import limits
from spectrace.errors import SpectraceError
from spectrace.io.input_files import regular_file

RGBE_SUFFIXES = (".hdr", ".rgbe")  # Radiance HDR: spectrace.io.rgbe


def read_picture(path: Path, where: str) -> np.ndarray:
    """(height, width, 3) values of a picture in [0, 1]: 8/16-bit PNG or JPEG code values divided by their maximum,
    or an EXR's R, G, B as stored. The size in the file's header is checked before anything is decoded."""
    if path.suffix.lower() == ".exr":
        return read_environment_map(path, where, what="image").astype(np.float64)
    regular_file(path, where, what="image")
    if (sixteen := _read_png16(path, where, "image")) is not None:
        return np.repeat(sixteen, 3, axis=-1) if sixteen.shape[-1] == 1 else sixteen

    def decode(picture) -> tuple[np.ndarray, bool]:
        bits16 = picture.mode.startswith("I;16") or picture.mode == "I"
        return np.asarray(picture.convert("RGB") if not bits16 else picture, dtype=np.float64), bits16

    values, bits16 = _read_with_pillow(path, where, "image", decode)
    if values.ndim == 2:
        values = np.repeat(values[..., None], 3, axis=-1)
    return values / (65535.0 if bits16 else 255.0)


def _read_with_pillow(path: Path, where: str, what: str, decode):
    """decode(picture) of an image Pillow reads, once its header's size is within the image limit; a failure is one
    line naming `what`, the file and `where`."""
    import warnings

    from PIL import Image as PILImage

    try:
        # Pillow warns of "decompression bombs" by its own measure; image_size_problem is the limit here.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PILImage.DecompressionBombWarning)
            with PILImage.open(path) as picture:  # reads the header only
                if problem := limits.image_size_problem(*picture.size):
                    raise SpectraceError(f"{what} '{path}': {problem}", where=where)
                return decode(picture)
    except SpectraceError:
        raise
    except Exception as exc:  # Pillow raises many types for unreadable files
        raise SpectraceError(f"cannot read {what} '{path}': {exc}", where=where) from None


def _read_png16(path: Path, where: str, what: str) -> np.ndarray | None:
    """A 16-bit RGB, RGBA or grey + alpha PNG's samples over 65535, (height, width, 1 or 3) without alpha, read at
    their 16 bits (spectrace.io.png16: Pillow reads them at 8); None for any other file."""
    from spectrace.io import png16

    try:
        with open(path, "rb") as file:
            header = png16.sixteen_bit_colour_header(file.read(33))
        if header is None:
            return None
        if problem := limits.image_size_problem(header[0], header[1]):
            raise SpectraceError(f"{what} '{path}': {problem}", where=where)
        samples = png16.read_png16(path)
    except SpectraceError:
        raise
    except Exception as exc:  # a malformed file: zlib, Pillow and the reader's own errors
        raise SpectraceError(f"cannot read {what} '{path}': {exc}", where=where) from None
    colour = samples[..., :1] if samples.shape[-1] == 2 else samples[..., :3]
    return colour.astype(np.float64) / 65535.0


def _exr_size(path: Path) -> tuple[int, int]:
    """(width, height) of an OpenEXR file's data window, from its header alone."""
    from spectrace.io.exr import read_exr_header

    (x_min, y_min), (x_max, y_max) = (np.asarray(corner).tolist() for corner in read_exr_header(path)["dataWindow"])
    return int(x_max) - int(x_min) + 1, int(y_max) - int(y_min) + 1


def read_exr_checked(path: Path, where: str, what: str) -> dict:
    """The channels of an OpenEXR file once it is known to be a regular file whose header's size is within the
    image limit (checked before any pixel is decoded); every failure one line naming `what`, the file and `where`."""
    from spectrace.io.exr import read_exr

    regular_file(path, where, what=what)
    try:
        size = _exr_size(path)
    except Exception as exc:  # OpenEXR raises bare exceptions for unreadable files
        raise SpectraceError(f"cannot read {what} '{path}': {exc}", where=where) from None
    if problem := limits.image_size_problem(*size):
        raise SpectraceError(f"{what} '{path}': {problem}", where=where)
    try:
        channels, _ = read_exr(path)
    except Exception as exc:
        raise SpectraceError(f"cannot read {what} '{path}': {exc}", where=where) from None
    return channels


def read_environment_map(path: Path, where: str, what: str = "environment map") -> np.ndarray:
    """The (height, width, 3) linear sRGB pixels of an OpenEXR or Radiance HDR (.hdr, .rgbe) latitude-longitude map
    (or a picture's EXR)."""
    if path.suffix.lower() in RGBE_SUFFIXES:
        from spectrace.io.rgbe import read_rgbe

        rgb = read_rgbe(path, where, what)
        if not np.all(np.isfinite(rgb)):
            raise SpectraceError(f"{what} '{path}' has NaN or infinite pixels", where=where)
        return rgb
    channels = read_exr_checked(path, where, what)
    if "RGB" in channels:
        rgb = channels["RGB"]
    elif {"R", "G", "B"} <= set(channels):
        rgb = np.stack([channels["R"], channels["G"], channels["B"]], axis=-1)
    else:
        raise SpectraceError(f"{what} '{path}' has no R, G, B channels", where=where)
    rgb = np.asarray(rgb, np.float32)
    if not np.all(np.isfinite(rgb)):
        raise SpectraceError(f"{what} '{path}' has NaN or infinite pixels", where=where)
    return rgb


def read_texture_image(path: Path, where: str) -> tuple[np.ndarray, bool]:
    """(values (height, width, channels), encoded) of an image texture: channels 1 (grey) or 3 (an alpha channel is
    dropped). PNG, JPEG, TIFF and the other formats Pillow reads give 8/16-bit code values divided by their maximum
    (encoded = True: the caller decodes the transfer curve); 32-bit float images (TIFF mode F) and OpenEXR
    (R, G, B, or Y) and Radiance RGBE (.hdr) give their values as stored (encoded = False). The size in the header is
    checked before anything is decoded; non-finite values are refused."""
    if path.suffix.lower() in RGBE_SUFFIXES:
        from spectrace.io.rgbe import read_rgbe

        values, encoded = read_rgbe(path, where, "texture").astype(np.float64), False
    elif path.suffix.lower() == ".exr":
        channels = read_exr_checked(path, where, "texture")  # which checks it is a regular file
        if "RGB" in channels or "RGBA" in channels:
            values = np.asarray(channels.get("RGB", channels.get("RGBA")))[..., :3]
        elif {"R", "G", "B"} <= set(channels):
            values = np.stack([channels["R"], channels["G"], channels["B"]], axis=-1)
        elif "Y" in channels:
            values = np.asarray(channels["Y"])[..., None]
        else:
            names = ", ".join(sorted(channels)) or "none"
            raise SpectraceError(f"texture '{path}' has no R, G, B (or Y) channels (it has {names})", where=where)
        encoded = False
        values = np.asarray(values, np.float64)
    else:
        regular_file(path, where, what="texture")
        if (sixteen := _read_png16(path, where, "texture")) is not None:
            values, encoded = sixteen, True
        else:
            values, encoded = _read_with_pillow(path, where, "texture", pil_image_values)
    if not np.all(np.isfinite(values)):
        raise SpectraceError(f"texture '{path}' has NaN or infinite values", where=where)
    return values, encoded


def pil_image_values(picture) -> tuple[np.ndarray, bool]:
    """(values (height, width, 1 or 3), encoded) of a Pillow image: code values over their maximum (encoded) or,
    for 32-bit float images, the values as stored."""
    mode = picture.mode
    if mode == "F":
        return np.asarray(picture, np.float64)[..., None], False
    if mode.startswith("I;16") or mode == "I":
        return np.asarray(picture, np.float64)[..., None] / 65535.0, True
    grey = mode in ("1", "L", "LA")
    converted = picture.convert("L" if grey else "RGB")
    values = np.asarray(converted, np.float64) / 255.0
    return (values[..., None] if grey else values), True
