"""pbrt-v4's partial spheres, disks and cylinders (phimax, zmin/zmax, innerradius) imported as spectrace's analytic
shapes: rays meet them where pbrt's definitions put them (a float64 reference written from pbrt's Sphere, Disk and
Cylinder: the far root where the near one is cut away, pbrt's (u, v)), and partial area lights light a point as the
closed form (an annulus sector) or a quadrature over the emitting surface (a cut sphere) says."""

import math

import numpy as np
import pytest
from tests.geometry.test_instances import _trace
from tests.interop.test_pbrt_analytic_shapes import LIGHT_HEADER, MARKER, _render_y, _rotate, _translate, _write

import spectrace
from spectrace.interop.pbrt import load_pbrt_scene

# (pbrt shape line, its parameters)
SHAPES = {
    "sphere": (
        'Shape "sphere" "float radius" 0.9 "float zmin" -0.5 "float zmax" 0.6 "float phimax" 250\n',
        {"radius": 0.9, "zmin": -0.5, "zmax": 0.6, "phimax": 250.0},
    ),
    "disk": (
        'Shape "disk" "float radius" 1.2 "float innerradius" 0.5 "float height" 0.3 "float phimax" 300\n',
        {"radius": 1.2, "innerradius": 0.5, "height": 0.3, "phimax": 300.0},
    ),
    "cylinder": (
        'Shape "cylinder" "float radius" 0.6 "float zmin" -0.5 "float zmax" 0.9 "float phimax" 200\n',
        {"radius": 0.6, "zmin": -0.5, "zmax": 0.9, "phimax": 200.0},
    ),
}


def _pbrt_partial_hits(kind, params, world_from_object, origins, directions):
    """pbrt-v4's partial shape, float64: the nearest root whose point is kept (φ <= φmax; the sphere's and cylinder's
    zmin <= z <= zmax; the disk's innerradius <= r <= radius); its t, world normal (outward, the disk's +z) and
    pbrt's (u, v)."""
    inverse = np.linalg.inv(world_from_object)
    o = origins @ inverse[:3, :3].T + inverse[:3, 3]
    d = directions @ inverse[:3, :3].T
    radius, phimax = params["radius"], math.radians(params["phimax"])
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "disk":
            roots = [(params["height"] - o[:, 2]) / d[:, 2]]
        else:
            xy = slice(0, 3) if kind == "sphere" else slice(0, 2)
            a, b = (d[:, xy] ** 2).sum(1), (o[:, xy] * d[:, xy]).sum(1)
            root = np.sqrt(b * b - a * ((o[:, xy] ** 2).sum(1) - radius**2))
            roots = [(-b - root) / a, (-b + root) / a]
        t = np.full(len(o), np.inf)
        for candidate in roots[::-1]:
            p = o + candidate[:, None] * d
            keep = (candidate > 0) & (np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi) <= phimax)
            if kind == "disk":
                r = np.hypot(p[:, 0], p[:, 1])
                keep &= (r >= params["innerradius"]) & (r <= radius)
            else:
                keep &= (p[:, 2] >= params["zmin"]) & (p[:, 2] <= params["zmax"])
            t = np.where(keep, candidate, t)
    p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    u = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi) / phimax
    if kind == "sphere":
        normal = p
        theta = np.arccos(np.clip(p[:, 2] / radius, -1, 1))
        theta_min, theta_max = np.arccos(params["zmin"] / radius), np.arccos(params["zmax"] / radius)
        v = (theta - theta_min) / (theta_max - theta_min)
    elif kind == "disk":
        normal = np.tile([0.0, 0.0, 1.0], (len(p), 1))
        v = (radius - np.hypot(p[:, 0], p[:, 1])) / (radius - params["innerradius"])
    else:
        normal = p * [1, 1, 0]
        v = (p[:, 2] - params["zmin"]) / (params["zmax"] - params["zmin"])
    normal = normal @ inverse[:3, :3]
    return t, normal / np.linalg.norm(normal, axis=1, keepdims=True), np.stack([u, v], 1)


@pytest.mark.parametrize("kind", SHAPES)
def test_partial_shapes_meet_rays_as_pbrt_defines_them(tmp_path, kernel_runner, kind):
    text, params = SHAPES[kind]
    ctm = _translate(0.3, -0.2, 0.5) @ _rotate(40, [1, 0, 0])
    checker = 'Texture "c" "spectrum" "checkerboard"\nMaterial "diffuse" "texture reflectance" "c"\n'
    body = MARKER + checker + "AttributeBegin\nTranslate 0.3 -0.2 0.5\nRotate 40 1 0 0\n" + text + "AttributeEnd\n"
    scene = load_pbrt_scene(_write(tmp_path, body))
    marker, shape = scene.shapes
    assert shape.analytic is not None and shape.analytic.kind == kind and shape.analytic.partial
    mirror = np.diag([np.sign(marker.analytic.to_world[0, 3]), 1.0, 1.0, 1.0])
    only = spectrace.Scene(camera=scene.camera, width=4, height=4, shapes=[shape])
    rng = np.random.default_rng(5)
    origins = rng.normal(size=(4000, 3))
    origins = 4.0 * origins / np.linalg.norm(origins, axis=1, keepdims=True)
    directions = rng.uniform(-1.2, 1.2, (4000, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    # pbrt's left-handed world is mirrored through x = 0 or not (the marker at pbrt's x = 4 says which); the
    # mirror does not turn pbrt's front (the normal follows the inverse transpose of the whole map).
    t_ref, n_ref, uv_ref = _pbrt_partial_hits(kind, params, mirror @ ctm, origins, directions)
    hit, _, normal = _trace(kernel_runner, only, origins, directions, np.full(len(origins), 1e9))[1][:3]
    assert np.isfinite(t_ref).mean() > 0.1
    assert np.mean(np.isfinite(hit[:, 0]) != np.isfinite(t_ref)) < 0.004
    both = np.isfinite(t_ref) & np.isfinite(hit[:, 0])
    np.testing.assert_allclose(hit[both, 0], t_ref[both], rtol=5e-5, atol=1e-5)
    np.testing.assert_allclose(normal[both, :3], n_ref[both], atol=2e-4)
    np.testing.assert_allclose(hit[both, 1:3], uv_ref[both], atol=3e-4)


def _sphere_patch_irradiance(centre, radius, zmin, zmax, phimax_degrees, x, up, steps=800):
    """E/L at x (surface normal `up`) from the outward face of a sphere patch (φ in [0, φmax], z in [zmin, zmax],
    in the sphere's own frame, axis-aligned here): ∫ cos θx cos θq / d² dA by the midpoint rule over (φ, z), dA =
    r dφ dz, where both cosines are positive (the patch's faces seen from x; a convex surface hides none of its
    own front from x)."""
    phi = (np.arange(steps) + 0.5) / steps * math.radians(phimax_degrees)
    z = zmin + (np.arange(steps) + 0.5) / steps * (zmax - zmin)
    pp, zz = np.meshgrid(phi, z, indexing="ij")
    rho = np.sqrt(radius**2 - zz**2)
    q = np.stack([rho * np.cos(pp), rho * np.sin(pp), zz], -1) + centre
    n = (q - centre) / radius
    to_q = q - x
    d2 = (to_q**2).sum(-1)
    cos_x = (to_q @ up) / np.sqrt(d2)
    cos_q = -(to_q * n).sum(-1) / np.sqrt(d2)
    integrand = np.where((cos_x > 0) & (cos_q > 0), cos_x * cos_q / d2, 0.0)
    return float(integrand.sum() * radius * (math.radians(phimax_degrees) / steps) * ((zmax - zmin) / steps))


@pytest.mark.parametrize("kind", ["disk", "sphere"])
def test_partial_area_lights_light_a_point_as_the_closed_form(tmp_path, device, kind):
    """A diffuse plane (reflectance ρ) under a partial area light of luminance-normalised radiance (pbrt's scale)
    shows ρ · scale · E/(π L): for an annulus sector of radii [a, b] and angle φmax at height h above the point,
    E/L = φmax h²/2 (1/(a² + h²) − 1/(b² + h²)); for a sphere cut at both heights and in azimuth, the quadrature
    above. Both are sampled by area over the partial surface only, with MIS against the plane's own samples."""
    rho, scale = 0.5, 3.0
    body = f'Material "diffuse" "spectrum reflectance" [360 {rho} 830 {rho}]\n' + (
        'Shape "trianglemesh" "point3 P" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "integer indices" [0 1 2 0 2 3]\n'
    )
    if kind == "disk":  # pbrt's disk faces +z: turned over to face the plane
        a, b, h, phimax = 0.3, 0.7, 1.0, 250.0
        shape = f'Shape "disk" "float radius" {b} "float innerradius" {a} "float phimax" {phimax}\n'
        body += f"AttributeBegin\nTranslate 0 0 {h}\nReverseOrientation\n"
        expected_e = math.radians(phimax) * h**2 / 2 * (1 / (a**2 + h**2) - 1 / (b**2 + h**2))
    else:
        radius, height, zmin, zmax, phimax = 0.5, 1.0, -0.4, 0.45, 240.0
        shape = (
            f'Shape "sphere" "float radius" {radius} "float zmin" {zmin} "float zmax" {zmax} "float phimax" {phimax}\n'
        )
        body += f"AttributeBegin\nTranslate 0.2 0 {height}\n"
        # The bottom cap below zmin is cut away: the point sees the sphere's inside (no light) through it.
        expected_e = _sphere_patch_irradiance(
            np.array([0.2, 0.0, height]), radius, zmin, zmax, phimax, np.zeros(3), np.array([0.0, 0.0, 1.0])
        )
    body += f'AreaLightSource "diffuse" "blackbody L" 4000 "float scale" {scale}\n' + shape + "AttributeEnd\n"
    scene = load_pbrt_scene(_write(tmp_path, body, LIGHT_HEADER))
    (light,) = [s for s in scene.shapes if s.analytic is not None]
    assert light.analytic.partial
    y = _render_y(scene, device, 64)
    expected = rho * scale * expected_e / math.pi
    standard_error = y.std(ddof=1) / math.sqrt(y.size)
    # The pixels span about ±0.03 around the origin: E there is within a few 0.1 % of the centre's.
    assert abs(y.mean() - expected) <= 4 * standard_error + 5e-3 * expected, (y.mean(), expected, standard_error)
