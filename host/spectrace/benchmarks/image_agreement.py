"""Do two renders of one scene agree? Mean film XYZ over a few image regions, compared against the noise.

Each renderer's pixels are independent Monte Carlo estimates (both samplers decorrelate pixels), so the
standard error of a region mean is sqrt(σ²/P) for P pixels of noise variance σ². σ² is estimated from
differences of neighbouring pixels, E[(p_i - p_j)²] / 2, which cancels the image's smooth shading and leaves
the noise; an edge inside a region only makes the estimate larger (a looser, never a stricter, check).
"""

from dataclasses import dataclass

import numpy as np

# Regions are (left, top, right, bottom) as fractions of the image; every set ends with the whole image.
WHOLE_IMAGE = {"whole image": (0.0, 0.0, 1.0, 1.0)}
# The bundled Cornell box as seen from its camera.
CORNELL_BOX_REGIONS = {
    "left wall (red)": (0.03, 0.30, 0.17, 0.70),
    "right wall (green)": (0.83, 0.30, 0.97, 0.70),
    "back wall": (0.55, 0.25, 0.75, 0.55),
    "floor": (0.08, 0.88, 0.46, 0.96),
    "light": (0.43, 0.125, 0.57, 0.15),
    **WHOLE_IMAGE,
}
QUADRANT_REGIONS = {
    "top left": (0.0, 0.0, 0.5, 0.5),
    "top right": (0.5, 0.0, 1.0, 0.5),
    "bottom left": (0.0, 0.5, 0.5, 1.0),
    "bottom right": (0.5, 0.5, 1.0, 1.0),
    **WHOLE_IMAGE,
}
SIGMA_LIMIT = 4.0


def region_pixels(image: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    """The pixels of `image` (H, W, C) inside a fractional box; at least one pixel on each axis."""
    height, width = image.shape[:2]
    left, top, right, bottom = box
    x0 = min(int(np.floor(left * width)), width - 1)
    y0 = min(int(np.floor(top * height)), height - 1)
    x1 = max(int(np.ceil(right * width)), x0 + 1)
    y1 = max(int(np.ceil(bottom * height)), y0 + 1)
    return image[y0:y1, x0:x1]


def region_mean_and_error(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean per channel and its standard error from neighbour differences (see the module docstring)."""
    pixels = np.asarray(pixels, dtype=np.float64)
    count = pixels.shape[0] * pixels.shape[1]
    squared_differences = []
    if pixels.shape[1] > 1:
        squared_differences.append((np.diff(pixels, axis=1) ** 2).reshape(-1, pixels.shape[2]))
    if pixels.shape[0] > 1:
        squared_differences.append((np.diff(pixels, axis=0) ** 2).reshape(-1, pixels.shape[2]))
    if not squared_differences:
        return pixels.reshape(-1, pixels.shape[2]).mean(axis=0), np.full(pixels.shape[2], np.inf)
    noise_variance = np.concatenate(squared_differences).mean(axis=0) / 2.0
    return pixels.reshape(-1, pixels.shape[2]).mean(axis=0), np.sqrt(noise_variance / count)


@dataclass
class RegionComparison:
    region: str
    ours: list[float]  # mean XYZ
    theirs: list[float]
    standard_error: list[float]  # of the difference
    sigmas: float  # largest |difference| / standard error over X, Y, Z
    relative_difference: float  # largest |difference| / mean, over X, Y, Z

    @property
    def agrees(self) -> bool:
        return self.sigmas <= SIGMA_LIMIT

    def as_dict(self) -> dict:
        return {**self.__dict__, "agrees": self.agrees}


def compare_regions(ours: np.ndarray, theirs: np.ndarray, regions: dict[str, tuple]) -> list[RegionComparison]:
    rows = []
    for name, box in regions.items():
        mean_a, error_a = region_mean_and_error(region_pixels(ours, box))
        mean_b, error_b = region_mean_and_error(region_pixels(theirs, box))
        difference = np.abs(mean_a - mean_b)
        error = np.sqrt(error_a**2 + error_b**2)
        with np.errstate(divide="ignore", invalid="ignore"):
            sigmas = np.where(error > 0, difference / error, np.where(difference > 0, np.inf, 0.0))
            relative = np.where(np.abs(mean_b) > 0, difference / np.abs(mean_b), 0.0)
        rows.append(
            RegionComparison(
                name, mean_a.tolist(), mean_b.tolist(), error.tolist(), float(sigmas.max()), float(relative.max())
            )
        )
    return rows


def regions_for(scene_source) -> dict[str, tuple]:
    """Named regions for the bundled Cornell box, image quadrants for any other scene."""
    from spectrace.resources import scenes_dir

    is_cornell = scene_source is not None and scene_source.resolve() == (scenes_dir() / "cornell_box.toml").resolve()
    return CORNELL_BOX_REGIONS if is_cornell else QUADRANT_REGIONS
