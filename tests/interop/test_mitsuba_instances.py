"""Mitsuba 3's shapegroup and instance imported as a spectrace object stored once and its instances: the instances
see the same surfaces as Mitsuba's (ray hits; texture coordinates too on spheres, disks and cylinders, which stay
exact under stretching instances), and the scene renders like Mitsuba's own rendering of the file."""

import re
from pathlib import Path

import numpy as np
import pytest
from tests.geometry.test_instances import _trace

from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import load_mitsuba_scene, mitsuba_scene_data

GROUP = """
<shape type="shapegroup" id="crate">
  <shape type="cube">
    <transform name="to_world"><scale x="0.3" y="0.3" z="0.2"/><translate z="0.2"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.4, 0.2"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale x="0.25" y="0.15"/><rotate x="1" angle="80"/><translate y="-0.35" z="0.45"/>
    </transform>
    <bsdf type="twosided"><bsdf type="roughconductor"><string name="material" value="Au"/>
      <float name="alpha" value="0.3"/></bsdf></bsdf>
  </shape>
</shape>
<shape type="instance"><ref id="crate"/></shape>
<shape type="instance"><ref id="crate"/>
  <transform name="to_world"><rotate z="1" angle="35"/><translate x="0.9" y="0.3"/></transform>
</shape>
<shape type="instance"><ref id="crate"/>
  <transform name="to_world"><scale x="1.4" y="0.8" z="1.6"/><rotate z="1" angle="-50"/><translate x="-0.9" y="0.2"/>
  </transform>
</shape>
<shape type="rectangle" id="floor">
  <transform name="to_world"><scale value="3"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
</shape>
<shape type="rectangle" id="light">
  <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="180"/><translate x="0.4" y="-0.5" z="2.2"/>
  </transform>
  <emitter type="area"><rgb name="radiance" value="12, 11, 10"/></emitter>
</shape>
<emitter type="constant"><rgb name="radiance" value="0.15, 0.17, 0.2"/></emitter>
"""


# Mitsuba 3's exact shapes in a shapegroup, placed under non-uniform scales, a shear and a mirror: the instance
# stretches the sphere into an ellipsoid, the disk and cylinder into elliptic ones.
ANALYTIC_GROUP = """
<shape type="shapegroup" id="parts">
  <shape type="sphere"><point name="center" x="0" y="0" z="0.35"/><float name="radius" value="0.3"/>
    <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.7, 0.3, 0.2"/>
      <float name="alpha" value="0.25"/></bsdf>
  </shape>
  <shape type="disk">
    <transform name="to_world"><scale x="0.3" y="0.2"/><rotate x="1" angle="60"/><translate x="0.45" z="0.3"/>
    </transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf>
  </shape>
  <shape type="cylinder"><point name="p0" x="-0.5" y="0" z="0"/><point name="p1" x="-0.5" y="0" z="0.6"/>
    <float name="radius" value="0.12"/>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.4, 0.8"/></bsdf></bsdf>
  </shape>
</shape>
<shape type="instance"><ref id="parts"/></shape>
<shape type="instance"><ref id="parts"/>
  <transform name="to_world"><scale x="1.4" y="0.7" z="1.5"/><rotate z="1" angle="35"/><translate x="1.0" y="0.4"/>
  </transform>
</shape>
<shape type="instance"><ref id="parts"/>
  <transform name="to_world"><matrix value="-1 0.3 0 -0.9  0 1.2 0 0.1  0 0 0.8 0  0 0 0 1"/></transform>
</shape>
<shape type="rectangle" id="floor">
  <transform name="to_world"><scale value="3"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
</shape>
<shape type="rectangle" id="light">
  <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="180"/><translate x="0.4" y="-0.5" z="2.2"/>
  </transform>
  <emitter type="area"><rgb name="radiance" value="12, 11, 10"/></emitter>
</shape>
<emitter type="constant"><rgb name="radiance" value="0.15, 0.17, 0.2"/></emitter>
"""


def _xml(folder: Path, size: int, body: str = GROUP) -> Path:
    sensor = f"""<sensor type="perspective"><float name="fov" value="50"/>
      <transform name="to_world"><lookat origin="0.3, -3.0, 1.9" target="0, 0, 0.2" up="0, 0, 1"/></transform>
      <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
      <rfilter type="box"/></film></sensor>"""
    path = folder / "instances.xml"
    path.write_text(
        f'<scene version="3.0.0">\n<integrator type="path"><integer name="max_depth" value="4"/>'
        f"</integrator>\n{sensor}\n{body}\n</scene>\n"
    )
    return path


def test_shapegroup_imports_as_one_object_placed_three_times(tmp_path):
    scene = load_mitsuba_scene(_xml(tmp_path, 8))
    assert len(scene.instances) == 3 and len({id(i.object) for i in scene.instances}) == 1
    assert [s.name for s in scene.shapes] == ["floor", "light"]
    assert len(scene.instances[0].object.shapes) == 2
    np.testing.assert_allclose(scene.instances[0].to_world, np.eye(4))


@pytest.mark.parametrize(
    ("body", "says"),
    [
        (
            '<shape type="shapegroup" id="g"><shape type="cube"><emitter type="area"><rgb name="radiance" value="1"/>'
            '</emitter></shape></shape><shape type="instance"><ref id="g"/></shape>',
            "emitters cannot be instanced",
        ),
        (
            '<shape type="shapegroup" id="g"><shape type="instance"><ref id="h"/></shape></shape>'
            '<shape type="shapegroup" id="h"><shape type="cube"/></shape><shape type="instance"><ref id="g"/></shape>',
            "nested instancing",
        ),
        ('<shape type="instance"><shape type="cube"/></shape>', "exactly one shapegroup"),
    ],
)
def test_what_mitsuba_refuses_is_one_line_naming_the_element(tmp_path, body, says):
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(_xml(tmp_path, 8, body))
    assert says in str(error.value) and "instances.xml" in str(error.value) and "\n" not in str(error.value)


@pytest.mark.peer
def test_instances_meet_rays_where_mitsuba_does(tmp_path, kernel_runner, mitsuba_scalar_spectral):
    """Rays through the instances: the hit distance and normal match Mitsuba's ray_intersect."""
    mi = mitsuba_scalar_spectral
    path = _xml(tmp_path, 8)
    ours = load_mitsuba_scene(path)
    theirs = mi.load_file(str(path))
    rng = np.random.default_rng(17)
    n = 400
    origins = np.array([0.0, 0.0, 0.3]) + rng.normal(size=(n, 3)) * [2.5, 2.5, 1.0]
    origins[:, 2] = np.abs(origins[:, 2]) + 0.5  # above the floor
    directions = rng.uniform([-1.4, -0.6, 0.0], [1.4, 0.8, 0.6], (n, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    _, out = _trace(kernel_runner, ours, origins, directions, np.full(n, 1e9))
    hit, normal = out[0], out[2]
    compared = disagreed = 0
    for i in range(n):
        si = theirs.ray_intersect(mi.Ray3f(origins[i].tolist(), directions[i].tolist()))
        if not si.is_valid() and not np.isfinite(hit[i, 0]):
            continue
        if si.is_valid() != bool(np.isfinite(hit[i, 0])):
            disagreed += 1  # a ray through an edge
            continue
        compared += 1
        assert hit[i, 0] == pytest.approx(float(si.t), rel=1e-4, abs=1e-5)
        np.testing.assert_allclose(np.abs(normal[i, :3] @ np.array(si.n)), 1.0, atol=1e-4)
    assert compared > 300 and disagreed <= 2


@pytest.mark.peer
@pytest.mark.slow
def test_instanced_scene_renders_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, 16 independent images each; 8 x 8-pixel block means and the image mean agree within
    5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 16, 8, 32, 8
    path = _xml(tmp_path, size)
    assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)


@pytest.mark.peer
@pytest.mark.parametrize("group", ["meshes", "analytic"])
def test_exported_instances_are_mitsubas_shapegroups_again(tmp_path, mitsuba_scalar_spectral, group):
    """The imported scene exported back (spectrace.interop.mitsuba.export: objects as shapegroups, instances as
    instances) meets every ray where Mitsuba's own load of the file does."""
    from spectrace.interop.mitsuba.export import scene_to_mitsuba_dict

    mi = mitsuba_scalar_spectral
    # The export covers the materials the peer benchmark uses: the gold card and the plastic ball become diffuse.
    source = GROUP if group == "meshes" else ANALYTIC_GROUP
    body = re.sub(r'<bsdf type="rough(conductor|plastic)">.*?</bsdf>', '<bsdf type="diffuse"/>', source, flags=re.S)
    path = _xml(tmp_path, 8, body)
    exported = scene_to_mitsuba_dict(load_mitsuba_scene(path), tmp_path / "meshes")
    assert sum(entry.get("type") == "instance" for entry in exported.values() if isinstance(entry, dict)) == 3
    original, again = mi.load_file(str(path)), mi.load_dict(exported)
    rng = np.random.default_rng(5)
    hits = 0
    for _ in range(300):
        origin = rng.normal(size=3) * [2.5, 2.5, 1.0] + [0, 0, 1.2]
        direction = rng.uniform([-1.4, -0.6, 0.0], [1.4, 0.8, 0.6]) - origin
        ray = mi.Ray3f(origin.tolist(), (direction / np.linalg.norm(direction)).tolist())
        a, b = original.ray_intersect(ray), again.ray_intersect(ray)
        assert a.is_valid() == b.is_valid()
        if a.is_valid():
            hits += 1
            assert float(b.t) == pytest.approx(float(a.t), rel=1e-5)
    assert hits > 200


def test_shapegroup_keeps_spheres_disks_and_cylinders_exact(tmp_path):
    scene = load_mitsuba_scene(_xml(tmp_path, 8, ANALYTIC_GROUP))
    shapes = scene.instances[0].object.shapes
    assert [s.analytic.kind if s.analytic else None for s in shapes] == ["sphere", "disk", "cylinder"]
    centre, radius = shapes[0].analytic.sphere_centre_radius()
    np.testing.assert_allclose(centre, [0, 0, 0.35], atol=1e-12)
    assert radius == pytest.approx(0.3)


@pytest.mark.peer
def test_instanced_analytic_shapes_meet_rays_where_mitsuba_does(tmp_path, kernel_runner, mitsuba_scalar_spectral):
    """Hit distance, normal and texture coordinates of Mitsuba's ray_intersect on the stretched, sheared and mirrored
    instances of its sphere, disk and cylinder."""
    mi = mitsuba_scalar_spectral
    path = _xml(tmp_path, 8, ANALYTIC_GROUP)
    ours = load_mitsuba_scene(path)
    theirs = mi.load_file(str(path))
    rng = np.random.default_rng(23)
    n = 600
    origins = np.array([0.0, 0.0, 0.3]) + rng.normal(size=(n, 3)) * [2.5, 2.5, 1.0]
    origins[:, 2] = np.abs(origins[:, 2]) + 0.6
    directions = rng.uniform([-1.6, -0.6, 0.0], [1.8, 1.0, 0.8], (n, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    buffers, out = _trace(kernel_runner, ours, origins, directions, np.full(n, 1e9))
    assert buffers.instanced_shape_count == 3
    hit, normal = out[0], out[2]
    compared = disagreed = on_shapes = 0
    for i in range(n):
        si = theirs.ray_intersect(mi.Ray3f(origins[i].tolist(), directions[i].tolist()))
        if not si.is_valid() and not np.isfinite(hit[i, 0]):
            continue
        if si.is_valid() != bool(np.isfinite(hit[i, 0])):
            disagreed += 1  # a ray grazing a rim
            continue
        compared += 1
        assert hit[i, 0] == pytest.approx(float(si.t), rel=1e-4, abs=1e-5)
        np.testing.assert_allclose(normal[i, :3] @ np.array(si.n), 1.0, atol=2e-4)  # the same side, too
        if si.shape.shape_type() != int(mi.ShapeType.Rectangle):
            on_shapes += 1
            du = (hit[i, 1:3] - np.array(si.uv) + 0.5) % 1.0 - 0.5  # u (or the disk's v) wraps at the seam
            np.testing.assert_allclose(du, 0.0, atol=2e-3)
    assert compared > 400 and disagreed <= 3 and on_shapes > 100


@pytest.mark.peer
@pytest.mark.slow
def test_instanced_analytic_shapes_render_like_mitsuba(tmp_path, device, mitsuba_scalar_spectral):
    """Both renderers, spectral, 16 independent images each; 8 x 8-pixel block means and the image mean agree within
    5 standard errors (tests/replica_agreement.py)."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 16, 8, 32, 8
    path = _xml(tmp_path, size, ANALYTIC_GROUP)
    assert_renders_like_mitsuba(mi, path, device, replicas, replica_spp, block)
