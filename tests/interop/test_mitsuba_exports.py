"""What scenes exported from Blender (the mitsuba-blender add-on) write, imported as Mitsuba 3 reads it: booleans in
any case, a dielectric's tints of exactly 1 written out, and a homogeneous medium's coefficients held in a
`constvolume`. Checked against Mitsuba 3 itself (what its parser accepts, what its BSDF returns, its render) and
by the exact tables the import writes."""

from pathlib import Path

import numpy as np
import pytest

from replica_agreement import assert_renders_like_mitsuba
from spectrace.errors import SpectraceError
from spectrace.interop.mitsuba import mitsuba_scene_data

SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>"""


def _write(folder: Path, body: str, name: str = "scene.xml") -> Path:
    path = folder / name
    path.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n</scene>\n')
    return path


# ---------------------------------------------------------------- booleans

# Mitsuba 3's parser lower-cases a boolean's text and takes exactly "true" or "false": nothing around it, no 1.
ACCEPTED = {"true": True, "True": True, "TRUE": True, "tRuE": True, "false": False, "False": False, "FALSE": False}
REFUSED = (" true", "true ", "1", "0", "yes", "", "trüe")


def _flipped_sphere(value: str) -> str:
    return f'<shape type="sphere"><boolean name="flip_normals" value="{value}"/></shape>'


@pytest.mark.parametrize("text", list(ACCEPTED))
def test_booleans_are_read_in_any_case(tmp_path, text):
    body = _flipped_sphere(text) + f'<shape type="sphere"><boolean name="face_normals" value="{text}"/></shape>'
    flipped, faceted = mitsuba_scene_data(_write(tmp_path, body))[0]["shapes"]
    assert flipped.get("flip_normals", False) is ACCEPTED[text]
    assert faceted.get("face_normals", False) is ACCEPTED[text]


@pytest.mark.parametrize("text", REFUSED)
def test_other_boolean_text_is_one_line_at_the_value(tmp_path, text):
    path = _write(tmp_path, _flipped_sphere(text))
    with pytest.raises(SpectraceError, match="expected true or false") as error:
        mitsuba_scene_data(path)
    assert error.value.where == f"{path}: shape/boolean@value"
    assert "\n" not in str(error.value)


@pytest.mark.peer
def test_the_booleans_accepted_are_those_mitsuba_accepts(mitsuba_scalar_spectral):
    mi = mitsuba_scalar_spectral
    for text in (*ACCEPTED, *REFUSED):
        xml = f'<scene version="3.0.0">{_flipped_sphere(text)}</scene>'
        try:
            mi.load_string(xml)
            theirs = True
        except RuntimeError:
            theirs = False
        assert theirs == (text in ACCEPTED), text


# ---------------------------------------------------------------- dielectric tints of 1

ONE = {
    "float": '<float name="{key}" value="1"/>',
    "rgb": '<rgb name="{key}" value="1, 1, 1"/>',
    "spectrum": '<spectrum name="{key}" value="400:1, 700:1"/>',
}


@pytest.mark.parametrize("kind", ["dielectric", "roughdielectric"])
@pytest.mark.parametrize("form", list(ONE))
def test_an_explicit_tint_of_one_is_mitsubas_default(tmp_path, kind, form):
    """specular_transmittance (or specular_reflectance) written as 1, alone or beside the other, imports as the
    untinted dielectric; a tint beside a 1 is still refused (spectrace's one tint covers both lobes)."""
    plain = mitsuba_scene_data(_write(tmp_path, f'<shape type="sphere"><bsdf type="{kind}"/></shape>'))[0]
    both = ["specular_reflectance", "specular_transmittance"]
    for keys in (both[1:], both[:1], both):
        tints = "".join(ONE[form].format(key=key) for key in keys)
        body = f'<shape type="sphere"><bsdf type="{kind}">{tints}</bsdf></shape>'
        assert mitsuba_scene_data(_write(tmp_path, body))[0]["materials"] == plain["materials"], keys
    half = '<rgb name="specular_reflectance" value="0.5, 0.5, 0.5"/>' + ONE[form].format(key="specular_transmittance")
    with pytest.raises(SpectraceError, match="specular_reflectance different from specular_transmittance"):
        mitsuba_scene_data(_write(tmp_path, f'<shape type="sphere"><bsdf type="{kind}">{half}</bsdf></shape>'))


def test_equal_tints_other_than_one_stay_one_tint(tmp_path):
    tints = "".join(
        f'<rgb name="{key}" value="0.8, 0.7, 0.6"/>' for key in ("specular_reflectance", "specular_transmittance")
    )
    body = f'<shape type="sphere"><bsdf type="dielectric">{tints}</bsdf></shape>'
    (table,) = mitsuba_scene_data(_write(tmp_path, body))[0]["materials"].values()
    assert table["specular_tint"] == {"rgb": [0.8, 0.7, 0.6]}


@pytest.mark.peer
@pytest.mark.parametrize("form", list(ONE))
def test_mitsuba_renders_a_tint_of_one_as_no_tint(mitsuba_scalar_spectral, form):
    """Mitsuba's dielectric returns the same sample (direction, weight) with specular_transmittance = 1 written out
    as without it, at incidences where both lobes are chosen: the value it treats as its default."""
    mi = mitsuba_scalar_spectral

    def bsdf(extra: str):
        return mi.load_string(f'<bsdf version="3.0.0" type="dielectric">{extra}</bsdf>')

    default, explicit = bsdf(""), bsdf(ONE[form].format(key="specular_transmittance"))
    interaction = mi.SurfaceInteraction3f()
    interaction.wavelengths = [450.0, 500.0, 600.0, 700.0]
    for cos_theta in (1.0, 0.6, 0.2):
        interaction.wi = mi.Vector3f(np.sqrt(1 - cos_theta**2), 0.0, cos_theta)
        for u in (0.01, 0.5, 0.99):  # reflection and transmission
            a_sample, a_weight = default.sample(mi.BSDFContext(), interaction, u, mi.Point2f(0.5, 0.5))
            b_sample, b_weight = explicit.sample(mi.BSDFContext(), interaction, u, mi.Point2f(0.5, 0.5))
            np.testing.assert_array_equal(np.array(a_sample.wo), np.array(b_sample.wo))
            np.testing.assert_array_equal(np.array(a_weight), np.array(b_weight))


# ---------------------------------------------------------------- constvolume

CUBE = """<shape type="cube"><bsdf type="null"/><medium type="homogeneous" name="interior">
    {sigma_t}{albedo}<float name="scale" value="1.5"/><phase type="hg"><float name="g" value="0.4"/></phase>
  </medium></shape>"""


def _constant(key: str, value: str) -> str:
    return f'<volume type="constvolume" name="{key}">{value.format(key="value")}</volume>'


@pytest.mark.parametrize(
    "sigma_t, albedo",
    [
        ('<float name="{key}" value="2"/>', '<float name="{key}" value="0.8"/>'),
        ('<float name="{key}" value="2"/>', '<rgb name="{key}" value="0.9, 0.6, 0.3"/>'),
        ('<rgb name="{key}" value="0.9, 0.5, 0.2"/>', '<rgb name="{key}" value="0.95, 0.6, 0.3"/>'),
    ],
    ids=["numbers", "rgb_albedo", "rgb_both"],
)
def test_a_constvolume_is_the_spectrum_it_holds(tmp_path, sigma_t, albedo):
    """Mitsuba makes a spectrum written in place into a constvolume of it: both import as the same interior."""
    in_place = CUBE.format(sigma_t=sigma_t.format(key="sigma_t"), albedo=albedo.format(key="albedo"))
    held = CUBE.format(sigma_t=_constant("sigma_t", sigma_t), albedo=_constant("albedo", albedo))
    expected = mitsuba_scene_data(_write(tmp_path, in_place, "in_place.xml"))[0]["shapes"][0]["interior"]
    data, notes = mitsuba_scene_data(_write(tmp_path, held, "held.xml"))
    assert data["shapes"][0]["interior"] == expected
    assert not [note for note in notes if "volume" in note], notes


def test_a_constvolume_without_value_is_one(tmp_path):
    """Mitsuba's constvolume defaults to 1: σt = 1 · scale, albedo 1 (nothing absorbed)."""
    body = CUBE.format(sigma_t='<volume type="constvolume" name="sigma_t"/>', albedo=_constant("albedo", ""))
    interior = mitsuba_scene_data(_write(tmp_path, body))[0]["shapes"][0]["interior"]
    assert interior == {"sigma_a": {"value": 0.0}, "sigma_s": {"value": 1.5}, "g": 0.4}


def test_a_gridvolume_is_refused_in_one_line(tmp_path):
    grid = '<volume type="gridvolume" name="sigma_t"><string name="filename" value="smoke.vol"/></volume>'
    path = _write(tmp_path, CUBE.format(sigma_t=grid, albedo=""))
    with pytest.raises(SpectraceError) as error:
        mitsuba_scene_data(path)
    message = str(error.value)
    assert "\n" not in message
    assert "volume 'gridvolume' as a homogeneous medium's sigma_t (constvolume only" in message
    assert "coloured" not in message  # the gridvolume is named once, not again as a colour


@pytest.mark.peer
def test_a_constvolume_cube_renders_like_mitsuba_volpath(tmp_path, device, mitsuba_scalar_spectral):
    """A cube of a medium whose σt and rgb albedo are constvolumes, in a uniform environment: both renderers
    spectral, 16 replicas of 8 spp, 8 x 8-pixel block means and the image mean within 5 standard errors."""
    mi = mitsuba_scalar_spectral
    medium = CUBE.format(
        sigma_t=_constant("sigma_t", '<float name="{key}" value="2"/>'),
        albedo=_constant("albedo", '<rgb name="{key}" value="0.95, 0.6, 0.3"/>'),
    )
    path = tmp_path / "constvolume.xml"
    path.write_text(
        f"""<scene version="3.0.0">
<integrator type="volpath"><integer name="max_depth" value="16"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/>
  <transform name="to_world"><lookat origin="0, -4, 1" target="0, 0, 0" up="0, 0, 1"/></transform>
  <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
  <rfilter type="box"/></film></sensor>
<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
{medium}
</scene>
"""
    )
    by_mitsuba = assert_renders_like_mitsuba(mi, path, device, 16, 8, 8)
    # The medium is seen, and coloured: the cube's centre is darker than the open environment, and not grey.
    centre = by_mitsuba[:, 12:20, 12:20].mean(axis=(0, 1, 2))
    assert centre.sum() < 0.8 * by_mitsuba[:, :4, :4].mean(axis=(0, 1, 2)).sum()
    assert centre[0] > 1.2 * centre[2]
