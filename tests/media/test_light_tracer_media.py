"""The light tracer and BDPT in homogeneous media (docs/media.md): light paths start in their light's medium, scatter
in media as the path tracer's camera paths do (free flights, Henyey–Greenstein), and every connection carries the
media's transmittance. Checked against a closed form (a point light inside an absorber), the path tracer on a
scattering scene (region means), and themselves split into passes."""

import math

import numpy as np
import pytest

from replica_agreement import spectrace_replicas
from scene_text import camera_film
from spectrace.engine.renderer import Renderer
from spectrace.interop.mitsuba import load_mitsuba_scene
from spectrace.scene import load_scene

SIGMA_A = 0.8

# A white floor at z = -0.5 and a point light 0.6 to the side, 1 above it, both inside an absorbing index-matched box
# spanning z in [-1, 1]; a camera 5.5 above the floor looking straight down (fov 20°).
POINT_IN_ABSORBER = (
    camera_film(origin="[0, 0, 5]", target="[0, 0, -0.5]", fov="20", width="8", height="8")
    + """
[integrator]
type = "{integrator}"
max_depth = 2

[sampler]
spp = 64

[materials.white]
type = "diffuse"
reflectance = {{ value = 1.0 }}

[[shapes]]
type = "rectangle"
material = "white"
transform = [{{ scale = 1.5 }}, {{ translate = [0, 0, -0.5] }}]

[[shapes]]
type = "cube"
interior = {{ sigma_a = {{ value = {sigma_a} }} }}
transform = [{{ scale = [2, 2, 1] }}]

[[lights]]
type = "point"
position = [0.6, 0, 0.5]
intensity = {{ value = 2.0 }}
"""
)


def _floor_mean(sigma_a: float) -> float:
    """The image mean of the floor's radiance, by midpoint quadrature over the square the camera sees (a film
    parallel to the floor maps pixels to equal floor areas): ρ/π · I cos θ / r² · exp(−σa r) at the floor, times
    exp(−σa · 1.5 / cos α) along the camera ray's 1.5 units of height inside the box."""
    half = 5.5 * math.tan(math.radians(10.0))
    u = (np.arange(400) + 0.5) / 400 * 2 * half - half
    x, y = np.meshgrid(u, u, indexing="ij")
    r = np.sqrt((x - 0.6) ** 2 + y**2 + 1.0)
    at_floor = 2.0 * (1.0 / r) / r**2 * np.exp(-sigma_a * r) / math.pi
    cos_alpha = 5.5 / np.sqrt(5.5**2 + x**2 + y**2)
    return float(np.mean(at_floor * np.exp(-sigma_a * 1.5 / cos_alpha)))


def _replica_means(scene, device, replicas=8, replica_spp=16):
    xyz = spectrace_replicas(Renderer(scene, device), replicas, replica_spp)
    return xyz[..., 1].mean(axis=(1, 2))  # Y of each replica's image mean


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_a_point_light_inside_an_absorber_lights_the_floor_through_it(tmp_path, device, integrator):
    """Image means with σa and without (σa = 0): their ratio is the closed form's, within 5 standard errors. A light
    path starting outside the medium would miss exp(−σa r) on its way to the floor."""
    means = {}
    for sigma_a in (SIGMA_A, 0.0):
        path = tmp_path / f"absorber_{sigma_a}.toml"
        path.write_text(POINT_IN_ABSORBER.format(sigma_a=sigma_a, integrator=integrator))
        means[sigma_a] = _replica_means(load_scene(path), device)
    a, b = means[SIGMA_A], means[0.0]
    ratio = a.mean() / b.mean()
    standard_error = ratio * math.sqrt(a.var(ddof=1) / len(a) / a.mean() ** 2 + b.var(ddof=1) / len(b) / b.mean() ** 2)
    expected = _floor_mean(SIGMA_A) / _floor_mean(0.0)
    assert abs(ratio - expected) <= 5 * standard_error + 1e-4, (ratio, expected, standard_error)
    assert expected < 0.5  # the medium matters


FOG = """<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="6"/></integrator>
<sensor type="perspective"><float name="fov" value="35"/>
  <transform name="to_world"><lookat origin="0, -5, 0.5" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
  <rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  <transform name="to_world"><scale value="0.3"/><translate value="0.5, 0, -0.7"/></transform></shape>
<shape type="cube"><transform name="to_world"><scale value="1.2"/></transform><bsdf type="null"/>
  <medium type="homogeneous" name="interior">
    <float name="sigma_t" value="2.5"/><float name="albedo" value="0.6"/>
    <phase type="hg"><float name="g" value="0.4"/></phase></medium></shape>
<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate value="0, 0, -1.2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf></shape>
<shape type="sphere"><float name="radius" value="0.2"/><transform name="to_world"><translate value="-0.3, 0, 0.3"/>
  </transform><emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter></shape>
</scene>
"""


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_light_paths_and_the_path_tracer_agree_on_a_lamp_in_fog(tmp_path, device, integrator):
    """A lamp and a diffuse ball inside a box of scattering fog (index-matched) over a floor outside: 4 x 4 blocks
    of 4 x 4 pixels and the image mean of the light tracer or BDPT and of the path tracer within 5 standard errors
    of the replicas."""
    path = tmp_path / "fog.xml"
    path.write_text(FOG)
    scene = load_mitsuba_scene(path)
    replicas, replica_spp, block = 8, 32, 4
    ours = {
        kind: spectrace_replicas(Renderer(scene.with_overrides(integrator=kind), device), replicas, replica_spp)
        for kind in (integrator, "path")
    }
    n = 16 // block
    for reduce in (
        lambda images: images.reshape(replicas, n, block, n, block, 3).mean(axis=(2, 4)),
        lambda images: images.mean(axis=(1, 2)),
    ):
        a, b = reduce(ours[integrator]), reduce(ours["path"])
        difference = a.mean(axis=0) - b.mean(axis=0)
        standard_error = np.sqrt(a.var(axis=0, ddof=1) / replicas + b.var(axis=0, ddof=1) / replicas)
        assert np.all(np.abs(difference) <= 5 * standard_error), np.max(np.abs(difference) / standard_error)
    assert np.all(ours["path"].mean(axis=(0, 1, 2)) > 0.01)  # the lamp lights the scene through the fog


@pytest.mark.parametrize("integrator", ["light", "bdpt"])
def test_a_light_traced_medium_keeps_its_bits_however_split(tmp_path, device, integrator):
    path = tmp_path / "fog.xml"
    path.write_text(FOG)
    scene = load_mitsuba_scene(path).with_overrides(integrator=integrator)
    whole = Renderer(scene, device)
    whole.render(spp=8)
    split = Renderer(scene, device)
    split.render(spp=8, pass_spp=3)
    assert np.array_equal(whole.image().xyz, split.image().xyz)


# The fog box lit from outside by a sky (constant environment) and a sun (distant light): lights at infinity, whose
# BDPT subpaths start outside the scene and whose joins carry the transmittance to infinity through the fog.
FOG_UNDER_SKY = FOG.replace(
    "</scene>",
    '<emitter type="constant"><rgb name="radiance" value="0.3, 0.3, 0.3"/></emitter>\n'
    '<emitter type="directional"><vector name="direction" value="0.3, 0.4, -1"/>'
    '<rgb name="irradiance" value="2, 2, 2"/></emitter>\n</scene>',
)


def test_bdpt_and_the_path_tracer_agree_on_fog_under_a_sky_and_a_sun(tmp_path, device):
    """The fog scene with a constant environment and a distant light added: BDPT's and the path tracer's 4 x 4 blocks
    of 4 x 4 pixels and image means within 5 standard errors of the replicas. A join to a light at infinity that
    skipped the fog's transmittance, or an environment vertex inside the fog without the flight's weight, would be
    too bright."""
    path = tmp_path / "fog_sky.xml"
    path.write_text(FOG_UNDER_SKY)
    scene = load_mitsuba_scene(path)
    replicas, replica_spp, block = 8, 16, 4
    ours = {
        kind: spectrace_replicas(Renderer(scene.with_overrides(integrator=kind), device), replicas, replica_spp)
        for kind in ("bdpt", "path")
    }
    n = 16 // block
    for reduce in (
        lambda images: images.reshape(replicas, n, block, n, block, 3).mean(axis=(2, 4)),
        lambda images: images.mean(axis=(1, 2)),
    ):
        a, b = reduce(ours["bdpt"]), reduce(ours["path"])
        difference = a.mean(axis=0) - b.mean(axis=0)
        standard_error = np.sqrt(a.var(axis=0, ddof=1) / replicas + b.var(axis=0, ddof=1) / replicas)
        assert np.all(np.abs(difference) <= 5 * standard_error), np.max(np.abs(difference) / standard_error)
