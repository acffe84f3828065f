"""An RGB bitmap where Mitsuba 3 reads one number per point (a bumpmap's heights, a mask's opacity, an α): Mitsuba
takes its luminance, so the importer gives that texture `luminance = true`. Checked against the published luminance
weights, and rendered against Mitsuba 3's own image of a bump-mapped panel whose three channels hold different
heights, each renderer compared with itself."""

import numpy as np
import pytest
from PIL import Image

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data
from spectrace.spectral import xyz_to_linear_srgb
from spectrace.textures.bitmap import make as bitmap

SIZE = 32


def _heights(path, channels: str = "rgb") -> None:
    """A raw 16 x 16 8-bit image: red ramps along u, green along v, blue is a checker; `channels` "r" writes the
    red channel alone as a grey image."""
    u, v = np.meshgrid(np.arange(16), np.arange(16))
    rgb = np.stack([u * 16, v * 16, ((u // 4 + v // 4) % 2) * 255], axis=-1).astype(np.uint8)
    Image.fromarray(rgb if channels == "rgb" else rgb[..., 0]).save(path)


def _xml(folder, image: str = "heights.png"):
    path = folder / f"bump_{image}.xml"
    path.write_text(
        f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{SIZE}"/><integer name="height" value="{SIZE}"/>
      <rfilter type="box"/></film></sensor>
  <shape type="rectangle">
    <bsdf type="bumpmap"><texture type="bitmap" name="h"><string name="filename" value="{image}"/>
      <boolean name="raw" value="true"/><string name="filter_type" value="bilinear"/></texture>
      <float name="scale" value="0.4"/>
      <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf></bsdf>
  </shape>
  <emitter type="directional"><vector name="direction" x="-1" y="-0.4" z="-0.5"/><rgb name="irradiance" value="3"/>
  </emitter>
</scene>"""
    )
    return path


def test_luminance_weights_are_the_srgb_y_row():
    """IEC 61966-2-1's Y row: 0.2126, 0.7152, 0.0722 (to four places, within rounding), summing to 1 (white stays
    white)."""
    for rgb, expected in (((1, 0, 0), 0.2126), ((0, 1, 0), 0.7152), ((0, 0, 1), 0.0722), ((1, 1, 1), 1.0)):
        texture = bitmap(np.full((1, 1, 3), rgb, np.float64), luminance=True)
        assert texture.channels == 1
        assert float(texture.values[0, 0, 0]) == pytest.approx(expected, abs=1e-4)
    grey = np.array([[0.25, 0.5]])
    np.testing.assert_array_equal(bitmap(grey, luminance=True).values[..., 0], grey.astype(np.float32))


def test_an_rgb_bump_map_imports_as_its_luminance(tmp_path):
    _heights(tmp_path / "heights.png")
    data, _ = mitsuba_scene_data(_xml(tmp_path))
    material = data["materials"][data["shapes"][0]["material"]]
    texture = data["textures"][material["bump_map"]["texture"]]
    assert texture["luminance"] is True and len(data["textures"]) == 1
    detail = load_mitsuba_scene(_xml(tmp_path)).shapes[0].material.detail
    assert detail.bump_map.channels == 1
    _heights(tmp_path / "red.png", "r")
    data, _ = mitsuba_scene_data(_xml(tmp_path, "red.png"))
    assert all("luminance" not in t for t in data["textures"].values())  # a grey image as it is


@pytest.mark.peer
@pytest.mark.slow
def test_mitsuba_reads_an_rgb_bump_map_as_its_luminance(tmp_path, device, mitsuba_scalar_spectral):
    """8 independent images each: 8 x 8-pixel block means and the image mean within 5 standard errors. Mitsuba's
    image of the RGB heights is its image of their luminance written as a grey image (and not that of the red channel
    alone); spectrace's import of the RGB heights renders as its import of that grey image. (The two renderers'
    images of this steep bump map differ from each other: the comparison is each with itself.)"""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, block = 8, 4, 8
    _heights(tmp_path / "heights.png")
    _heights(tmp_path / "red.png", "r")
    rgb = np.asarray(Image.open(tmp_path / "heights.png"), np.float64)
    grey = np.round(rgb @ np.array([0.212671, 0.715160, 0.072169])).astype(np.uint8)
    Image.fromarray(grey).save(tmp_path / "luminance.png")

    def theirs(image: str) -> np.ndarray:
        scene = mi.load_file(str(_xml(tmp_path, image)))
        return np.stack([np.array(mi.render(scene, spp=replica_spp, seed=seed)) for seed in range(replicas)])

    def ours(image: str) -> np.ndarray:
        renderer = Renderer(load_mitsuba_scene(_xml(tmp_path, image)), device)
        return xyz_to_linear_srgb(spectrace_replicas(renderer, replicas, replica_spp))

    by_mitsuba = theirs("heights.png")
    assert_replicas_agree(theirs("luminance.png"), by_mitsuba, block)
    with pytest.raises(AssertionError):
        assert_replicas_agree(theirs("red.png"), by_mitsuba, block)
    assert_replicas_agree(ours("heights.png"), ours("luminance.png"), block)
