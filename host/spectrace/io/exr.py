"""OpenEXR output: linear sRGB as 32-bit float R, G, B, optionally the film's X, Y, Z, plus render metadata."""

from pathlib import Path

import numpy as np
import OpenEXR

from spectrace.io.atomic import write_atomically


def write_exr(path: Path, linear_srgb: np.ndarray, xyz: np.ndarray | None, metadata: dict[str, str]) -> None:
    channels = {"RGB": np.ascontiguousarray(linear_srgb, dtype=np.float32)}
    if xyz is not None:
        for i, name in enumerate("XYZ"):
            channels[name] = np.ascontiguousarray(xyz[..., i], dtype=np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({f"spectrace:{k}": str(v) for k, v in metadata.items()})

    def write(temp: Path) -> None:
        with OpenEXR.File(header, channels) as exr:
            exr.write(str(temp))

    write_atomically(path, write)


def read_exr(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    """Channels (RGB as one (H, W, 3) array, others (H, W)) and the header."""
    with OpenEXR.File(str(path)) as exr:
        channels = {name: np.array(ch.pixels) for name, ch in exr.channels().items()}
        return channels, dict(exr.header())
