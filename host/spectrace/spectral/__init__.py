"""Host-side spectral core: the wavelength grid, CIE colorimetry, spectra loading, RGB uplift (one colour, or a
whole texture), and the device spectrum table. See the modules for the conventions (grid, film XYZ normalisation)."""

from spectrace.spectral.colorimetry import (
    CIE_1931_CMFS,
    CIE_Y_INTEGRAL,
    LINEAR_SRGB_TO_XYZ,
    XYZ_TO_LINEAR_SRGB,
    cmf_table_normalised,
    linear_srgb_to_xyz,
    normalised_to_unit_y,
    reflectance_to_xyz,
    spectrum_to_xyz,
    srgb_decode,
    srgb_encode,
    xyz_to_linear_srgb,
    xyz_to_xy,
)
from spectrace.spectral.grid import GRID_MAX_NM, GRID_MIN_NM, GRID_NM, GRID_SIZE, GRID_STEP_NM, integrate_on_grid
from spectrace.spectral.illuminants import cie_illuminant, cie_illuminant_names, d65_normalised
from spectrace.spectral.rgb_texture import (
    illuminant_texture_coefficients,
    reflectance_coefficients,
    texture_illuminant_coefficients,
    texture_reflectance_coefficients,
)
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_io import (
    library_spectrum,
    list_library_spectra,
    load_spectrum_csv,
    parse_inline_spectrum,
    spectrum_from_colour,
)
from spectrace.spectral.table import SpectrumTable
from spectrace.spectral.uplift import (
    illuminant_coefficients,
    sigmoid_polynomial_spectrum,
    uplift_illuminant,
    uplift_reflectance,
)

__all__ = [
    "CIE_1931_CMFS",
    "CIE_Y_INTEGRAL",
    "GRID_MAX_NM",
    "GRID_MIN_NM",
    "GRID_NM",
    "GRID_SIZE",
    "GRID_STEP_NM",
    "LINEAR_SRGB_TO_XYZ",
    "XYZ_TO_LINEAR_SRGB",
    "Spectrum",
    "SpectrumTable",
    "cie_illuminant",
    "cie_illuminant_names",
    "cmf_table_normalised",
    "d65_normalised",
    "illuminant_coefficients",
    "illuminant_texture_coefficients",
    "integrate_on_grid",
    "library_spectrum",
    "linear_srgb_to_xyz",
    "list_library_spectra",
    "load_spectrum_csv",
    "normalised_to_unit_y",
    "parse_inline_spectrum",
    "reflectance_coefficients",
    "reflectance_to_xyz",
    "sigmoid_polynomial_spectrum",
    "spectrum_from_colour",
    "spectrum_to_xyz",
    "srgb_decode",
    "srgb_encode",
    "texture_illuminant_coefficients",
    "texture_reflectance_coefficients",
    "uplift_illuminant",
    "uplift_reflectance",
    "xyz_to_linear_srgb",
    "xyz_to_xy",
]
