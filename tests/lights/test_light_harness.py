"""Every light type, run on the device through kernels/testing/lights.cl, checked against its own sampler and its
closed form, as tests/materials/test_bsdfs.py checks the BSDFs:
- the pdf a BSDF-sampled ray that reaches the light is given (what the path tracer's MIS weight uses) equals the pdf
  next-event estimation returned for the same direction, and it integrates to 1 over the directions toward the light;
- the directions next-event estimation draws follow that pdf (chi-square over a binning of directions);
- what arrives is each type's closed form: I/d² for a point light, I·falloff(θ)/d² for a spot across its whole
  transition (the documented smoothstep in cos θ, or linear in θ, written here from its definition), E for a distant
  light, the radiance of the texel a direction falls in for an environment map, L on an area light's emitting side;
- the first rays of light paths (light tracing, BDPT) carry on average the light's flux, from its definition.

Cases are listed by the light registry's names (spectrace.lights.LIGHTS, plus `area` on meshes and on every analytic
shape, with and without an emission texture); a registered light without cases fails. Random numbers come from fixed
seeds; tolerances from each estimator's standard error."""

from dataclasses import dataclass, field

import numpy as np
import pytest

import spectrace
from spectrace.engine.renderer import upload_scene
from spectrace.engine.scene_buffers import build_scene_buffers, render_params
from spectrace.geometry.analytic import ANALYTIC_SHAPES
from spectrace.geometry.bvh4 import traversal_defines
from spectrace.lights import LIGHTS
from spectrace.lights.goniometric import GoniometricLight
from spectrace.lights.projector import ProjectorLight
from spectrace.scene.model import (
    Camera,
    ConstantEnvironment,
    DiffuseMaterial,
    DistantLight,
    EnvironmentMap,
    PointLight,
    Scene,
    SpotLight,
)
from spectrace.spectral.grid import GRID_NM
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.uplift import uplift_illuminant
from spectrace.textures import bitmap, spectral
from stats_toolkit import assert_chi_square_fits, assert_within_standard_errors, mean_and_standard_error

HARNESS = "testing/lights.cl"
LAMBDA_NM = np.array([420.0, 510.0, 600.0, 690.0], np.float32)  # whole nanometres: grid points of the table
CAMERA = Camera(origin=(0.0, 0.0, 10.0), target=(0.0, 0.0, 0.0))
GREY = DiffuseMaterial(Spectrum.constant(0.5))


def _at(spectrum: Spectrum) -> np.ndarray:
    return np.interp(LAMBDA_NM, GRID_NM, spectrum.values)


def _basis() -> np.ndarray:
    """(3, 4): the emission spectra an RGB texel weights (docs/textures.md), at LAMBDA_NM."""
    return np.array([_at(uplift_illuminant(primary)) for primary in np.eye(3)])


def _unit(v) -> np.ndarray:
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _float4(vectors: np.ndarray) -> np.ndarray:
    out = np.zeros((len(vectors), 4), np.float32)
    out[:, :3] = vectors
    return out


def _frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    axis = _unit(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = _unit(np.cross(helper, axis))
    return x, np.cross(axis, x), axis


# ---------------------------------------------------------------- the cases


@dataclass
class Case:
    """A scene whose only emitter is the light under test, the points it is seen from, and what arrives."""

    id: str
    scene: Scene
    points: list[tuple[float, float, float]]
    delta: bool
    # For the chi-square and the pdf's integral: the directions from points[0] that can reach the light, a cone about
    # `axis` of cos θ >= cos_min (-1: the whole sphere).
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    cos_min: float = -1.0
    # The radiance (W/(m² sr nm)) or, for a delta light, irradiance (W/(m² nm)) arriving at `p` from direction `wi`
    # from the light point `q` (each (n, 3)), at LAMBDA_NM: (n, 4).
    arriving: object = None
    # Non-delta lights whose sample must carry no light (a one-sided emitter seen from behind) from these points.
    dark_points: list[tuple[float, float, float]] = field(default_factory=list)
    # The quadrature grid of the pdf's integral (cos θ, φ cells): finer for a map, whose texel edges are steps.
    grid: tuple[int, int] = (256, 512)


def _scene(shapes=(), lights=()) -> Scene:
    return Scene(camera=CAMERA, width=1, height=1, shapes=list(shapes), lights=list(lights))


def _cone_toward(centre, radius, point) -> tuple[tuple[float, float, float], float]:
    """The cone from `point` holding a sphere (centre, radius), widened a little for tessellations and rounding."""
    offset = np.subtract(centre, point)
    distance = np.linalg.norm(offset)
    half_angle = np.arcsin(min(1.0, 1.05 * radius / distance)) * 1.02
    return tuple(offset / distance), float(np.cos(half_angle))


def _point_case() -> Case:
    position = np.array([0.3, 1.5, -0.2])
    light = spectrace.point_light(tuple(position), intensity="cie:A")

    def arriving(p, wi, q):
        d2 = np.sum((position - p) ** 2, axis=1, keepdims=True)
        return _at(light.intensity)[None, :] / d2

    return Case("point", _scene(lights=[light]), [(0, 0, 0), (1.0, -0.5, 2.0)], True, arriving=arriving)


def _spot_case() -> Case:
    position = np.array([0.0, 2.0, 0.0])
    light = spectrace.spot_light(tuple(position), (0.0, 0.0, 0.0), 40.0, 15.0, intensity="cie:D65")

    def arriving(p, wi, q):
        to_p = p - position
        d2 = np.sum(to_p**2, axis=1, keepdims=True)
        theta = np.arccos(np.clip(_unit(to_p) @ [0.0, -1.0, 0.0], -1.0, 1.0))
        falloff = _smoothstep_profile(theta, np.radians(15.0), np.radians(40.0))
        return _at(light.intensity)[None, :] * falloff[:, None] / d2

    # From the axis, inside the falloff start, and two points within the transition.
    points = [(0, 0, 0), (0.3, 0.0, 0.2), (1.2, 0.0, 0.3), (0.0, 0.5, -1.1)]
    return Case("spot", _scene(lights=[light]), points, True, arriving=arriving)


def _projector_case(profile: str) -> Case:
    """A white projector looking down −y, 60° across a 3:2 field: I = I₀/cos³θ (irradiance profile, Mitsuba 3's) or
    I₀ (intensity profile, pbrt-v4's) within the field (docs/scene-format.md)."""
    position, axis = np.array([0.0, 2.0, 0.0]), np.array([0.0, -1.0, 0.0])
    light = spectrace.projector_light(
        tuple(position), (0.0, 0.0, 0.0), 60.0, intensity="cie:D65", up=(0.0, 0.0, -1.0), aspect=1.5, profile=profile
    )

    def arriving(p, wi, q):
        to_p = p - position
        d2 = np.sum(to_p**2, axis=1, keepdims=True)
        cos_theta = (_unit(to_p) @ axis)[:, None]
        shape = 1.0 / cos_theta**3 if profile == "irradiance" else 1.0
        return _at(light.intensity)[None, :] * shape / d2

    # The field's half-widths at the origin's depth are 2 tan 30° and that over 1.5: every point lies inside.
    points = [(0, 0, 0), (0.3, 0.0, 0.2), (1.0, 0.0, -0.6), (-0.4, 0.5, 0.3)]
    return Case(f"projector-{profile}", _scene(lights=[light]), points, True, arriving=arriving)


# A goniometric light's image: 8 x 8 texels of an equal-area map, random values, a bright one at [2, 5].
GONIO_IMAGE = np.random.default_rng(9).uniform(0.2, 1.5, (8, 8))
GONIO_IMAGE[2, 5] = 6.0


def _goniometric_case(mirrored: bool) -> Case:
    """A goniometric light at (0.3, 1.0, −0.2), its map's pole along (0.2, 1, 0.1), its v axis toward +x (turned
    round when mirrored): I(ω) = I₀·image[texel of the equal-area square at ω in that frame] / d², the map written
    here from Clarberg's paper (tests/cameras/test_equal_area_camera.py)."""
    from tests.cameras.test_equal_area_camera import sphere_to_square

    position, up, front = np.array([0.3, 1.0, -0.2]), np.array([0.2, 1.0, 0.1]), np.array([1.0, 0.0, 0.0])
    light = spectrace.goniometric_light(
        tuple(position), "cie:D65", image=GONIO_IMAGE, up=tuple(up), front=tuple(front), mirrored=mirrored
    )
    z = _unit(up)
    y = _unit(front - (front @ z) * z)
    x = np.cross(y, z)
    y = -y if mirrored else y

    def arriving(p, wi, q):
        d = _unit(p - position)
        uv = sphere_to_square(np.stack([d @ x, d @ y, d @ z], axis=1))
        n = GONIO_IMAGE.shape[0]
        texel = GONIO_IMAGE[
            np.clip((uv[:, 1] * n).astype(int), 0, n - 1), np.clip((uv[:, 0] * n).astype(int), 0, n - 1)
        ]
        d2 = np.sum((p - position) ** 2, axis=1, keepdims=True)
        return _at(light.intensity)[None, :] * texel[:, None] / d2

    rng = np.random.default_rng(4 + mirrored)
    points = [tuple(position + 1.5 * _unit(v)) for v in rng.normal(size=(24, 3))]
    return Case(
        f"goniometric{'-mirrored' if mirrored else ''}", _scene(lights=[light]), points, True, arriving=arriving
    )


def _projector_flux_factor(tan_x: float, tan_y: float, profile: str) -> float:
    """∫ I/I₀ dω over the field, by the midpoint rule on the plane z = 1 (dω = cos³θ dA): the image's area for the
    irradiance profile, the field's solid angle for the intensity profile."""
    n = 2000
    x = (np.arange(n) + 0.5) / n * 2.0 * tan_x - tan_x
    y = (np.arange(n) + 0.5) / n * 2.0 * tan_y - tan_y
    cos3 = (1.0 + x[:, None] ** 2 + y[None, :] ** 2) ** -1.5
    shape = np.ones_like(cos3) if profile == "irradiance" else cos3
    return float(shape.sum() * (2.0 * tan_x / n) * (2.0 * tan_y / n))


def _distant_case() -> Case:
    light = spectrace.distant_light((0.2, -1.0, 0.3), "cie:D65")
    return Case(
        "distant",
        _scene(lights=[light]),
        [(0, 0, 0), (3.0, 1.0, -2.0)],
        True,
        arriving=lambda p, wi, q: np.broadcast_to(_at(light.irradiance), (len(p), 4)),
    )


def _constant_case() -> Case:
    light = spectrace.constant_environment("cie:D65")
    return Case(
        "constant",
        _scene(lights=[light]),
        [(0, 0, 0)],
        False,
        axis=(0.0, 1.0, 0.0),
        arriving=lambda p, wi, q: np.broadcast_to(_at(light.radiance), (len(p), 4)),
    )


def _map_rgb() -> np.ndarray:
    rng = np.random.default_rng(5)
    rgb = rng.uniform(0.0, 0.4, (8, 16, 3))
    rgb[1, 3] = (30.0, 20.0, 8.0)  # a small bright sun the sampler must find
    rgb[6, 11] = (0.0, 4.0, 9.0)
    rgb[4, :5] = 0.0  # a black stretch no direction may be drawn toward
    return rgb


def _envmap_case(case_id: str, up=(0.0, 1.0, 0.0), front=(0.0, 0.0, -1.0)) -> Case:
    rgb, scale = _map_rgb(), 0.7
    light = EnvironmentMap(rgb.astype(np.float32), scale, up, front)

    def arriving(p, wi, q):
        """docs/scene-format.md: `up` is the image's zenith, `front` its centre; θ from up, row θ/π, column
        (φ + π)/2π with φ = 0 toward front, growing toward front × up's side (+x for the default frame)."""
        y = _unit(up)
        z = -_unit(np.asarray(front) - np.dot(front, y) * y)  # the map's -z is front
        x = np.cross(y, z)
        theta = np.arccos(np.clip(wi @ y, -1.0, 1.0))
        phi = np.arctan2(wi @ x, -(wi @ z))
        row = np.clip((theta / np.pi * rgb.shape[0]).astype(int), 0, rgb.shape[0] - 1)
        column = np.clip(((phi + np.pi) / (2 * np.pi) * rgb.shape[1]).astype(int), 0, rgb.shape[1] - 1)
        return scale * rgb[row, column] @ _basis()

    return Case(
        case_id, _scene(lights=[light]), [(0, 0, 0)], False, axis=(0.0, 1.0, 0.0), arriving=arriving, grid=(1024, 2048)
    )


def _area_arriving(radiance: Spectrum, front, two_sided: bool):
    """L on the emitting side (the side `front(q)` faces, at the light point q), 0 behind unless two-sided."""

    def arriving(p, wi, q):
        facing = np.einsum("ij,ij->i", front(q), p - q) > 0
        lit = np.ones(len(p), bool) if two_sided else facing
        return np.where(lit[:, None], _at(radiance)[None, :], 0.0)

    return arriving


def _area_cases() -> list[Case]:
    radiance = spectrace.area_emitter("cie:D65").radiance
    cases = []
    # A rectangle [-1, 1]² facing +z, moved to z = 1 and turned a little: two triangles, two Light rows.
    steps = [{"rotate": {"axis": [1, 0, 0], "angle": 20}}, {"translate": [0.2, 0.0, 1.0]}]
    normal = _unit([0.0, -np.sin(np.radians(20)), np.cos(np.radians(20))])
    centre = np.array([0.2, 0.0, 1.0])
    for two_sided in (False, True):
        emitter = spectrace.area_emitter(radiance, two_sided=two_sided)
        shape = spectrace.shape("rectangle", GREY, emitter, transform=steps)
        p0 = (0.1, -0.3, 3.0)
        axis, cos_min = _cone_toward(centre, np.sqrt(2.0), p0)
        cases.append(
            Case(
                f"area-rectangle-{'two' if two_sided else 'one'}-sided",
                _scene([shape]),
                [p0, (-0.8, 0.6, 2.2)],
                False,
                axis,
                cos_min,
                _area_arriving(radiance, lambda q: np.broadcast_to(normal, q.shape), two_sided),
                [] if two_sided else [(0.0, 0.2, -1.0)],
            )
        )
    for kind in ANALYTIC_SHAPES:
        emitter = spectrace.area_emitter(radiance, two_sided=kind == "cylinder")
        if kind == "sphere":
            centre, r = np.array([0.0, 0.5, 0.0]), 0.6
            shape = spectrace.shape("sphere", GREY, emitter, center=tuple(centre), radius=r)
            p0 = (0.4, 1.1, 3.0)
            axis, cos_min = _cone_toward(centre, r, p0)

            def outward(q, centre=centre):
                return _unit(q - centre)

            cases.append(
                Case(
                    "area-sphere-outside",
                    _scene([shape]),
                    [p0, (-2.0, 0.0, 0.5)],
                    False,
                    axis,
                    cos_min,
                    _area_arriving(radiance, outward, False),
                )
            )
            inner = spectrace.shape("sphere", GREY, emitter, center=tuple(centre), radius=r, flip_normals=True)
            cases.append(
                Case(
                    "area-sphere-inside",
                    _scene([inner]),
                    [(0.1, 0.6, 0.2), (-0.2, 0.3, -0.1)],
                    False,
                    arriving=_area_arriving(radiance, lambda q, centre=centre: -outward(q, centre), False),
                )
            )
        elif kind == "disk":
            shape = spectrace.shape("disk", GREY, emitter, transform=[{"translate": [0.0, 0.0, 1.0]}])
            p0 = (0.3, 0.2, 2.5)
            axis, cos_min = _cone_toward((0.0, 0.0, 1.0), 1.0, p0)
            cases.append(
                Case(
                    "area-disk",
                    _scene([shape]),
                    [p0, (-1.5, 0.4, 1.6)],
                    False,
                    axis,
                    cos_min,
                    _area_arriving(radiance, lambda q: np.broadcast_to([0.0, 0.0, 1.0], q.shape), False),
                    [(0.0, 0.0, 0.0)],
                )
            )
        elif kind == "cylinder":
            # Seen from inside, where every direction meets the open tube at most once; two-sided to be lit there.
            shape = spectrace.shape("cylinder", GREY, emitter, transform=[{"scale": [1.0, 1.0, 3.0]}])
            cases.append(
                Case(
                    f"area-{kind}-inside",
                    _scene([shape]),
                    [(0.1, -0.2, 1.5), (0.4, 0.3, 1.0)],
                    False,
                    arriving=_area_arriving(radiance, lambda q: _unit(q * [1.0, 1.0, 0.0]), True),
                )
            )
        else:
            cases.append(Case(f"area-{kind}-missing", _scene(), [], False))
    return cases + _partial_area_cases(radiance)


def _partial_area_cases(radiance) -> list[Case]:
    """Partial shapes (kernels/shape_partial.cl), each seen from where a direction meets it at most once: an annulus
    sector from above its front, a cut sphere and a cut cylinder from inside. Some of the points lie beyond a cut,
    where only parts of the surface are seen."""
    one_sided, two_sided = spectrace.area_emitter(radiance), spectrace.area_emitter(radiance, two_sided=True)
    disk = spectrace.shape(
        "disk", GREY, one_sided, transform=[{"translate": [0.0, 0.0, 1.0]}], phi_max=270.0, inner_radius=0.4
    )
    p0 = (0.3, 0.2, 2.5)
    # A bounding cone about a point off the hole's centre: its edge then lies where the quadrature's cells are
    # small (near the cone's axis a cell of uniform cos θ spans many degrees).
    axis, cos_min = _cone_toward((-0.6, 0.0, 1.0), 1.6, p0)
    up = _area_arriving(radiance, lambda q: np.broadcast_to([0.0, 0.0, 1.0], q.shape), False)
    centre = np.array([0.0, 0.5, 0.0])
    sphere = spectrace.shape(
        "sphere",
        GREY,
        one_sided,
        center=tuple(centre),
        radius=0.6,
        flip_normals=True,
        phi_max=200.0,
        z_min=-0.3,
        z_max=0.5,
    )
    inward = _area_arriving(radiance, lambda q: _unit(centre - q), False)
    cylinder = spectrace.shape("cylinder", GREY, two_sided, transform=[{"scale": [1.0, 1.0, 3.0]}], phi_max=150.0)
    radial = _area_arriving(radiance, lambda q: _unit(q * [1.0, 1.0, 0.0]), True)
    return [
        Case("area-partialdisk", _scene([disk]), [p0, (-1.5, 0.4, 1.6)], False, axis, cos_min, up, [(0.0, 0.0, 0.0)]),
        Case(
            "area-partialsphere-inside", _scene([sphere]), [(0.1, 0.6, 0.2), (-0.2, 0.3, -0.1)], False, arriving=inward
        ),
        Case(
            "area-partialcylinder-inside",
            _scene([cylinder]),
            [(0.1, -0.2, 1.5), (0.4, 0.3, 1.0)],
            False,
            arriving=radial,
        ),
    ]


# Two texels: the left half of the image bright red-ish, the right half blue-ish; seen through nearest lookups, every
# point of the light shows one of the two.
TEXELS = np.array([[[4.0, 1.0, 0.2], [0.3, 0.8, 3.0]]])
BANDS_NM = np.array([400.0, 550.0, 700.0])
BAND_TEXELS = np.array([[[1.0, 3.0, 0.5], [2.5, 0.2, 1.5]]])
BAND_VALUES = np.array([np.interp(LAMBDA_NM, BANDS_NM, texel) for texel in BAND_TEXELS[0]])  # (2, 4)


def _textured_cases() -> list[Case]:
    cases = []
    steps = [{"translate": [0.0, 0.0, 1.0]}]
    p0 = (0.2, -0.1, 3.0)
    axis, cos_min = _cone_toward((0.0, 0.0, 1.0), np.sqrt(2.0), p0)
    image = bitmap.make(TEXELS, filter="nearest")
    rgb_values = TEXELS[0] @ _basis()  # (2, 4)
    bands = spectral.make(BAND_TEXELS, BANDS_NM, filter="nearest")
    band_values = BAND_VALUES
    for name, texture, values in (("bitmap", image, rgb_values), ("spectral", bands, band_values)):
        shape = spectrace.shape("rectangle", GREY, spectrace.area_emitter(texture, scale=0.5), transform=steps)

        def arriving(p, wi, q, values=values):
            """One of the two texels' radiance, times the scale (which one: the test matches each to its nearest)."""
            return 0.5 * values

        cases.append(
            Case(f"area-textured-{name}", _scene([shape]), [p0, (0.7, 0.5, 2.0)], False, axis, cos_min, arriving)
        )
    return cases


CASES: dict[str, list[Case]] = {
    "point": [_point_case()],
    "spot": [_spot_case()],
    "projector": [_projector_case("irradiance"), _projector_case("intensity")],
    "goniometric": [_goniometric_case(False), _goniometric_case(True)],
    "distant": [_distant_case()],
    "constant": [_constant_case()],
    "envmap": [_envmap_case("envmap"), _envmap_case("envmap-turned", up=(0.3, 0.9, 0.2), front=(1.0, 0.0, 0.4))],
    "area": [*_area_cases(), *_textured_cases()],
}
EVERY = [case for name in (*LIGHTS, "area") for case in CASES.get(name, ())]
NON_DELTA = [case for case in EVERY if not case.delta]


def test_every_registered_light_and_every_analytic_emitter_has_cases():
    assert set(CASES) == {*LIGHTS, "area"}
    assert all(CASES[name] for name in CASES)
    assert not [case.id for case in EVERY if case.id.endswith("-missing")]


# ---------------------------------------------------------------- the device


class Lights:
    """One scene's lights on the device."""

    def __init__(self, runner, scene: Scene):
        self.runner = runner
        self.buffers = build_scene_buffers(scene)
        self.scene_args = [
            runner.buffer(render_params(scene, self.buffers, 0, 1)),
            *upload_scene(runner.device.context, self.buffers),
        ]
        self.lam = runner.buffer(LAMBDA_NM)

    def sample(self, points, n: int, seed: int) -> dict:
        """n samples from one point (3,) or from each of n points (n, 3)."""
        points = np.broadcast_to(np.asarray(points, np.float64), (n, 3))
        u = np.random.default_rng(seed).random((n, 2), dtype=np.float32)
        wi_pdf, target, arriving = (np.zeros((n, 4), np.float32) for _ in range(3))
        flags = np.zeros(n, np.int32)
        args = [
            *self.scene_args,
            self.lam,
            self.runner.buffer(_float4(points)),
            self.runner.buffer(u),
            self.runner.buffer(wi_pdf, True),
            self.runner.buffer(target, True),
            self.runner.buffer(arriving, True),
            self.runner.buffer(flags, True),
            np.int32(n),
        ]
        first = len(self.scene_args) + 3
        outputs = {first: wi_pdf, first + 1: target, first + 2: arriving, first + 3: flags}
        self.runner.run("light_samples", n, args, outputs)
        return {
            "p": np.array(points),
            "wi": wi_pdf[:, :3].astype(np.float64),
            "pdf": wi_pdf[:, 3].astype(np.float64),
            "q": target[:, :3].astype(np.float64),
            "distance": target[:, 3].astype(np.float64),
            "arriving": arriving.astype(np.float64),
            "ok": (flags & 1) > 0,
            "delta": (flags & 2) > 0,
        }

    def hits(self, origins: np.ndarray, directions: np.ndarray) -> dict:
        n = len(directions)
        origins = np.broadcast_to(np.asarray(origins, np.float64), (n, 3))
        pdf, t = np.zeros(n, np.float32), np.zeros(n, np.float32)
        emitted = np.zeros((n, 4), np.float32)
        light = np.zeros(n, np.int32)
        args = [
            *self.scene_args,
            self.lam,
            self.runner.buffer(_float4(origins)),
            self.runner.buffer(_float4(directions)),
            self.runner.buffer(pdf, True),
            self.runner.buffer(emitted, True),
            self.runner.buffer(light, True),
            self.runner.buffer(t, True),
            np.int32(n),
        ]
        first = len(self.scene_args) + 3
        self.runner.run("light_hits", n, args, {first: pdf, first + 1: emitted, first + 2: light, first + 3: t})
        return {"pdf": pdf.astype(np.float64), "emitted": emitted.astype(np.float64), "light": light, "t": t}

    def emit(self, n: int, seed: int, radius: float) -> np.ndarray:
        """The flux (W/nm) each of n first rays of light paths carries; distant and environment lights shine
        across a sphere of `radius` about the origin."""
        u = np.random.default_rng(seed).random((n, 4), dtype=np.float32)
        weight = np.zeros((n, 4), np.float32)
        sphere = np.array([0.0, 0.0, 0.0, radius], np.float32)
        args = [
            *self.scene_args,
            self.lam,
            sphere,
            self.runner.buffer(u),
            self.runner.buffer(weight, True),
            np.int32(n),
        ]
        self.runner.run("light_emissions", n, args, {len(self.scene_args) + 3: weight})
        return weight.astype(np.float64)


@pytest.fixture(scope="module")
def lights(kernel_runner):
    runner = kernel_runner(HARNESS, traversal_defines())  # the BVH layout the scene buffers are built in
    return lambda scene: Lights(runner, scene)


def _ids(cases):
    return [case.id for case in cases]


def _assert_arriving(case: Case, got: np.ndarray, expected: np.ndarray, what: str) -> None:
    if case.id.startswith("area-textured"):
        # Each point shows one of the two texels: the nearest of the two must be that texel.
        distance = np.abs(got[:, None, :] - expected[None, :, :]).max(axis=2)
        nearest = expected[np.argmin(distance, axis=1)]
        np.testing.assert_allclose(got, nearest, rtol=2e-3, err_msg=what)
        assert len(np.unique(np.argmin(distance, axis=1))) == 2, f"{what}: both texels seen"
        return
    np.testing.assert_allclose(got, expected, rtol=2e-3, atol=1e-7 * np.max(expected), err_msg=what)


# ---------------------------------------------------------------- every light


@pytest.mark.parametrize("case", EVERY, ids=_ids(EVERY))
def test_sampled_light_is_its_closed_form_and_delta_exactly_where_declared(lights, case):
    device = lights(case.scene)
    for index, point in enumerate(case.points):
        s = device.sample(point, 4000, seed=10 + index)
        assert np.all(s["ok"]), (case.id, point)
        assert np.all(s["delta"] == case.delta), (case.id, point)
        np.testing.assert_allclose(np.linalg.norm(s["wi"], axis=1), 1.0, atol=1e-5)
        expected = case.arriving(s["p"], s["wi"], s["q"])
        _assert_arriving(case, s["arriving"], expected, f"{case.id} from {point}")
    for point in case.dark_points:
        s = device.sample(point, 2000, seed=20)
        assert np.all(s["arriving"][s["ok"]] == 0.0), (case.id, point)


@pytest.mark.parametrize("case", [c for c in EVERY if c.delta], ids=_ids([c for c in EVERY if c.delta]))
def test_delta_lights_point_at_their_source_and_no_ray_meets_them(lights, case):
    """A delta light's direction is exact (toward its position, or against its travel) and its pdf is its pick
    probability (1 here); a BSDF-sampled ray along it finds no emitter, as only next-event estimation reaches it."""
    device = lights(case.scene)
    light = case.scene.lights[0]
    for index, point in enumerate(case.points):
        s = device.sample(point, 500, seed=30 + index)
        expected = _unit(np.subtract(light.position, point)) if hasattr(light, "position") else -_unit(light.direction)
        np.testing.assert_allclose(s["wi"], np.broadcast_to(expected, s["wi"].shape), atol=2e-6)
        np.testing.assert_allclose(s["pdf"], 1.0, rtol=1e-6)
        h = device.hits(s["p"], s["wi"])
        assert np.all(h["light"] < 0) and np.all(h["pdf"] == 0.0), case.id


@pytest.mark.parametrize("case", NON_DELTA, ids=_ids(NON_DELTA))
def test_pdf_at_a_hit_is_the_pdf_the_sampler_returned(lights, case):
    """For every direction next-event estimation draws, a ray along it meets the sampled light point (or, for an
    environment, nothing) and is given, for MIS, the very pdf the sampler returned; and the radiance it brings back
    is the radiance the sample carried."""
    device = lights(case.scene)
    for index, point in enumerate(case.points):
        s = device.sample(point, 4000, seed=40 + index)
        h = device.hits(s["p"], s["wi"])
        environment = np.isinf(s["distance"])
        finite = np.where(environment, 0.0, s["distance"])
        met = np.where(environment, np.isinf(h["t"]), np.abs(h["t"] - finite) <= 1e-3 * finite)
        assert np.all(h["light"] >= 0) and np.mean(met) == 1.0, (case.id, point, np.mean(met))
        # A direction drawn within a float's rounding of a map texel's edge may be looked up in its neighbour: a
        # few in a thousand at most, where a pdf off by a factor is off everywhere.
        same = np.all(np.isclose(h["emitted"], s["arriving"], rtol=2e-3, atol=1e-6), axis=1)
        same &= np.isclose(h["pdf"], s["pdf"], rtol=2e-3)
        assert np.mean(~same) <= 2e-3, (case.id, point, h["pdf"][~same][:5], s["pdf"][~same][:5])


# Bins of the chi-square test, uniform in cos θ over [cos_min, 1] about the case's axis and in φ; each bin's expected
# probability integrates the hit pdf over a finer grid of directions (midpoint rule).
CHI2_COS_BINS, CHI2_PHI_BINS = 8, 16
CHI2_SAMPLES = 40_000
CHI2_SIGNIFICANCE = 0.01 / len(NON_DELTA)  # Bonferroni over every chi-square test


def _directions(case: Case, cos_theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    x, y, z = _frame(np.asarray(case.axis))
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta**2))
    return (sin_theta * np.cos(phi))[:, None] * x + (sin_theta * np.sin(phi))[:, None] * y + cos_theta[:, None] * z


def _bin_probabilities(device: Lights, case: Case) -> np.ndarray:
    grid_cos, grid_phi = case.grid
    span = 1.0 - case.cos_min
    cos_theta = case.cos_min + span * (np.arange(grid_cos) + 0.5) / grid_cos
    phi = 2.0 * np.pi * (np.arange(grid_phi) + 0.5) / grid_phi
    c, f = np.meshgrid(cos_theta, phi, indexing="ij")
    h = device.hits(case.points[0], _directions(case, c.ravel(), f.ravel()))
    cell = (span / grid_cos) * (2.0 * np.pi / grid_phi)
    grid = (h["pdf"] * cell).reshape(grid_cos, grid_phi)
    return grid.reshape(CHI2_COS_BINS, grid_cos // CHI2_COS_BINS, CHI2_PHI_BINS, grid_phi // CHI2_PHI_BINS).sum(
        axis=(1, 3)
    )


@pytest.mark.parametrize("case", NON_DELTA, ids=_ids(NON_DELTA))
def test_sampler_follows_the_hit_pdf_chi_square_and_the_pdf_integrates_to_one(lights, case):
    """Histogram of the drawn directions against N × the hit pdf integrated over each bin; that integral over all
    bins is 1 (every sample is a direction toward the light, and every direction toward it can be drawn), within
    the midpoint rule's error at the light's edge."""
    device = lights(case.scene)
    probabilities = _bin_probabilities(device, case)
    assert abs(probabilities.sum() - 1.0) < 5e-3, (case.id, probabilities.sum())
    s = device.sample(case.points[0], CHI2_SAMPLES, seed=50)
    assert np.all(s["ok"]), case.id
    x, y, z = _frame(np.asarray(case.axis))
    wi = s["wi"]
    cos_theta = wi @ z
    assert np.all(cos_theta >= case.cos_min), case.id  # the bounding cone holds every sample
    span = 1.0 - case.cos_min
    cos_bin = np.clip(((cos_theta - case.cos_min) / span * CHI2_COS_BINS).astype(int), 0, CHI2_COS_BINS - 1)
    phi = np.mod(np.arctan2(wi @ y, wi @ x), 2.0 * np.pi)
    phi_bin = np.clip((phi / (2.0 * np.pi) * CHI2_PHI_BINS).astype(int), 0, CHI2_PHI_BINS - 1)
    observed = np.zeros((CHI2_COS_BINS, CHI2_PHI_BINS))
    np.add.at(observed, (cos_bin, phi_bin), 1.0)
    assert_chi_square_fits(observed.ravel(), CHI2_SAMPLES * probabilities.ravel(), CHI2_SIGNIFICANCE, what=case.id)


# ---------------------------------------------------------------- the spot's profile


def _smoothstep_profile(theta: np.ndarray, start: float, cutoff: float) -> np.ndarray:
    """pbrt-v4's spot falloff (docs/scene-format.md): 1 inside the falloff start, 0 beyond the cutoff, between them
    the smoothstep 3t² − 2t³ of t = (cos θ − cos θc) / (cos θs − cos θc)."""
    t = np.clip((np.cos(theta) - np.cos(cutoff)) / (np.cos(start) - np.cos(cutoff)), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _linear_profile(theta: np.ndarray, start: float, cutoff: float) -> np.ndarray:
    """Mitsuba 3's spot falloff (spot.cpp; docs/mitsuba.md): linear in θ from 1 at the start to 0 at the cutoff."""
    return np.clip((cutoff - theta) / (cutoff - start), 0.0, 1.0)


def _spot_profile(lights, linear: bool, theta: np.ndarray, start_deg: float, cutoff_deg: float):
    """The kernel's intensity ratio I(θ)/I(0) = arriving · d² / I, seen from points at distance 2 at angles θ from
    the axis (+z from the origin), at φ spread around it."""
    light = spectrace.spot_light(
        (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), cutoff_deg, start_deg, intensity="cie:D65", linear_falloff=linear
    )
    device = lights(_scene(lights=[light]))
    phi = np.linspace(0.0, 2.0 * np.pi, len(theta), endpoint=False) * 7.0
    points = 2.0 * np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    s = device.sample(points, len(points), seed=60)  # a delta light's sample does not depend on the numbers
    assert np.all(s["ok"] == (s["arriving"][:, 0] > 0))
    return s["arriving"] * 4.0 / _at(light.intensity)[None, :]


@pytest.mark.parametrize("linear", [False, True], ids=["smoothstep", "linear"])
def test_spot_profile_across_its_whole_transition(lights, linear):
    """The falloff at 400 angles from the axis to beyond the cutoff, most inside the transition, against the
    documented profile; and the profile the kernel applies, integrated over the sphere, times ∫I dλ, is the power
    the light was given."""
    start_deg, cutoff_deg = 15.0, 40.0
    start, cutoff = np.radians(start_deg), np.radians(cutoff_deg)
    theta = np.concatenate([np.linspace(0.0, start, 40), np.linspace(start, cutoff, 320), np.linspace(cutoff, 0.9, 40)])
    profile = _spot_profile(lights, linear, theta, start_deg, cutoff_deg)
    expected = (_linear_profile if linear else _smoothstep_profile)(theta, start, cutoff)
    np.testing.assert_allclose(profile, np.broadcast_to(expected[:, None], profile.shape), atol=3e-4, rtol=0)

    # The power: 2π ∫ falloff(θ) sin θ dθ of the kernel's own values, on a fine grid.
    fine = np.linspace(0.0, cutoff * 1.02, 3001)
    kernel_profile = _spot_profile(lights, linear, fine, start_deg, cutoff_deg)
    powered = spectrace.spot_light(
        (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), cutoff_deg, start_deg, power_w=25.0, spectrum="cie:D65", linear_falloff=linear
    )
    solid_angle = 2.0 * np.pi * np.trapezoid(kernel_profile[:, 0] * np.sin(fine), fine)
    flux = solid_angle * np.trapezoid(powered.intensity.values, GRID_NM)
    assert flux == pytest.approx(25.0, rel=1e-3)


# ---------------------------------------------------------------- the flux leaving


# Emitting areas of the area cases, from their shapes' definitions (docs/scene-format.md): the rectangle [-1, 1]²,
# the sphere of radius 0.6, the unit disk, the unit cylinder stretched to length 3.
EMITTING_AREA = {
    "rectangle": 4.0,
    "textured": 4.0,
    "sphere": 4.0 * np.pi * 0.6**2,
    "disk": np.pi,
    "cylinder": 2.0 * np.pi * 3.0,
    # φmax (1 − r_inner²)/2, φmax r (zmax − zmin), φmax · length
    "partialdisk": np.radians(270.0) * (1.0 - 0.4**2) / 2.0,
    "partialsphere": np.radians(200.0) * 0.6 * 0.8,
    "partialcylinder": np.radians(150.0) * 3.0,
}


def _flux(case: Case, radius: float) -> np.ndarray:
    """The flux (W/nm) the case's light emits, at LAMBDA_NM, from its definition: 4πI for a point light,
    I·2π[(1 − cos θs) + (cos θs − cos θc)/2] for a spot (docs/scene-format.md), E·πR² across the disk a sphere of
    radius R shows a distant light, πR² ∫L dω for an environment, π·A·L per emitting side of an area light."""
    if case.scene.lights:
        light = case.scene.lights[0]
        if isinstance(light, PointLight):
            return 4.0 * np.pi * _at(light.intensity)
        if isinstance(light, SpotLight):
            cos_s, cos_c = np.cos(np.radians([light.falloff_start_degrees, light.cutoff_degrees]))
            return _at(light.intensity) * 2.0 * np.pi * ((1.0 - cos_s) + 0.5 * (cos_s - cos_c))
        if isinstance(light, ProjectorLight):
            tan_x = np.tan(np.radians(60.0) / 2.0)
            return _at(light.intensity) * _projector_flux_factor(tan_x, tan_x / 1.5, light.profile)
        if isinstance(light, GoniometricLight):  # every texel covers 4π / texel count
            return _at(light.intensity) * 4.0 * np.pi * GONIO_IMAGE.mean()
        if isinstance(light, DistantLight):
            return _at(light.irradiance) * np.pi * radius**2
        if isinstance(light, ConstantEnvironment):
            return _at(light.radiance) * 4.0 * np.pi * np.pi * radius**2
        if isinstance(light, EnvironmentMap):
            height, width = light.rgb.shape[:2]
            edges = np.cos(np.pi * np.arange(height + 1) / height)
            texel_solid_angle = (edges[:-1] - edges[1:]) * 2.0 * np.pi / width
            radiance = light.scale * light.rgb.astype(np.float64) @ _basis()  # (height, width, 4)
            return np.pi * radius**2 * np.einsum("hwk,h->k", radiance, texel_solid_angle)
        raise AssertionError(f"{case.id}: no closed form for the flux of a {type(light).__name__}")
    emitter = case.scene.shapes[0].emitter
    area = EMITTING_AREA[case.id.split("-")[1]]
    sides = 2.0 if emitter.two_sided else 1.0
    if emitter.image is None:
        return np.pi * area * sides * _at(emitter.radiance)
    # The two texels each cover half the rectangle.
    values = TEXELS[0] @ _basis() if emitter.image.primaries is not None else BAND_VALUES
    return np.pi * area * sides * emitter.image.scale * values.mean(axis=0)


@pytest.mark.parametrize("case", EVERY, ids=_ids(EVERY))
def test_light_paths_start_with_the_lights_flux(lights, case):
    """The mean flux the first rays of light paths carry (light_emission.cl, after the pick) is the light's flux,
    within 4 standard errors (a point light's rays all carry the same: float rounding only)."""
    radius = 3.0
    weight = lights(case.scene).emit(20000, seed=70, radius=radius)
    mean, standard_error = mean_and_standard_error(weight)
    expected = _flux(case, radius)
    assert_within_standard_errors(mean, expected, standard_error, slack=2e-5 * expected, what=case.id)
