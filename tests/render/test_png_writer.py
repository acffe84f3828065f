"""The display-image writer's PNGs (Pillow's encoder, with the text and extra chunks spectrace adds): Pillow's
decoder reads back every pixel, every text chunk, and a chunk given by type, and its checks (CRCs, chunk order)
pass."""

import numpy as np
from PIL import Image as PILImage

from spectrace.io.raster import write_display_image as write_png


def test_pillow_reads_back_pixels_and_text(tmp_path):
    rng = np.random.default_rng(7)
    encoded = rng.uniform(-0.2, 1.2, size=(5, 7, 3))  # values outside [0, 1] are clipped
    metadata = {"spp": "16", "scene": "café ☕ scene"}  # Latin-1 and beyond it
    path = tmp_path / "a.png"
    write_png(path, encoded, metadata, png_chunks={b"cICP": bytes([12, 13, 0, 1])})
    expected = np.rint(np.clip(encoded, 0.0, 1.0) * 255).astype(np.uint8)
    with PILImage.open(path) as png:
        png.load()  # verifies every chunk's CRC and the zlib stream
        assert png.mode == "RGB" and png.size == (7, 5)
        assert np.array_equal(np.asarray(png), expected)
        assert png.text["spectrace:spp"] == "16"
        assert png.text["spectrace:scene"] == "café ☕ scene"
    data = path.read_bytes()
    assert data.index(b"cICP") < data.index(b"IDAT")


def test_one_pixel_and_wide_images(tmp_path):
    for shape in ((1, 1, 3), (2, 3000, 3)):
        encoded = np.linspace(0.0, 1.0, int(np.prod(shape))).reshape(shape)
        path = tmp_path / f"{shape[1]}.png"
        write_png(path, encoded, {})
        with PILImage.open(path) as png:
            assert np.array_equal(np.asarray(png), np.rint(encoded * 255).astype(np.uint8))
