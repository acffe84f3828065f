"""The render command's output options beyond the image itself: colour space and white balance of the files
(docs/colour.md), and the false-colour luminance map (spectrace.plots). Parsed before rendering, so a typo fails
at once rather than after a long render."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from spectrace.errors import SpectraceError
from spectrace.film.colour_output import (
    Adaptation,
    ColourSpace,
    WhiteBalance,
    parse_colour_space,
    parse_white_balance,
)
from spectrace.film.image import BIT_DEPTHS, Image, output_format_problem

FalseColourScale = Literal["log", "linear"]
FALSE_COLOUR_SCALES: tuple[FalseColourScale, ...] = ("log", "linear")


@dataclass(frozen=True)
class RenderOutputOptions:
    colour_space: ColourSpace = ColourSpace.SRGB
    white_balance: WhiteBalance | None = None
    false_colour_path: Path | None = None
    false_colour_scale: FalseColourScale = "log"
    bit_depth: int = 8

    @classmethod
    def parse(
        cls,
        output: Path | None,
        colour_space: ColourSpace | str = "srgb",
        white_balance: WhiteBalance | str | None = None,
        adaptation: Adaptation | str = "bradford",
        false_colour: Path | None = None,
        false_colour_scale: str = "log",
        names: tuple[str | None, str | None, str | None] = ("--colour-space", "--white-balance", "--adaptation"),
        bit_depth: int = 8,
        bit_depth_name: str = "--bit-depth",
    ) -> RenderOutputOptions:
        """The options as given on the command line or to spectrace.render (there already parsed or as text);
        `output`: the image file, None for an image kept in memory; `names`: what errors call the colour space,
        the white and the adaptation."""
        space_name, white_name, method_name = names
        space = (
            parse_colour_space(colour_space, space_name) if isinstance(colour_space, str) else ColourSpace(colour_space)
        )
        if output is not None and (problem := output_format_problem(output, 8, space)):
            raise SpectraceError(problem, where=space_name)
        if bit_depth not in BIT_DEPTHS:
            raise SpectraceError(f"must be 8 or 16, got {bit_depth}", where=bit_depth_name)
        if output is not None and bit_depth != 8 and (problem := output_format_problem(output, bit_depth)):
            raise SpectraceError(problem, where=bit_depth_name)
        balance = (
            parse_white_balance(white_balance, adaptation, where=white_name, method_where=method_name)
            if isinstance(white_balance, str)
            else white_balance
        )
        if not white_balance and str(adaptation).strip().lower() != "bradford":
            # reports an unknown adaptation even without a white
            parse_white_balance("D65", adaptation, where=white_name, method_where=method_name)
        if false_colour_scale not in FALSE_COLOUR_SCALES:
            raise SpectraceError(
                f"unknown scale '{false_colour_scale}' (use {' or '.join(FALSE_COLOUR_SCALES)})",
                where="--false-color-scale",
            )
        if false_colour is not None:
            from spectrace.plot_extra import require_matplotlib

            require_matplotlib("--false-color")
        if false_colour is not None and false_colour.suffix.lower() not in (".png", ".pdf", ".svg"):
            raise SpectraceError(
                f"unknown figure format '{false_colour.suffix}' (use .png, .pdf or .svg)", where="--false-color"
            )
        return cls(space, balance, false_colour, false_colour_scale, bit_depth)

    def apply(self, image: Image) -> Image:
        """Set the image's colour space and white balance (its film XYZ is untouched)."""
        image.colour_space = self.colour_space
        image.white_balance = self.white_balance
        image.bit_depth = self.bit_depth
        return image

    def write_false_colour(self, image: Image, log: Callable[[str], None] = print) -> None:
        if self.false_colour_path is None:
            return
        from spectrace.plots import plot_false_colour_luminance

        low, high = plot_false_colour_luminance(image.xyz, self.false_colour_path, scale=self.false_colour_scale)
        log(f"wrote {self.false_colour_path}: luminance, {self.false_colour_scale} scale {low:.4g}..{high:.4g} cd/m²")
