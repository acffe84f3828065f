"""pbrt-v4's whole disks, cylinders and spheres imported as spectrace's analytic shapes: rays meet them where pbrt's
own definitions put them (float64 closed forms of pbrt's Disk, Cylinder, Sphere: hit distance, front normal flipped by
ReverseOrientation and by a placement that swaps handedness, pbrt's (u, v)), also inside ObjectBegin; a cylinder's
projected area seen orthographically; a disk light's irradiance against the closed form; a checkerboard on a disk
lands at pbrt's (u, v)."""

import math
from pathlib import Path

import numpy as np
import pytest
from tests.geometry.test_instances import _trace

import spectrace
from spectrace.interop.pbrt import load_pbrt_scene, pbrt_scene_data

HEADER = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 8 "integer yresolution" 6
WorldBegin
"""
MARKER = 'AttributeBegin\nTranslate 4 0 0\nShape "sphere" "float radius" 0.1\nAttributeEnd\n'
CHECKER = (
    'Texture "c" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 1\n'
    '  "rgb tex1" [0.8 0.05 0.05] "rgb tex2" [0.05 0.05 0.8]\nMaterial "diffuse" "texture reflectance" "c"\n'
)


def _write(folder: Path, body: str, header: str = HEADER) -> Path:
    path = folder / "scene.pbrt"
    path.write_text(header + body)
    return path


def _translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = x, y, z
    return m


def _rotate(degrees, axis):
    """pbrt's Rotate (Rodrigues' formula about the normalised axis)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + math.sin(math.radians(degrees)) * k + (1 - math.cos(math.radians(degrees))) * k @ k
    return m


def _scale(x, y, z):
    return np.diag([x, y, z, 1.0])


def _pbrt_hits(kind, params, world_from_object, flip, origins, directions):
    """Nearest hit of pbrt's disk (z = height, r <= radius) or cylinder (x² + y² = radius², zmin <= z <= zmax) in
    float64: t, unit world normal (object normal, negated when `flip`, by the inverse transpose) and pbrt's (u, v)."""
    inverse = np.linalg.inv(world_from_object)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    d = directions @ inverse[:3, :3].T
    n = len(o)
    t = np.full(n, np.inf)
    radius = params["radius"]
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "disk":
            t0 = (params["height"] - o[:, 2]) / d[:, 2]
            p = o + t0[:, None] * d
            t = np.where((t0 > 0) & (np.hypot(p[:, 0], p[:, 1]) <= radius), t0, np.inf)
        else:
            xy = slice(0, 3) if kind == "sphere" else slice(0, 2)
            a = (d[:, xy] ** 2).sum(1)
            b = (o[:, xy] * d[:, xy]).sum(1)
            c = (o[:, xy] ** 2).sum(1) - radius**2
            root = np.sqrt(b * b - a * c)
            for candidate in ((-b + root) / a, (-b - root) / a):
                z = o[:, 2] + candidate * d[:, 2]
                ok = (candidate > 0) & (candidate < t)
                if kind == "cylinder":
                    ok &= (z >= params["zmin"]) & (z <= params["zmax"])
                t = np.where(ok, candidate, t)
    p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    phi = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi)
    if kind == "disk":
        normal = np.tile([0.0, 0.0, 1.0], (n, 1))
        uv = np.stack([phi / (2 * np.pi), (radius - np.hypot(p[:, 0], p[:, 1])) / radius], axis=1)
    elif kind == "sphere":  # pbrt's whole sphere: v = (θ − θ(zmin)) / (θ(zmax) − θ(zmin)) = 1 − θ/π
        normal = p
        uv = np.stack([phi / (2 * np.pi), 1 - np.arccos(np.clip(p[:, 2] / radius, -1, 1)) / np.pi], axis=1)
    else:
        normal = p * [1, 1, 0]
        uv = np.stack([phi / (2 * np.pi), (p[:, 2] - params["zmin"]) / (params["zmax"] - params["zmin"])], axis=1)
    normal = (-1.0 if flip else 1.0) * normal @ inverse[:3, :3]
    return t, normal / np.linalg.norm(normal, axis=1, keepdims=True), uv


DISK = {"height": 0.4, "radius": 1.2}
CYLINDER = {"radius": 0.6, "zmin": -0.5, "zmax": 0.9}
SPHERE = {"radius": 0.9}
# (pbrt text before the shape, its CTM, pbrt's flip: ReverseOrientation xor the CTM swapping handedness)
PLACEMENTS = [
    ("Translate 0.3 -0.2 0.5\nRotate 40 1 0 0\n", _translate(0.3, -0.2, 0.5) @ _rotate(40, [1, 0, 0]), False),
    ("Rotate 60 0 1 1\nScale 1 1 -1\n", _rotate(60, [0, 1, 1]) @ _scale(1, 1, -1), True),
    ("ReverseOrientation\nTranslate 0 0.2 0\nScale 1.3 0.8 1\n", _translate(0, 0.2, 0) @ _scale(1.3, 0.8, 1), True),
]


def _shape_text(kind: str) -> str:
    if kind == "sphere":
        return 'Shape "sphere" "float radius" 0.9\n'
    if kind == "disk":
        return 'Shape "disk" "float height" 0.4 "float radius" 1.2\n'
    return 'Shape "cylinder" "float radius" 0.6 "float zmin" 0.9 "float zmax" -0.5\n'  # pbrt orders zmin, zmax


def _rays(count: int, seed: int):
    rng = np.random.default_rng(seed)
    origins = rng.normal(size=(count, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    directions = rng.uniform(-1.2, 1.2, (count, 3)) - origins
    return origins, directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _compare(kernel_runner, scene, kind, world_from_object, flip, seed):
    origins, directions = _rays(3000, seed)
    params = {"disk": DISK, "cylinder": CYLINDER, "sphere": SPHERE}[kind]
    t_ref, n_ref, uv_ref = _pbrt_hits(kind, params, world_from_object, flip, origins, directions)
    hit, _, normal = _trace(kernel_runner, scene, origins, directions, np.full(len(origins), 1e9))[1][:3]
    assert np.isfinite(t_ref).mean() > 0.2
    assert np.mean(np.isfinite(hit[:, 0]) != np.isfinite(t_ref)) < 0.003
    both = np.isfinite(t_ref) & np.isfinite(hit[:, 0])
    np.testing.assert_allclose(hit[both, 0], t_ref[both], rtol=5e-5, atol=1e-5)
    np.testing.assert_allclose(normal[both, :3], n_ref[both], atol=2e-4)
    du = np.abs(hit[both, 1] - uv_ref[both, 0])
    np.testing.assert_array_less(np.minimum(du, 1 - du), 2e-4)  # u wraps at φ = 0
    np.testing.assert_allclose(hit[both, 2], uv_ref[both, 1], atol=2e-4)


@pytest.mark.parametrize("kind", ["disk", "cylinder", "sphere"])
@pytest.mark.parametrize("placement", range(len(PLACEMENTS)))
def test_whole_disks_and_cylinders_meet_rays_as_pbrt_defines_them(tmp_path, kernel_runner, kind, placement):
    text, ctm, flip = PLACEMENTS[placement]
    body = MARKER + CHECKER + "AttributeBegin\n" + text + _shape_text(kind) + "AttributeEnd\n"
    scene = load_pbrt_scene(_write(tmp_path, body))
    marker, shape = scene.shapes
    if kind == "sphere" and placement == 2:  # a stretched sphere that is reversed or textured needs triangles
        assert shape.analytic is None
        return
    assert shape.analytic is not None and shape.analytic.kind == kind
    # pbrt's left-handed world is mirrored through x = 0 or not (the marker at pbrt's x = 4 says which).
    mirror = np.diag([np.sign(marker.analytic.to_world[0, 3]), 1.0, 1.0, 1.0])
    only = spectrace.Scene(camera=scene.camera, width=4, height=4, shapes=[shape])
    _compare(kernel_runner, only, kind, mirror @ ctm, flip, seed=placement)


@pytest.mark.parametrize("kind", ["disk", "cylinder"])
def test_disks_and_cylinders_in_objects_stay_analytic_under_instances(tmp_path, kernel_runner, kind):
    """Inside ObjectBegin the front follows the shape's own placement (pbrt flips by its definition's handedness,
    not the instance's); the instance map (here mirroring and stretching) carries the exact surface."""
    text, ctm, flip = PLACEMENTS[1]
    defined = f'ObjectBegin "thing"\n{text}{_shape_text(kind)}ObjectEnd\n'
    use = 'AttributeBegin\nTranslate 0.2 0 0\nScale -1.4 0.9 1.1\nObjectInstance "thing"\nAttributeEnd\n'
    scene = load_pbrt_scene(_write(tmp_path, MARKER + CHECKER + defined + use))
    (instance,) = scene.instances
    assert [s.analytic.kind for s in instance.object.shapes] == [kind]
    mirror = np.diag([np.sign(scene.shapes[0].analytic.to_world[0, 3]), 1.0, 1.0, 1.0])
    only = spectrace.Scene(camera=scene.camera, width=4, height=4, shapes=[], instances=scene.instances)
    placed = mirror @ _translate(0.2, 0, 0) @ _scale(-1.4, 0.9, 1.1) @ ctm
    _compare(kernel_runner, only, kind, placed, flip, seed=7)


def test_partial_disks_and_cylinders_are_analytic_with_their_cuts(tmp_path):
    """phimax and innerradius become the analytic shapes' keys (the unit disk's hole a fraction of its radius);
    a degenerate disk (innerradius >= radius) stays triangles."""
    body = (
        'Shape "disk" "float innerradius" 0.3 "float radius" 0.6\nShape "disk" "float phimax" 180\n'
        'Shape "cylinder" "float phimax" 90\nShape "disk"\nShape "cylinder"\nShape "disk" "float innerradius" 2\n'
    )
    data, _ = pbrt_scene_data(_write(tmp_path, body))
    assert [s["type"] for s in data["shapes"]] == ["disk", "disk", "cylinder", "disk", "cylinder", "mesh"]
    assert data["shapes"][0]["inner_radius"] == pytest.approx(0.5) and "phi_max" not in data["shapes"][0]
    assert data["shapes"][1]["phi_max"] == 180 and data["shapes"][2]["phi_max"] == 90
    assert not {"phi_max", "inner_radius"} & (data["shapes"][3].keys() | data["shapes"][4].keys())


def test_cylinder_projected_area_seen_orthographically(tmp_path, kernel_runner):
    """Parallel rays across the axis of an imported cylinder (radius 0.6, z from -0.5 to 0.9) meet a window of it
    2 r (zmax − zmin) in area: the fraction of uniform rays that hit, with its binomial standard error."""
    from stats_toolkit import assert_within_standard_errors

    scene = load_pbrt_scene(_write(tmp_path, _shape_text("cylinder")))
    rng = np.random.default_rng(3)
    count, half = 200_000, 1.0
    origins = np.stack([rng.uniform(-half, half, count), np.full(count, 10.0), rng.uniform(-half, half, count)], 1)
    directions = np.tile([0.0, -1.0, 0.0], (count, 1))
    occluded = _trace(kernel_runner, scene, origins, directions, np.full(count, 100.0))[1][4]
    p = float(np.mean(occluded == 1))
    window = (2 * half) ** 2
    area = 2 * 0.6 * (0.9 + 0.5)
    assert_within_standard_errors(p * window, area, np.sqrt(p * (1 - p) / count) * window, sigmas=4.5, what="area")


LIGHT_HEADER = """LookAt 3 0 2  0 0 0  0 0 1
Camera "perspective" "float fov" 0.5
Film "rgb" "integer xresolution" 4 "integer yresolution" 4
Integrator "path" "integer maxdepth" 1
WorldBegin
"""


def _render_y(scene, device, spp: int) -> np.ndarray:
    from spectrace.engine.renderer import Renderer

    renderer = Renderer(scene, device)
    renderer.render(spp=spp)
    return renderer.image().xyz[..., 1].astype(np.float64)


@pytest.mark.parametrize(
    ("placement", "lit"),
    [
        ("ReverseOrientation\n", True),  # the front turned to -z: toward the plane
        ("", False),  # pbrt's disk faces +z, away from the plane
        ("Rotate 180 1 0 0\n", True),
        ("Scale 1 1 -1\n", False),  # swapped handedness flips the object normal, the mirror brings it back up
        ("ReverseOrientation\nScale 1 1 -1\n", True),
    ],
)
def test_disk_light_irradiance_matches_the_closed_form(tmp_path, device, placement, lit):
    """A one-sided disk light of radius r at height h lights the point below its centre with E = π L r²/(r² + h²)
    when its front (pbrt's) faces down; a diffuse plane of reflectance ρ there shows ρ L r²/(r² + h²). pbrt
    normalises L to luminance `scale`."""
    r, h, rho, scale = 0.5, 1.0, 0.5, 3.0
    body = f'Material "diffuse" "spectrum reflectance" [360 {rho} 830 {rho}]\n' + (
        'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'
    )
    body += f"AttributeBegin\nTranslate 0 0 {h}\n{placement}"
    body += f'AreaLightSource "diffuse" "blackbody L" 4000 "float scale" {scale}\n'
    body += f'Shape "disk" "float radius" {r}\nAttributeEnd\n'
    scene = load_pbrt_scene(_write(tmp_path, body, LIGHT_HEADER))
    assert [s.analytic.kind for s in scene.shapes if s.analytic is not None] == ["disk"]
    y = _render_y(scene, device, 64)
    # The pixels span about ±0.03 around the origin: E there is within 0.2 % of the centre's.
    expected = rho * scale * r**2 / (r**2 + h**2) if lit else 0.0
    standard_error = y.std(ddof=1) / math.sqrt(y.size)
    assert abs(y.mean() - expected) <= 4 * standard_error + 3e-3 * rho * scale * r**2 / (r**2 + h**2), (
        y.mean(),
        expected,
        standard_error,
    )


def test_checkerboard_on_a_disk_lands_at_pbrt_uv(tmp_path, device):
    """pbrt's disk has u = φ/2π: a checkerboard with uscale 4 puts tex1 (red) where φ lies in [0°, 90°) and
    [180°, 270°), tex2 (blue) in the other quadrants. The camera looks down pbrt's -z; each pixel's world point
    (pbrt's x, y, from the camera ray) says which quadrant it shows."""
    from spectrace.engine.renderer import Renderer
    from spectrace.spectral import xyz_to_linear_srgb

    header = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "path" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0]
"""
    scene = load_pbrt_scene(_write(tmp_path, CHECKER + 'Shape "disk" "float radius" 0.8\n', header))
    assert scene.shapes[0].analytic is not None and scene.shapes[0].analytic.pbrt_uv
    renderer = Renderer(scene, device)
    renderer.render(spp=4)
    rgb = xyz_to_linear_srgb(renderer.image().xyz.astype(np.float64))
    # pbrt's camera: image right is camera +x = up × view = (0 1 0) × (0 0 -1) = world -x; image up is world +y.
    # Pixel (row, column) centres; the disk (radius 0.8) spans ±0.8 / (5 tan 10°) = ±0.91 of the half-width.
    coordinate = (np.arange(16) + 0.5) / 8 - 1.0
    x = -coordinate[None, :] * 5 * math.tan(math.radians(10))
    y = -coordinate[:, None] * 5 * math.tan(math.radians(10))
    phi = np.degrees(np.mod(np.arctan2(y, x), 2 * np.pi)) * np.ones((16, 16))
    # Away from the centre, where a pixel spans many degrees of φ (and a filtered texture blends the quadrants).
    inside = (np.abs(np.hypot(x, y) - 0.5) < 0.2) * np.ones((16, 16), bool)
    away_from_edges = np.abs(np.mod(phi + 15, 90) - 15) > 15  # 15° from each quadrant's border
    red = rgb[..., 0] > 3 * rgb[..., 2]
    blue = rgb[..., 2] > 3 * rgb[..., 0]
    expect_red = (phi < 90) | ((phi >= 180) & (phi < 270))
    chosen = inside & away_from_edges
    assert chosen.sum() > 40
    assert np.all(red[chosen & expect_red]) and np.all(blue[chosen & ~expect_red])


def test_disk_with_pbrt_uv_exports_to_mitsuba_as_triangles_carrying_them(tmp_path, mitsuba_scalar_spectral):
    """Mitsuba's disk has u = r, v = φ/2π: a disk with pbrt's (u, v) is exported as its tessellation, whose
    vertices carry pbrt's u = φ/2π, v = 1 − r/radius (φ in pbrt's object space, here its world)."""
    from dataclasses import replace

    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    header = HEADER.replace("WorldBegin", 'PixelFilter "box"\nWorldBegin')
    scene = load_pbrt_scene(_write(tmp_path, MARKER + CHECKER + 'Shape "disk" "float radius" 1.5\n', header))
    grey = spectrace.diffuse(0.5)
    shapes = [replace(shape, material=grey) for shape in scene.shapes]
    assert shapes[1].analytic.pbrt_uv
    entries = scene_to_mitsuba_dict(replace(scene, shapes=shapes), tmp_path, spp=1)
    disk = entries["shape_1"]
    assert disk["type"] == "ply"
    # The PLY's vertex rows as written (x, y, z, nx, ny, nz, u, v: float32), read without a loader's conventions.
    data = Path(disk["filename"]).read_bytes()
    header, body = data.split(b"end_header\n", 1)
    count = int(header.split(b"element vertex ")[1].split()[0])
    assert header.count(b"property float") == 8
    rows = np.frombuffer(body[: count * 32], "<f4").reshape(count, 8).astype(np.float64)
    mirror = np.sign(shapes[0].analytic.to_world[0, 3])  # pbrt's world is spectrace's mirrored through x = 0, or not
    x, y = mirror * rows[:, 0], rows[:, 1]
    radius = np.hypot(x, y)
    away = radius > 1e-6  # φ is undefined at the centre
    u = np.mod(np.arctan2(y, x), 2 * np.pi)[away] / (2 * np.pi)
    du = np.abs(rows[away, 6] - u)
    np.testing.assert_array_less(np.minimum(du, 1 - du), 1e-5)
    np.testing.assert_allclose(rows[:, 7], 1 - radius / 1.5, atol=1e-5)
