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
    rendered = image
    if noisy is not None:
        from spectrace.denoising import denoise_with_emission_pass, noisy_image

        write_image(noisy_image(job.finish(image), output), noisy, include_xyz, state_file)
        image = denoise_with_emission_pass(job.scene, image, device, log=log)
    write_image(job.finish(image), output, include_xyz, state_file)
    job.outputs.write_false_colour(image, log=log)
    write_delta_e_map(job, rendered, output, log)
    return image


def delta_e_map_path(output: Path) -> Path:
    """Where `--delta-e-map` writes its false-colour picture: `<stem>.deltaE00.png` beside the EXR."""
    return output.with_name(f"{output.stem}.deltaE00.png")


def write_delta_e_map(job: RenderJob, image: Image, output: Path, log: Callable[[str], None]) -> None:
    """The image's ΔE map (the film response's pair of observers), if it has one, as a false-colour picture."""
    from spectrace.film.response import DELTA_E_CHANNEL, observer_xyz_image, scene_white_y

    response = job.scene.film_response
    if DELTA_E_CHANNEL not in image.channels or response.delta_e_pair is None:
        return
    import numpy as np

    from spectrace.plots import plot_delta_e_map

    first, second = response.delta_e_pair
    white = response.delta_e_white_y or scene_white_y(observer_xyz_image(image.channels, first)[..., 1])
    delta_e = image.channels[DELTA_E_CHANNEL]
    mean = float(np.nanmean(delta_e))
    path = delta_e_map_path(output)
    title = f"CIEDE2000, {first} vs {second}: mean {mean:.3g}; white Y_n = {white:.4g}"
    low, high = plot_delta_e_map(delta_e, path, title)
    log(f"wrote {path}: ΔE2000 map, mean {mean:.3g}, scale {low:g}..{high:.3g}, white Y_n = {white:.4g}")
