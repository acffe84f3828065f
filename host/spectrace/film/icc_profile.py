"""ICC display profiles (matrix/TRC) of the output colour spaces, embedded in PNG, JPEG and TIFF files so that
viewers which read no cICP chunk (most of them) still show Display P3 and Rec.2020 files right.

Built from the space's own numbers, as ICC.1:2022 (profile version 4.4) lays a three-component matrix/TRC display
profile out (clauses 7 and 9, the tag types of clause 10):

- header: device class 'mntr', data colour space 'RGB ', connection space 'XYZ ', D50 illuminant;
- rXYZ, gXYZ, bXYZ: the columns of the space's RGB → XYZ matrix (the one `xyz_to_rgb_matrix` inverts, so the
  profile says what the file's numbers mean here) adapted from its D65 white to the connection space's D50 with
  Bradford, the adaptation recorded in 'chad' (Annex G);
- rTRC, gTRC, bTRC: the space's decoding curve as a parametricCurveType of function type 3,
  Y = (aX + b)^g for X ≥ d, Y = cX below: IEC 61966-2-1 for sRGB and Display P3, the inverse of the ITU-R BT.2020
  (= BT.709) OETF for Rec.2020 — the curves `encode_for_display` applies;
- wtpt: D50 (a version 4 profile's media white), desc and cprt as multiLocalizedUnicodeType.

Numbers are s15Fixed16 (signed, 16 fraction bits) as the tag types require.
"""

from __future__ import annotations

import struct
from functools import cache

import numpy as np

from spectrace.film.colour_output import Adaptation, ColourSpace, adaptation_matrix, output_white_xyz, xyz_to_rgb_matrix

# The connection space's illuminant, ICC.1 clause 7.2.16: exactly these s15Fixed16 numbers.
PCS_D50 = (0.9642, 1.0, 0.8249)

# Decoding curves (g, a, b, c, d) of parametric function type 3.
_SRGB_CURVE = (2.4, 1 / 1.055, 0.055 / 1.055, 1 / 12.92, 0.04045)
_BT2020_CURVE = (1 / 0.45, 1 / 1.099, 0.099 / 1.099, 1 / 4.5, 4.5 * 0.018)  # α, β of 10-bit systems, as encoded
_CURVES = {ColourSpace.SRGB: _SRGB_CURVE, ColourSpace.DISPLAY_P3: _SRGB_CURVE, ColourSpace.REC2020: _BT2020_CURVE}
_NAMES = {ColourSpace.SRGB: "sRGB", ColourSpace.DISPLAY_P3: "Display P3", ColourSpace.REC2020: "ITU-R BT.2020"}


def _s15(value: float) -> bytes:
    return struct.pack(">i", int(round(value * 65536.0)))


def _xyz_tag(xyz) -> bytes:
    return b"XYZ \x00\x00\x00\x00" + b"".join(_s15(v) for v in xyz)


def _text_tag(text: str) -> bytes:
    """multiLocalizedUnicodeType with one record, en-US, UTF-16BE."""
    data = text.encode("utf-16-be")
    return b"mluc\x00\x00\x00\x00" + struct.pack(">II", 1, 12) + b"enUS" + struct.pack(">II", len(data), 28) + data


def _curve_tag(parameters) -> bytes:
    return b"para\x00\x00\x00\x00" + struct.pack(">HH", 3, 0) + b"".join(_s15(v) for v in parameters)


def _matrix_tag(matrix: np.ndarray) -> bytes:
    """s15Fixed16ArrayType, row by row (chad)."""
    return b"sf32\x00\x00\x00\x00" + b"".join(_s15(v) for v in np.asarray(matrix).ravel())


def colorants_d50(space: ColourSpace) -> np.ndarray:
    """3x3: columns the connection-space XYZ of the space's red, green and blue (Bradford-adapted to D50)."""
    rgb_to_xyz = np.linalg.inv(xyz_to_rgb_matrix(space))
    chad = adaptation_matrix(output_white_xyz(space), np.array(PCS_D50), Adaptation.BRADFORD)
    return chad @ rgb_to_xyz


@cache
def icc_profile(space: ColourSpace) -> bytes:
    """The ICC profile bytes of an RGB output space (sRGB, Display P3, Rec.2020)."""
    space = ColourSpace(space)
    if space not in _CURVES:
        raise ValueError(f"no ICC profile for {space}")
    chad = adaptation_matrix(output_white_xyz(space), np.array(PCS_D50), Adaptation.BRADFORD)
    colorants = colorants_d50(space)
    curve = _curve_tag(_CURVES[space])
    tags = [
        (b"desc", _text_tag(f"spectrace {_NAMES[space]}")),
        (b"cprt", _text_tag("No copyright, use freely")),
        (b"wtpt", _xyz_tag(PCS_D50)),
        (b"chad", _matrix_tag(chad)),
        (b"rXYZ", _xyz_tag(colorants[:, 0])),
        (b"gXYZ", _xyz_tag(colorants[:, 1])),
        (b"bXYZ", _xyz_tag(colorants[:, 2])),
        (b"rTRC", curve),
        (b"gTRC", curve),
        (b"bTRC", curve),
    ]
    table_size = 4 + 12 * len(tags)
    offset = 128 + table_size
    entries, blobs, placed = [], [], {}
    for signature, data in tags:
        if data not in placed:  # the three curves share one element, as clause 7.3.1 allows
            placed[data] = offset
            padded = data + b"\x00" * (-len(data) % 4)  # every tag element starts on a 4-byte boundary
            blobs.append(padded)
            offset += len(padded)
        entries.append(signature + struct.pack(">II", placed[data], len(data)))
    body = struct.pack(">I", len(tags)) + b"".join(entries) + b"".join(blobs)
    size = 128 + len(body)
    header = (
        struct.pack(">I", size)
        + b"\x00\x00\x00\x00"  # preferred CMM: none
        + bytes([4, 0x40, 0, 0])  # version 4.4
        + b"mntrRGB XYZ "
        + struct.pack(">6H", 2026, 1, 1, 0, 0, 0)  # a fixed date: the same image gives the same file
        + b"acsp"
        + b"\x00" * 4  # primary platform
        + struct.pack(">I", 0)  # flags
        + b"\x00" * 8  # device manufacturer and model
        + b"\x00" * 8  # device attributes
        + struct.pack(">I", 0)  # perceptual rendering intent
        + b"".join(_s15(v) for v in PCS_D50)
        + b"\x00" * 4  # creator
        + b"\x00" * 16  # profile ID: not computed (allowed: all zero)
        + b"\x00" * 28
    )
    assert len(header) == 128
    return header + body
