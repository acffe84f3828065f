"""What `spectrace render` writes once its samples are in, whether rendered here or in tiles: the image (with
--denoise, the noisy one beside it first), then the false-colour map."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from spectrace.errors import SpectraceError

if TYPE_CHECKING:
    from spectrace.device import Device
    from spectrace.engine.job import RenderJob
    from spectrace.film.image import Image


def write_image(image: Image, output: Path, include_xyz: bool, state_file: Path | None) -> None:
    """Write `image`; a failure is one line that names the file and, when there is one, the checkpoint that keeps
    the render's samples."""
    try:
        image.write(output, include_xyz=include_xyz)
    except OSError as error:
        kept = f"; the render's state is in {state_file} (continue with --resume)" if state_file else ""
        raise SpectraceError(f"cannot write the image ({error.strerror or error}){kept}", where=str(output)) from None


def write_render(
    job: RenderJob,
    image: Image,
    output: Path,
    *,
    include_xyz: bool,
    state_file: Path | None,
    noisy: Path | None,
    device: Device | str | None,
    log: Callable[[str], None],
) -> Image:
    """Write the render's files and return the image written (the denoised one with `noisy`, where the noisy one
    goes first; its emission pass runs on `device`)."""
    if noisy is not None:
        from spectrace.denoising import denoise_with_emission_pass, noisy_image

        write_image(noisy_image(job.finish(image), output), noisy, include_xyz, state_file)
        image = denoise_with_emission_pass(job.scene, image, device, log=log)
    write_image(job.finish(image), output, include_xyz, state_file)
    job.outputs.write_false_colour(image, log=log)
    return image
