"""Export of a spectrace scene to Mitsuba 3 (the peer benchmark's input): the bundled Cornell box, with its
measured spectra, rendered by both renderers must give the same film XYZ within the noise; what has no faithful
Mitsuba counterpart is refused; the mesh files carry the triangles exactly (as float32)."""

from dataclasses import replace

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace import plastic as make_plastic
from spectrace.engine.renderer import Renderer
from spectrace.errors import SpectraceError
from spectrace.geometry.primitives import rectangle, sphere
from spectrace.geometry.transforms import apply_transform
from spectrace.interop.mitsuba.export import mitsuba_film_xyz, scene_to_mitsuba_dict, write_binary_ply
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene
from spectrace.scene.model import AreaEmitter, Camera, DiffuseMaterial, Scene, Shape, SpotLight
from spectrace.spectral import spectrum_to_xyz
from spectrace.spectral.spectrum import Spectrum
from spectrace.spectral.spectrum_input import rgb_reflectance


@pytest.mark.peer
@pytest.mark.slow
def test_exported_cornell_box_renders_like_spectrace(tmp_path, device, mitsuba_scalar_spectral):
    """REPLICAS independent images of REPLICA_SPP samples from each renderer, depth 5 with Russian roulette from
    bounce 2 (so the roulette's semantics matter); film XYZ means over 8 x 8-pixel blocks and over the whole image
    must agree within 5 standard errors of the difference (from the replicas' spread). The light is inside the
    top-middle blocks, so its measured emission spectrum is compared too. Measured: whole-image means within
    2.5 standard errors; the light's radiance scaled by 1.03 in the export fails at 8 standard errors."""
    mi = mitsuba_scalar_spectral
    replicas, replica_spp, size, block = 24, 32, 32, 8
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(
        width=size, height=size, max_depth=5, rr_depth=2
    )
    mitsuba_scene = mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path, spp=replica_spp))
    by_mitsuba = np.stack(
        [mitsuba_film_xyz(mi.render(mitsuba_scene, spp=replica_spp, seed=seed), mi) for seed in range(replicas)]
    )

    by_spectrace = spectrace_replicas(Renderer(scene, device), replicas, replica_spp)
    assert_replicas_agree(by_spectrace, by_mitsuba, block)
    assert by_mitsuba[..., 1].mean() > 0.05  # the comparison saw a lit image


@pytest.mark.peer
@pytest.mark.parametrize("emission", ["constant 1", "Cornell box light"])
def test_film_xyz_normalisation_matches_the_integral(tmp_path, device, emission, mitsuba_scalar_spectral):
    """A view filled by one emitter, emitters only (max_depth 1): each renderer's mean film XYZ must equal the
    emission's ∫ L cmf dλ / ∫ ȳ dλ within 5 standard errors (per-pixel spread; only the wavelengths are random).
    Without mitsuba_film_xyz Mitsuba's Y is 0.1 % high, which fails here."""
    mi = mitsuba_scalar_spectral
    if emission == "constant 1":
        radiance = Spectrum.constant(1.0)
    else:
        cornell = load_scene(scenes_dir() / "cornell_box.toml")
        radiance = next(shape for shape in cornell.shapes if shape.emitter is not None).emitter.radiance
    wall = apply_transform(rectangle(), np.diag([10.0, 10.0, 1.0, 1.0]))
    scene = Scene(
        camera=Camera(origin=(0, 0, 2), target=(0, 0, 0), fov_degrees=30),
        width=48,
        height=48,
        shapes=[Shape(mesh=wall, material=DiffuseMaterial(Spectrum.constant(0.5)), emitter=AreaEmitter(radiance))],
        max_depth=1,
        spp=128,
    )
    expected = spectrum_to_xyz(radiance)
    ours = Renderer(scene, device).render().xyz.reshape(-1, 3).astype(np.float64)
    theirs = mitsuba_film_xyz(mi.render(mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path))), mi).reshape(-1, 3)
    for image in (ours, theirs):
        standard_error = image.std(axis=0, ddof=1) / np.sqrt(len(image))
        assert np.all(np.abs(image.mean(axis=0) - expected) <= 5 * standard_error), (
            image.mean(axis=0) / expected,
            standard_error / expected,
        )


@pytest.mark.peer
def test_what_mitsuba_cannot_match_is_refused(tmp_path, mitsuba_scalar_spectral):
    scene = load_scene(scenes_dir() / "cornell_box.toml")
    spot = SpotLight(position=(0.3, 0.5, 0.3), direction=(0, -1, 0), intensity=Spectrum.constant(1.0))
    with pytest.raises(SpectraceError, match="SpotLight has no equivalent Mitsuba emitter"):
        scene_to_mitsuba_dict(replace(scene, lights=[spot]), tmp_path)
    with pytest.raises(SpectraceError, match="integrator 'direct'"):
        scene_to_mitsuba_dict(replace(scene, integrator="direct"), tmp_path)
    light = next(shape for shape in scene.shapes if shape.emitter is not None)
    two_sided = replace(light, emitter=replace(light.emitter, two_sided=True))
    with pytest.raises(SpectraceError, match="one-sided"):
        scene_to_mitsuba_dict(replace(scene, shapes=[two_sided]), tmp_path)
    polarised = replace(light, emitter=replace(light.emitter, stokes=(1.0, 0.0, 0.0)))
    with pytest.raises(SpectraceError, match="Mitsuba's area light is unpolarised"):
        scene_to_mitsuba_dict(replace(scene, shapes=[polarised]), tmp_path)


def test_ply_files_hold_the_triangles(tmp_path):
    import trimesh

    mesh = sphere(2)
    path = tmp_path / "ball.ply"
    write_binary_ply(mesh, path)
    loaded = trimesh.load(path, process=False, maintain_order=True)
    np.testing.assert_array_equal(np.asarray(loaded.faces), mesh.faces)
    np.testing.assert_array_equal(np.asarray(loaded.vertices), mesh.vertices.astype(np.float32))
    # the sphere's vertex normals go along (smooth shading in both renderers); a flat mesh has none
    np.testing.assert_allclose(np.asarray(loaded.vertex_normals), mesh.normals, atol=1e-6)
    flat = tmp_path / "flat.ply"
    write_binary_ply(mesh.with_normals(None), flat)
    assert b"property float nx" in path.read_bytes()[:400] and b"property float nx" not in flat.read_bytes()[:400]


@pytest.mark.peer
def test_peer_sampler_is_exported_and_checked(tmp_path, mitsuba_scalar_spectral):
    """The bench may give Mitsuba any of its samplers (stratified ones are the fair match for spectrace's Sobol);
    the export carries the choice, and a misspelt one is refused in one line naming the option."""
    mi = mitsuba_scalar_spectral
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=8, height=8)
    for sampler in ("independent", "multijitter"):
        scene_dict = scene_to_mitsuba_dict(scene, tmp_path, spp=4, sampler=sampler)
        assert scene_dict["sensor"]["sampler"] == {"type": sampler, "sample_count": 4}
        assert mi.load_dict(scene_dict).sensors()[0].sampler().sample_count() == 4
    with pytest.raises(SpectraceError, match="unknown Mitsuba sampler 'sobol'") as error:
        scene_to_mitsuba_dict(scene, tmp_path, sampler="sobol")
    assert error.value.where == "--peer-sampler"


@pytest.mark.peer
def test_analytic_shapes_export_as_mitsubas_own(tmp_path, mitsuba_scalar_spectral):
    """Analytic shapes become Mitsuba's sphere, disk and cylinder with the same map and facing: the same area and
    bounds, and Mitsuba's normal where a ray meets them is spectrace's front (flip_normals too)."""
    import spectrace

    mi = mitsuba_scalar_spectral
    grey = DiffuseMaterial(Spectrum.constant(0.5))
    shapes = [
        spectrace.shape("sphere", grey, center=[0.5, 0, 0], radius=0.4, flip_normals=True, name="ball"),
        spectrace.shape("disk", grey, transform=[{"scale": [1, 0.5, 1]}, {"translate": [0, 0, -1]}], name="floor"),
        spectrace.shape("cylinder", grey, transform=[{"scale": [0.3, 0.3, 2]}, {"translate": [-1, 0, -1]}]),
    ]
    scene = Scene(camera=Camera(origin=(0, -4, 0), target=(0, 0, 0)), width=8, height=8, shapes=shapes)
    exported = mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path, spp=1))
    for shape, theirs in zip(shapes, exported.shapes()):
        assert theirs.surface_area() == pytest.approx(shape.analytic.area(), rel=1e-5)
        lo, hi = shape.analytic.bounds()
        np.testing.assert_allclose(np.array(theirs.bbox().min), lo, atol=1e-4)
        np.testing.assert_allclose(np.array(theirs.bbox().max), hi, atol=1e-4)
    ball = exported.shapes()[0].ray_intersect(mi.Ray3f([0.5, -3.0, 0.0], [0.0, 1.0, 0.0]))
    np.testing.assert_allclose(np.array(ball.n), [0.0, 1.0, 0.0], atol=1e-5)  # flipped: inward, toward +y there


@pytest.mark.peer
@pytest.mark.slow
def test_light_traced_cornell_box_exports_to_mitsubas_particle_tracer(tmp_path, device, mitsuba_scalar_spectral):
    """The light tracer's Cornell box, exported, is rendered by Mitsuba 3's ptracer: image means agree within 5
    standard errors of independent replicas (XYZ film, Mitsuba's rescaled to spectrace's convention)."""
    mi = mitsuba_scalar_spectral
    scene = load_scene(scenes_dir() / "cornell_box.toml").with_overrides(width=24, height=24, integrator="light")
    entries = scene_to_mitsuba_dict(scene, tmp_path)
    assert entries["integrator"]["type"] == "ptracer"
    loaded = mi.load_dict(entries)
    theirs = np.stack(
        [mitsuba_film_xyz(np.array(mi.render(loaded, spp=4, seed=seed)), mi).mean(axis=(0, 1)) for seed in range(8)]
    )
    ours = spectrace_replicas(Renderer(scene, device), 8, 4).mean(axis=(1, 2))
    difference = ours.mean(axis=0) - theirs.mean(axis=0)
    standard_error = np.sqrt(ours.var(axis=0, ddof=1) / 8 + theirs.var(axis=0, ddof=1) / 8)
    assert np.all(np.abs(difference) <= 5 * standard_error), difference / standard_error


@pytest.mark.peer
def test_an_emitting_sphere_under_a_mirror_exports_facing_out(tmp_path, device, mitsuba_scalar_spectral):
    """A pbrt-v4 scene's sphere light (pbrt's handedness makes the import mirror the world, so the sphere's matrix
    has a negative determinant): the exported sphere must face out as spectrace's does. Mitsuba turns a mirrored
    sphere's normals inward, which left the light black (measured: mean 0 against spectrace's 5.8). Means of the
    film Y within 5 standard errors."""
    from spectrace.interop.pbrt import load_pbrt_scene
    from spectrace.pixel_filters import BOX_FILTER

    mi = mitsuba_scalar_spectral
    path = tmp_path / "sphere.pbrt"
    path.write_text(
        'LookAt 0 0 3  0 0 0  0 1 0\nCamera "perspective" "float fov" 30\n'
        'Film "rgb" "integer xresolution" 16 "integer yresolution" 16\n'
        'Sampler "independent" "integer pixelsamples" 16\n'
        'WorldBegin\nAttributeBegin\nAreaLightSource "diffuse" "rgb L" [8 8 8]\nShape "sphere" "float radius" 0.75\n'
        "AttributeEnd\n"
    )
    scene = load_pbrt_scene(path).with_overrides(pixel_filter=BOX_FILTER)
    assert np.linalg.det(scene.shapes[0].analytic.linear) < 0
    ours = Renderer(scene, device).render().xyz.reshape(-1, 3).astype(np.float64)[:, 1]
    theirs = mitsuba_film_xyz(mi.render(mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path))), mi).reshape(-1, 3)[:, 1]
    assert ours.mean() > 1.0
    standard_error = np.sqrt(ours.var(ddof=1) / len(ours) + theirs.var(ddof=1) / len(theirs))
    assert abs(ours.mean() - theirs.mean()) <= 5 * standard_error, (ours.mean(), theirs.mean(), standard_error)


@pytest.mark.peer
@pytest.mark.parametrize(
    "material",
    [
        'Material "dielectric" "float eta" 1.5',
        'Material "dielectric" "float eta" 1.5 "float roughness" 0.04',
        # Plastics (a smooth coat, a rough one crossed by its own transmittance), put on the sphere after the
        # import: pbrt's coateddiffuse is the stochastic layered material, which Mitsuba 3 does not have.
        "plastic",
        "roughplastic",
    ],
)
def test_exported_dielectrics_and_plastics_render_like_spectrace(tmp_path, device, mitsuba_scalar_spectral, material):
    """A sphere of glass (smooth, rough) or of plastic (a smooth coat, a rough one crossed by its own
    transmittance) on a diffuse floor under a sky, imported from pbrt text and exported: 8 replicas of
    16 spp from each renderer, 8 x 8-pixel block means and the image mean within 5 standard errors."""
    from spectrace.interop.pbrt import load_pbrt_scene
    from spectrace.pixel_filters import BOX_FILTER

    mi = mitsuba_scalar_spectral
    path = tmp_path / "sphere.pbrt"
    sphere_material = material if material.startswith("Material") else 'Material "diffuse"'
    path.write_text(
        'LookAt 0 1 4  0 0.5 0  0 1 0\nCamera "perspective" "float fov" 35\n'
        'Film "rgb" "integer xresolution" 16 "integer yresolution" 16\nIntegrator "path" "integer maxdepth" 6\n'
        'WorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\n'
        'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [6 6 6]\n'
        'Translate 1 3 1\nShape "sphere" "float radius" 0.4\nAttributeEnd\n'
        'Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]\n'
        'Shape "trianglemesh" "point3 P" [-5 0 -5  5 0 -5  5 0 5  -5 0 5] "integer indices" [0 1 2  0 2 3]\n'
        f"{sphere_material}\n"
        'AttributeBegin\nTranslate 0 0.6 0\nShape "sphere" "float radius" 0.6\nAttributeEnd\n'
    )
    scene = load_pbrt_scene(path).with_overrides(pixel_filter=BOX_FILTER)
    if not material.startswith("Material"):
        rough = {"roughness": 0.2, "coat_transmission": "rough"} if material == "roughplastic" else {}
        plastic = make_plastic(rgb_reflectance([0.7, 0.2, 0.1]), nonlinear=True, **rough)
        scene = replace(scene, shapes=[*scene.shapes[:-1], replace(scene.shapes[-1], material=plastic)])
    mitsuba_scene = mi.load_dict(scene_to_mitsuba_dict(scene, tmp_path, spp=16))
    by_mitsuba = np.stack([mitsuba_film_xyz(mi.render(mitsuba_scene, spp=16, seed=seed), mi) for seed in range(8)])
    assert_replicas_agree(spectrace_replicas(Renderer(scene, device), 8, 16), by_mitsuba, 8)
    assert by_mitsuba[..., 1].mean() > 0.05


@pytest.mark.peer
def test_a_shape_with_an_interior_medium_is_refused(tmp_path, mitsuba_scalar_spectral):
    """The export wrote such a glass without its medium (a 9 % brighter image of a pbrt scene with coloured gems)."""
    from spectrace.interop.pbrt import load_pbrt_scene

    path = tmp_path / "gem.pbrt"
    path.write_text(
        'LookAt 0 0 4  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\n'
        'MakeNamedMedium "ruby" "string type" "homogeneous" "rgb sigma_a" [0.01 0.2 0.5] "rgb sigma_s" [0 0 0]\n'
        'Material "dielectric" "float eta" 1.7\nMediumInterface "ruby" ""\nShape "sphere"\n'
    )
    from spectrace.pixel_filters import BOX_FILTER

    scene = load_pbrt_scene(path).with_overrides(pixel_filter=BOX_FILTER)
    with pytest.raises(SpectraceError, match="interior medium"):
        scene_to_mitsuba_dict(scene, tmp_path)


def test_each_exported_bitmap_gets_its_own_image_file(tmp_path, monkeypatch, mitsuba_scalar_spectral):
    """The export writes each bitmap's linear values once and names that file in the bitmap's entry. Those values
    are often a temporary (a grey image repeated into RGB, float64 texels made float32), freed once written, whose
    id() the next one may get: every bitmap must still name a file of its own values. The second round makes every
    id() the same, as a freed array's is for the next one, since the interpreter reuses ids only at times."""
    from spectrace.interop.mitsuba import export as mitsuba_export
    from spectrace.io.exr import read_exr
    from spectrace.textures import bitmap

    greys = [0.125 * k for k in range(1, 8)]
    for round_ in ("ids as they come", "every id the same"):
        if round_ == "every id the same":
            monkeypatch.setattr(mitsuba_export, "id", lambda _: 1, raising=False)
        folder = tmp_path / round_.replace(" ", "-")
        folder.mkdir()
        exporter = mitsuba_export.MitsubaExport(None, folder)  # type: ignore[arg-type]
        for grey in greys:
            entry = bitmap.to_mitsuba(bitmap.make(np.full((2, 3, 1), grey), filter="nearest"), exporter)
            channels, _ = read_exr(entry["filename"])
            assert np.all(channels["RGB"] == np.float32(grey)), (round_, grey, entry["filename"])
        assert len(list(folder.glob("*.exr"))) == len(greys), round_
