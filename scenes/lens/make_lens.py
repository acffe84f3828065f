"""Writes lens.obj: a thick biconvex (equiconvex) spherical lens as a closed, outward-wound triangle mesh with its
exact vertex normals, for scenes/lens_sun.toml.

Two spherical caps of radius of curvature R over an aperture of radius a, their vertices sag = R − √(R² − a²) from
the rim, joined by a short cylindrical rim of the edge thickness t_e = t_c − 2·sag. The optical axis is z, the lens
centred at the origin, lengths in metres. Each cap's normals point from its centre of curvature through the vertex
(the exact sphere's normal, so the smooth shading refracts as the true surface would); the rim keeps its own radial
normals, so the cap-rim creases stay sharp (the OBJ gives those positions one vertex per normal).

Run from this directory: python make_lens.py
"""

import math
from pathlib import Path

APERTURE_RADIUS = 0.05  # a, m
CURVATURE_RADIUS = 0.25  # R, m, both faces
CENTRE_THICKNESS = 0.016  # t_c, m
RINGS, SEGMENTS = 24, 96  # the caps' polar grid: rings of equal radius step, segments around


def main() -> None:
    a, r, tc = APERTURE_RADIUS, CURVATURE_RADIUS, CENTRE_THICKNESS
    sag = r - math.sqrt(r * r - a * a)
    half_edge = tc / 2 - sag
    assert half_edge > 0, "the caps would cross: thicker lens or flatter faces"
    positions: list[tuple[float, float, float]] = []
    normals: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []  # 0-based, same index for position and normal

    def vertex(p: tuple[float, float, float], n: tuple[float, float, float]) -> int:
        positions.append(p)
        normals.append(n)
        return len(positions) - 1

    def cap(side: float) -> list[int]:
        """The face on the +z (side = 1) or −z (side = −1) side; returns its rim ring's vertex indices."""
        centre_z = side * (tc / 2 - r)  # the centre of curvature, on the far side
        apex = vertex((0.0, 0.0, side * tc / 2), (0.0, 0.0, side))
        previous = [apex] * SEGMENTS
        for ring in range(1, RINGS + 1):
            rho = a * ring / RINGS
            z = centre_z + side * math.sqrt(r * r - rho * rho)
            current = []
            for k in range(SEGMENTS):
                phi = 2 * math.pi * k / SEGMENTS
                x, y = rho * math.cos(phi), rho * math.sin(phi)
                current.append(vertex((x, y, z), (x / r, y / r, (z - centre_z) / r)))
            for k in range(SEGMENTS):
                k1 = (k + 1) % SEGMENTS
                quad = (previous[k], current[k], current[k1], previous[k1])
                tris = [(quad[0], quad[1], quad[2])] if ring == 1 else [quad[:3], (quad[0], quad[2], quad[3])]
                for t in tris:
                    faces.append(t if side > 0 else (t[0], t[2], t[1]))
            previous = current
        return previous

    cap(1.0)
    cap(-1.0)
    top, bottom = [], []
    for k in range(SEGMENTS):
        phi = 2 * math.pi * k / SEGMENTS
        c, s = math.cos(phi), math.sin(phi)
        top.append(vertex((a * c, a * s, half_edge), (c, s, 0.0)))
        bottom.append(vertex((a * c, a * s, -half_edge), (c, s, 0.0)))
    for k in range(SEGMENTS):
        k1 = (k + 1) % SEGMENTS
        faces.append((bottom[k], bottom[k1], top[k1]))
        faces.append((bottom[k], top[k1], top[k]))
    lines = [f"# equiconvex lens: aperture radius {a} m, faces' radius {r} m, centre thickness {tc} m (make_lens.py)"]
    lines += [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in positions]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in normals]
    lines += [f"f {i + 1}//{i + 1} {j + 1}//{j + 1} {k + 1}//{k + 1}" for i, j, k in faces]
    Path(__file__).with_name("lens.obj").write_text("\n".join(lines) + "\n", encoding="ascii")


if __name__ == "__main__":
    main()
