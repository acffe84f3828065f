"""The rendered image: film XYZ (relative to ∫ȳ, so a constant radiance 1 has Y = 1) and how it was made."""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.film.colour_output import (
    ColourSpace,
    WhiteBalance,
    encode_for_display,
    exr_chromaticities,
    png_cicp,
    xyz_to_output,
)
from spectrace.spectral.colorimetry import srgb_encode


@dataclass
class SpectralBands:
    """Band-averaged spectral radiance per pixel: band i spans edges_nm[i]..edges_nm[i+1] and holds
    (1/Δλ)∫ L dλ over it, W/(m² sr nm)."""

    edges_nm: np.ndarray  # (bins + 1,)
    radiance: np.ndarray  # (height, width, bins) float32

    @property
    def centres_nm(self) -> np.ndarray:
        return 0.5 * (self.edges_nm[:-1] + self.edges_nm[1:])


IMAGE_SUFFIXES = (".exr", ".png", ".tif", ".tiff", ".jpg", ".jpeg", ".pfm")
BIT_DEPTHS = (8, 16)


def output_format_problem(path: Path, bit_depth: int = 8, space: ColourSpace | str = ColourSpace.SRGB) -> str | None:
    """Why an image cannot be written to `path` with that bit depth and colour space, or None."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMAGE_SUFFIXES:
        return f"unknown image format '{Path(path).suffix}' (use {', '.join(IMAGE_SUFFIXES)})"
    if bit_depth not in BIT_DEPTHS:
        return f"bit depth must be 8 or 16, got {bit_depth}"
    if bit_depth == 16 and suffix not in (".png", ".tif", ".tiff"):
        holds = "32-bit floats" if suffix in (".exr", ".pfm") else "8 bits"
        return f"16 bits go to .png and .tif files only; {suffix} holds {holds}"
    if ColourSpace(space) is ColourSpace.XYZ and suffix not in (".exr", ".pfm"):
        return "XYZ output needs an .exr or .pfm file (the other formats hold display-encoded RGB)"
    return None


@dataclass
class Image:
    xyz: np.ndarray  # (height, width, 3) float32, mean per pixel
    spp: int
    seed: int
    device: str
    render_seconds: float
    dropped_samples: int = 0  # non-finite samples left out of the film
    rays_traced: int = 0
    exposure: float = 0.0  # stops: the RGB outputs are scaled by 2**exposure; xyz is not
    spectral: SpectralBands | None = None  # when rendered with spectral bins
    # Further named (height, width) float32 channels (more observers' X, Y, Z, a sensor's channels, a ΔE map),
    # written to EXR under these names.
    channels: dict[str, np.ndarray] = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    colour_space: ColourSpace = ColourSpace.SRGB  # of the files `write` makes (see spectrace.film.colour_output)
    white_balance: WhiteBalance | None = None  # chromatic adaptation applied to every RGB output
    # AOVs by name (spectrace.film.aovs): albedo (h, w, 3) XYZ, normal and position (h, w, 3), depth and variance (h, w)
    aovs: dict[str, np.ndarray] = field(default_factory=dict)
    bit_depth: int = 8  # of the PNG and TIFF files `write` makes (8 or 16)

    def __repr__(self) -> str:
        # The dataclass's own repr would print every pixel (tens of kilobytes in a notebook).
        extras = [f"spectral_bins={len(self.spectral.edges_nm) - 1}"] if self.spectral is not None else []
        extras += [f"aovs={','.join(self.aovs)}"] if self.aovs else []
        extras += [f"dropped_samples={self.dropped_samples}"] if self.dropped_samples else []
        extras += [f"exposure={self.exposure:g}"] if self.exposure else []
        return (
            f"Image({self.width}x{self.height}, spp={self.spp}, seed={self.seed}, device={self.device!r}, "
            f"render_seconds={self.render_seconds:.3g}, colour_space={str(self.colour_space)!r}"
            + "".join(f", {extra}" for extra in extras)
            + ")"
        )

    @property
    def width(self) -> int:
        return self.xyz.shape[1]

    @property
    def height(self) -> int:
        return self.xyz.shape[0]

    def to_linear_srgb(self) -> np.ndarray:
        """Linear sRGB of the film (white-balanced if asked), times 2**exposure."""
        return xyz_to_output(self.xyz, ColourSpace.SRGB, self.white_balance, self.exposure)

    def to_srgb(self) -> np.ndarray:
        """Display-encoded sRGB in [0, 1] (out-of-gamut and over-bright values clipped)."""
        return srgb_encode(np.clip(self.to_linear_srgb(), 0.0, 1.0))

    def to_rgb(self) -> np.ndarray:
        """Linear values of `colour_space` (X, Y, Z for "xyz"), white-balanced if asked, times 2**exposure."""
        return xyz_to_output(self.xyz, self.colour_space, self.white_balance, self.exposure)

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """`np.asarray(image)`: the (height, width, 3) linear values `to_rgb()` gives, as an EXR file holds them (X,
        Y, Z for an "xyz" image); `to_srgb()` gives what a screen shows."""
        if copy is False:
            raise ValueError("an Image's array is computed from its film XYZ: it cannot be given without a copy")
        values = self.to_rgb()
        return values if dtype is None else values.astype(dtype, copy=False)

    def to_display(self) -> np.ndarray:
        """`to_rgb()` clipped to [0, 1] and encoded with `colour_space`'s transfer curve (what PNG files hold)."""
        return encode_for_display(self.to_rgb(), self.colour_space)

    def metadata(self) -> dict[str, str]:
        return {
            "spp": str(self.spp),
            "seed": str(self.seed),
            "device": self.device,
            "render_seconds": f"{self.render_seconds:.3f}",
            "dropped_samples": str(self.dropped_samples),
            "exposure": f"{self.exposure:g}",
            "colour_space": ColourSpace(self.colour_space).value,
            **({"white_balance": self.white_balance.describe()} if self.white_balance else {}),
            **{k: str(v) for k, v in self.extra.items()},
        }

    def write(self, path: str | Path, include_xyz: bool = True, bit_depth: int | None = None) -> None:
        """Write by suffix: .exr (linear float32 of the colour space, plus X, Y, Z channels, plus the spectral bands
        in the Fichet et al. 2021 layout when the image has them, the AOVs' channels (spectrace.film.aovs) and
        `channels` by name); .png, .tif/.tiff (8 or 16 bits: `bit_depth`, else the image's), .jpg/.jpeg (8 bits),
        each display-encoded with the colour space's curve and, for Display P3 and Rec.2020, carrying its ICC
        profile; .pfm (linear float RGB, unclipped). The display formats hold the colour only."""
        path = Path(path)
        suffix = path.suffix.lower()
        space = ColourSpace(self.colour_space)
        depth = self.bit_depth if bit_depth is None else bit_depth
        # Each writer imported only when used: OpenEXR's module takes longer to import than a small PNG to write.
        if suffix == ".exr":
            from spectrace.film.aovs import aov_channels
            from spectrace.io.exr import write_exr

            attributes = {} if space is ColourSpace.SRGB else {"chromaticities": exr_chromaticities(space)}
            write_exr(
                path,
                self.to_rgb(),
                self.xyz if include_xyz else None,
                self.metadata(),
                spectral=self.spectral,
                attributes=attributes,
                channels={**aov_channels(self.aovs, space), **self.channels},
            )
            return
        from spectrace.io import raster

        if (problem := output_format_problem(path, depth, space)) is not None:
            raise SpectraceError(problem, where=str(path))
        if suffix in raster.LINEAR_FORMATS:
            raster.write_pfm(path, self.to_rgb())
            return
        from spectrace.film.icc_profile import icc_profile

        raster.write_display_image(
            path,
            self.to_display(),
            self.metadata(),
            bit_depth=depth,
            icc_profile=None if space is ColourSpace.SRGB else icc_profile(space),
            png_chunks={} if space is ColourSpace.SRGB else {b"cICP": png_cicp(space)},
        )

    def _repr_png_(self) -> bytes:
        import io

        from PIL import Image as PILImage

        buffer = io.BytesIO()
        pixels = np.rint(self.to_srgb() * 255).astype(np.uint8)
        PILImage.fromarray(pixels, "RGB").save(buffer, format="PNG")
        return buffer.getvalue()
