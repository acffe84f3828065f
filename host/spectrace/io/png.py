"""PNG output: 8-bit sRGB (transfer curve applied, values clipped to [0, 1]) with metadata as text chunks."""

from pathlib import Path

import numpy as np
from PIL import Image as PILImage
from PIL.PngImagePlugin import PngInfo

from spectrace.io.atomic import write_atomically


def write_png(
    path: Path, encoded_srgb: np.ndarray, metadata: dict[str, str], chunks: dict[bytes, bytes] | None = None
) -> None:
    """chunks: extra PNG chunks by type (e.g. b"cICP" naming a colour space other than sRGB), before the pixels."""
    pixels = np.clip(np.rint(np.clip(encoded_srgb, 0.0, 1.0) * 255.0), 0, 255).astype(np.uint8)
    info = PngInfo()
    for chunk_type, payload in (chunks or {}).items():
        info.add(chunk_type, payload)
    for key, value in metadata.items():
        info.add_text(f"spectrace:{key}", str(value))
    write_atomically(path, lambda temp: PILImage.fromarray(pixels, "RGB").save(temp, format="PNG", pnginfo=info))
