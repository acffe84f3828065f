"""Colours, spectra and textures: what a spectrum-valued property may hold. In Mitsuba 3 a spectrum is a texture
plugin (uniform, regular, irregular, blackbody, d65, srgb), so both are read here.

Spectra: rgb (uplifted exactly as Mitsuba does: Jakob & Hanika 2019, emission D65-based), float, spectrum given as
a value, "λ:v" pairs, wavelengths/values or an .spd file, and the spectrum plugins. A <texture> (by id or inline)
becomes a [textures] table wherever a spectrum may be, converted by its spectrace module (spectrace.textures.<name>:
MITSUBA_PLUGINS, `from_mitsuba`); it is kept exactly where the material's or light's parameter table marks the
parameter `textured` (`checked_textures`), so a parameter that becomes textured there imports textures without a
change here.
"""

from __future__ import annotations

import math

import numpy as np

from spectrace.interop.mitsuba.context import FLOAT32_MAX, ImportContext, unique_name
from spectrace.interop.mitsuba.plugins import SPECTRUM_PLUGINS, TEXTURE_MODULES
from spectrace.interop.mitsuba.transforms import to_world
from spectrace.interop.mitsuba.tree import Element, read_input_file, shown
from spectrace.number_text import DECIMAL
from spectrace.textures import TEXTURES


def spectrum(ctx: ImportContext, element: Element, key: str) -> dict | None:
    """A spectrace spectrum table for a Mitsuba colour/spectrum property, or None (unsupported, recorded)."""
    element = ctx.resolve(element)
    with ctx.converting(element):
        return _spectrum(ctx, element, key)


def _spectrum(ctx: ImportContext, element: Element, key: str) -> dict | None:
    if element.tag == "rgb":
        values = ctx.numbers(element, "value")
        if len(values) not in (1, 3):
            raise ctx.fail(element, f"an rgb colour needs 3 numbers (or 1), got {len(values)}", "value")
        ctx.non_negative(values, element, "value")
        return {"rgb": values * 3 if len(values) == 1 else values}
    if element.tag == "float":
        value = ctx.number(element)
        ctx.non_negative([value], element, "value")
        return {"value": value}
    if element.tag == "spectrum":
        return spectrum_element(ctx, element)
    if element.tag == "texture":
        return texture(ctx, element, key)
    raise ctx.fail(element, f"'{key}' must be a colour or spectrum, got <{shown(element.tag)}>")


def texture(ctx: ImportContext, element: Element, key: str) -> dict | None:
    """A <texture> where a spectrum may be: a reference to its [textures] table, converted by its module on
    first use (once more, v flipped, for shapes whose v runs up). Whether the parameter takes a texture is
    decided by the material's or light's parameter table (`checked_textures`), not here."""
    if ctx.kind(element) in SPECTRUM_PLUGINS:  # Mitsuba 3's spectra are textures; its serialiser says so
        return spectrum_element(ctx, element)
    ctx.used_texture = True
    cache = (id(element), ctx.flip_v)
    if cache in ctx.texture_of_element:
        return {"texture": ctx.texture_of_element[cache]}
    module = TEXTURE_MODULES.get(ctx.kind(element))
    if module is None:
        ctx.unsupported_object(element, f" as {key}")
        return None
    table = module.from_mitsuba(ctx, element, ctx.properties(element))
    if table is None:
        return None
    base = (ctx.attribute(element, "id") or f"{key}_texture") + ("_flipped_v" if ctx.flip_v else "")
    name = unique_name(base, {**ctx.textures, **TEXTURES})  # a texture named after a type is ambiguous
    ctx.textures[name] = table
    ctx.texture_of_element[cache] = name
    ctx.texture_elements[name] = element
    ctx.origins[f"textures.{name}"] = element
    return {"texture": name}


def scalar_texture(ctx: ImportContext, element: Element, key: str) -> dict | None:
    """A texture where Mitsuba reads one number per point (a bump map's height, an opacity, an α, a blend's
    weight): an RGB bitmap there gives its luminance in Mitsuba, so it is imported as a texture of its own with
    luminance = true (a grey one as it is); a checkerboard there shows its sides the other way round (Mitsuba 3's
    number lookup puts color1 where its colour lookup puts color0), so it is imported with them swapped."""
    known = set(ctx.textures)
    reference = texture(ctx, element, key)
    if reference is None or list(reference) != ["texture"]:
        return reference
    name = reference["texture"]
    table = ctx.textures[name]
    if table["type"] == "checkerboard":
        return _checkerboard_as_number(ctx, name, name not in known)
    if table["type"] != "bitmap" or table.get("luminance"):
        return reference
    from spectrace.io.images import read_texture_image

    values, _ = read_texture_image(ctx.toml_folder / table["file"], f"{ctx.xml_path}: {key}")
    if values.shape[-1] == 1:
        return reference
    if name not in known:  # made for this use: it becomes the luminance, and a colour use makes its own
        table["luminance"] = True
        ctx.texture_of_element = {k: v for k, v in ctx.texture_of_element.items() if v != name}
        return reference
    grey = f"{name}_luminance"
    if grey not in ctx.textures:
        ctx.textures[grey] = table | {"luminance": True}
        ctx.texture_elements[grey] = ctx.texture_elements[name]
        ctx.origins[f"textures.{grey}"] = ctx.texture_elements[name]
    return {"texture": grey}


def texture_type(ctx: ImportContext, name: str) -> str:
    return ctx.textures[name]["type"]


def checked_textures(ctx: ImportContext, table: dict, module) -> bool:
    """False, recording each, where a texture was given to a parameter that `module`'s parameter table does not
    mark `textured`: marking one there is all it takes for the import to pass textures on to it."""
    textured = {parameter.name for parameter in module.PARAMETERS if parameter.textured}
    fine = True
    for key, value in table.items():
        if isinstance(value, dict) and list(value) == ["texture"] and key not in textured:
            ctx.unsupported_plugin(
                ctx.texture_elements[value["texture"]],
                f" as {key} of {module.NAME} (spectrace's {module.NAME} takes no texture there)",
            )
            fine = False
    return fine


def uv_placement(
    ctx: ImportContext, texture: Element, properties: dict[str, Element], squares: float = 1.0
) -> dict | None:
    """uv_scale and uv_offset for a texture's `to_uv`, which spectrace represents when it scales and translates
    (st = uv · uv_scale + uv_offset); `squares` multiplies both (a checkerboard's squares per unit of Mitsuba's
    uv'). Only what differs from the default (squares, 0) is written."""
    scale, offset = [1.0, 1.0], [0.0, 0.0]
    if "to_uv" in properties:
        element = ctx.resolve(properties["to_uv"])
        if element.tag != "transform":
            raise ctx.fail(element, f"to_uv must be a <transform>, got <{shown(element.tag)}>")
        matrix = to_world(ctx, properties, "to_uv")
        # Mitsuba keeps the 2D affine part of the 4 x 4 matrix (x and y rows and columns, and the translation).
        if matrix[0, 1] != 0.0 or matrix[1, 0] != 0.0:
            ctx.unsupported_plugin(
                texture, " with a to_uv that rotates or shears (spectrace's textures take uv_scale and uv_offset)"
            )
            return None
        scale, offset = [matrix[0, 0], matrix[1, 1]], [matrix[0, 3], matrix[1, 3]]
    if ctx.flip_v:  # the lookup at (u, 1 - v): st_v = -scale_v · v + scale_v + offset_v
        scale, offset = [scale[0], -scale[1]], [offset[0], scale[1] + offset[1]]
    table = {}
    if scale != [1.0, 1.0]:
        table["uv_scale"] = [float(squares * value) for value in scale]
    if offset != [0.0, 0.0]:
        table["uv_offset"] = [float(squares * value) for value in offset]
    return table


def spectrum_element(ctx: ImportContext, element: Element) -> dict | None:
    kind = element.get("type")
    if kind is None:
        if element.get("filename") is not None:
            return {"values": spd_file(ctx, element)}
        if element.get("wavelengths") is not None:
            wavelengths = ctx.numbers(element, "wavelengths")
            values = ctx.numbers(element, "values")
            return {"values": pairs(ctx, element, wavelengths, values, "values")}
        text = ctx.required(element, "value")
        if ":" in text:
            wavelengths, values = [], []
            for entry in (entry.strip() for entry in text.split(",")):
                parts = entry.split(":")
                if len(parts) != 2:
                    raise ctx.fail(
                        element,
                        f"expected 'wavelength:value' pairs separated by commas, got '{shown(entry)}'",
                        "value",
                    )
                wavelengths.append(ctx.parse_number(parts[0], element, "value"))
                values.append(ctx.parse_number(parts[1], element, "value"))
            return {"values": pairs(ctx, element, wavelengths, values, "value")}
        value = ctx.number(element)
        ctx.non_negative([value], element, "value")
        return {"value": value}
    properties = ctx.properties(element)
    if kind == "uniform":
        if "value" not in properties:
            return {"value": 1.0}
        value = ctx.number(properties["value"])
        ctx.non_negative([value], properties["value"], "value")
        return {"value": value}
    if kind == "irregular":
        wavelengths_element = ctx.child(properties, "wavelengths", element)
        values_element = ctx.child(properties, "values", element)
        wavelengths = ctx.numbers(wavelengths_element, "value")
        values = ctx.numbers(values_element, "value")
        return {"values": pairs(ctx, values_element, wavelengths, values, "value")}
    if kind == "regular":
        low = ctx.number(ctx.child(properties, "wavelength_min", element))
        high = ctx.number(ctx.child(properties, "wavelength_max", element))
        values_element = ctx.child(properties, "values", element)
        values = ctx.numbers(values_element, "value")
        if not 0.0 < low < high:
            raise ctx.fail(element, f"needs 0 < wavelength_min < wavelength_max, got {low:g} and {high:g}")
        wavelengths = [float(w) for w in np.linspace(low, high, len(values))] if len(values) > 1 else [low]
        return {"values": pairs(ctx, values_element, wavelengths, values, "value")}
    if kind == "blackbody":
        from spectrace.spectral.blackbody import WIEN_DISPLACEMENT, planck_radiance

        temperature_element = ctx.child(properties, "temperature", element)
        temperature = ctx.number(temperature_element)
        if not temperature > 0.0:
            raise ctx.fail(
                temperature_element, f"a black body's temperature must be > 0 K, got {temperature:g}", "value"
            )
        # Mitsuba's black body is Planck's law in W/(m² sr nm); spectrace's is normalised to a peak of 1.
        with np.errstate(all="ignore"):
            peak = float(planck_radiance(np.array([WIEN_DISPLACEMENT / temperature * 1e9]), temperature)[0])
        if not (math.isfinite(peak) and peak > 0.0):
            raise ctx.fail(temperature_element, f"a black body of {temperature:g} K has no finite radiance", "value")
        return {"blackbody": temperature, "scale": peak}
    if kind == "d65":
        from spectrace.spectral.colorimetry import spectrum_to_xyz
        from spectrace.spectral.illuminants import cie_illuminant

        scale = ctx.number(properties["scale"]) if "scale" in properties else 1.0
        if "scale" in properties:
            ctx.non_negative([scale], properties["scale"], "value")
        if "color" in properties:
            ctx.unsupported_plugin(element, " with a color")
            return None
        # Mitsuba's d65 has unit luminance, i.e. film Y = 1 in spectrace's convention.
        return {"spectrum": "cie:D65", "scale": scale / float(spectrum_to_xyz(cie_illuminant("D65"))[1])}
    if kind == "srgb" and "color" in properties:
        return spectrum(ctx, properties["color"], "color")
    ctx.unsupported_plugin(element)
    return None


def pairs(
    ctx: ImportContext, element: Element, wavelengths: list[float], values: list[float], key: str
) -> list[list[float]]:
    """(wavelength, value) pairs, checked: as many wavelengths as values, wavelengths positive and increasing,
    values not negative."""
    if len(wavelengths) != len(values):
        raise ctx.fail(element, f"{len(wavelengths)} wavelengths but {len(values)} values", key)
    if wavelengths[0] <= 0.0:
        raise ctx.fail(element, f"wavelengths must be > 0 nm, got {wavelengths[0]:g}", key)
    for before, after in zip(wavelengths, wavelengths[1:]):
        if not after > before:
            raise ctx.fail(element, f"wavelengths must increase, got {before:g} then {after:g}", key)
    ctx.non_negative(values, element, key)
    return [[w, v] for w, v in zip(wavelengths, values)]


def spd_file(ctx: ImportContext, element: Element) -> list[list[float]]:
    """An .spd file: lines 'wavelength value' (nm), '#' comments."""
    name = ctx.required(element, "filename")
    path = ctx.find_file(element, name)
    where = f"{ctx.where(element)}@filename"
    data = read_input_file(path, where)
    try:
        lines = data.decode("utf-8").splitlines()
    except UnicodeDecodeError as error:
        raise ctx.fail(
            element, f"spectrum file '{shown(name)}' is not UTF-8 text (byte {error.start})", "filename"
        ) from None
    wavelengths, values = [], []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        parts = text.split()
        if len(parts) != 2 or not all(DECIMAL.fullmatch(part) for part in parts):
            raise ctx.fail(
                element,
                f"line {number} of '{shown(name)}': expected 'wavelength value', got '{shown(text)}'",
                "filename",
            )
        pair = [float(part) for part in parts]
        if not all(abs(value) <= FLOAT32_MAX for value in pair):
            raise ctx.fail(element, f"line {number} of '{shown(name)}': beyond the float32 range (±3.4e38)", "filename")
        wavelengths.append(pair[0])
        values.append(pair[1])
    if not wavelengths:
        raise ctx.fail(element, f"spectrum file '{shown(name)}' holds no 'wavelength value' lines", "filename")
    return pairs(ctx, element, wavelengths, values, "filename")


def _checkerboard_as_number(ctx: ImportContext, name: str, made_here: bool) -> dict:
    table = ctx.textures[name]
    swapped = table | {"color0": table["color1"], "color1": table["color0"]}
    if made_here:  # made for this use: it becomes the number's, and a colour use makes its own
        ctx.textures[name] = swapped
        ctx.texture_of_element = {k: v for k, v in ctx.texture_of_element.items() if v != name}
        return {"texture": name}
    for other, made in ctx.textures.items():  # the number's table an earlier use made
        if made == swapped:
            return {"texture": other}
    number = f"{name}_as_number"
    if number not in ctx.textures:
        ctx.textures[number] = swapped
        ctx.texture_elements[number] = ctx.texture_elements[name]
        ctx.origins[f"textures.{number}"] = ctx.texture_elements[name]
    return {"texture": number}
