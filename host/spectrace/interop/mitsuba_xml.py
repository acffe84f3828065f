"""Mitsuba 3 XML scenes -> spectrace scene TOML, for the subset spectrace represents exactly.

Imported: shapes obj, ply, rectangle, cube, sphere (center, radius); BSDFs diffuse, conductor and roughconductor
(material "Au", "Ag", "Cu", "Al" or "none", eta and k, alpha, specular_reflectance), plastic and roughplastic
(diffuse_reflectance, int_ior / ext_ior as numbers or Mitsuba's names, alpha), dielectric and roughdielectric
(int_ior / ext_ior, alpha, equal specular_reflectance and specular_transmittance), and twosided around one of them
(spectrace's materials already reflect on both faces); emitters area, point, constant, directional; the
perspective sensor (fov with any fov_axis, or focal_length; to_world with lookat/translate/rotate/scale/matrix);
hdrfilm width/height; the sampler's sample_count and seed; integrators path (max_depth, rr_depth), direct (as path
with max_depth 2) and volpath/volpathmis (as path: spectrace has no media). Spectra: rgb (uplifted exactly as
Mitsuba does: Jakob & Hanika 2019, emission D65-based), float, spectrum given as a value, "λ:v" pairs,
wavelengths/values or an .spd file, and the spectrum plugins uniform, regular, irregular, blackbody, d65 and srgb.
`$name` parameters and <default> are substituted as Mitsuba does.

Anything else (another plugin type, textures, media, include) is reported in one error naming each unsupported
plugin and its line; choices spectrace makes differently (the reconstruction filter, the sampler) are returned as
notes. Parameters are documented in Mitsuba 3's plugin reference (mitsuba.readthedocs.io, "Plugin reference").
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.geometry.transforms import transform_matrix
from spectrace.spectral.glasses import IOR_RANGE

SUPPORTED = {
    "shape": ("obj", "ply", "rectangle", "cube", "sphere"),
    "bsdf": ("diffuse", "twosided", "conductor", "roughconductor", "plastic", "roughplastic", "dielectric",
             "roughdielectric"),
    "emitter": ("area", "point", "constant", "directional"),
    "sensor": ("perspective",),
    "film": ("hdrfilm",),
    "integrator": ("path", "direct", "volpath", "volpathmis"),
}
# Mitsuba BSDFs whose spectrace counterparts are being written; until then they are reported as unsupported.
_PLANNED_BSDFS = ("thindielectric",)
# Mitsuba's `material` names for conductors that spectrace ships measured data for ("none" is a perfect mirror).
_CONDUCTOR_MATERIALS = ("Au", "Ag", "Cu", "Al")
# Mitsuba 3's named indices of refraction (its documentation's table, at about 589 nm), for int_ior / ext_ior.
_NAMED_IOR = {"vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277, "carbon dioxide": 1.00045,
              "water": 1.333, "acetone": 1.36, "ethanol": 1.361, "carbon tetrachloride": 1.461, "glycerol": 1.4729,
              "benzene": 1.501, "silicone oil": 1.52045, "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458,
              "pyrex": 1.470, "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046, "sodium chloride": 1.544,
              "amber": 1.55, "pet": 1.575, "diamond": 2.419}
_OBJECT_TAGS = ("scene", "shape", "bsdf", "emitter", "sensor", "film", "sampler", "integrator", "rfilter", "texture",
                "medium", "phase", "volume", "spectrum")
_FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # Mitsuba's focal_length is in 35 mm film equivalent (36 x 24 mm)
MITSUBA_DEFAULT_FILM = (768, 576)  # hdrfilm's default width and height
MITSUBA_DEFAULT_FOCAL_LENGTH_MM = 50.0  # the perspective sensor's, when neither fov nor focal_length is given


@dataclass
class Element:
    tag: str
    attributes: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.attributes.get(key, default)

    def label(self) -> str:
        kind = self.get("type")
        return f"{self.tag} '{kind}'" if kind else self.tag


def parse_xml(path: Path) -> Element:
    """The XML tree with each element's line number (for messages)."""
    parser = expat.ParserCreate()
    stack: list[Element] = []
    root: list[Element] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = Element(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    try:
        parser.Parse(path.read_bytes(), True)
    except OSError as error:
        raise SpectraceError(f"cannot read ({error.strerror or error})", where=str(path)) from None
    except expat.ExpatError as error:
        raise SpectraceError(f"XML syntax error: {expat.ErrorString(error.code)}",
                             where=f"{path}:{error.lineno}") from None
    if not root or root[0].tag != "scene":
        raise SpectraceError("not a Mitsuba scene: the root element must be <scene>", where=str(path))
    return root[0]


# ---------------------------------------------------------------- values


def _numbers(text: str, where: str) -> list[float]:
    try:
        return [float(part) for part in re.split(r"[,\s]+", text.strip()) if part]
    except ValueError:
        raise SpectraceError(f"expected numbers, got '{text}'", where=where) from None


class _Importer:
    def __init__(self, xml_path: Path, toml_folder: Path, parameters: dict[str, str]):
        self.xml_path = xml_path
        self.toml_folder = toml_folder
        self.parameters = dict(parameters)
        self.ids: dict[str, Element] = {}
        self.unsupported: list[str] = []
        self.notes: list[str] = []
        self.materials: dict[str, dict] = {}
        self._material_of_element: dict[int, str] = {}

    # -------------------------------------------------- helpers

    def where(self, element: Element) -> str:
        return f"{self.xml_path}:{element.line}"

    def attribute(self, element: Element, key: str, default: str | None = None) -> str | None:
        """An attribute with $parameters substituted."""
        value = element.get(key, default)
        if value is None or "$" not in value:
            return value

        def substitute(match: re.Match) -> str:
            name = match.group(1)
            if name not in self.parameters:
                raise SpectraceError(f"undefined parameter ${name} (add <default name=\"{name}\" value=\"...\"/>)",
                                     where=self.where(element))
            return self.parameters[name]

        return re.sub(r"\$([A-Za-z_][A-Za-z0-9_]*)", substitute, value)

    def unsupported_plugin(self, element: Element, detail: str = "") -> None:
        self.unsupported.append(f"{element.label()}{detail} (line {element.line})")

    def number(self, element: Element, key: str = "value") -> float:
        values = _numbers(self.attribute(element, key) or "", self.where(element))
        if len(values) != 1:
            raise SpectraceError(f"<{element.tag} name=\"{element.get('name')}\"> needs one number",
                                 where=self.where(element))
        return values[0]

    def vector(self, element: Element, default: float = 0.0) -> list[float]:
        """<point>/<vector> (x, y, z attributes or value="x, y, z")."""
        if element.get("value") is not None:
            values = _numbers(self.attribute(element, "value"), self.where(element))
            if len(values) == 1:
                values *= 3
        else:
            values = [float(self.attribute(element, axis, str(default))) for axis in "xyz"]
        if len(values) != 3:
            raise SpectraceError(f"<{element.tag}> needs 3 numbers", where=self.where(element))
        return values

    def resolve(self, element: Element) -> Element:
        if element.tag != "ref":
            return element
        identifier = self.attribute(element, "id")
        if identifier not in self.ids:
            raise SpectraceError(f"reference to undefined id '{identifier}'", where=self.where(element))
        return self.ids[identifier]

    def properties(self, element: Element) -> dict[str, Element]:
        """Named children (property elements, references, nested objects); unnamed nested objects by tag."""
        found: dict[str, Element] = {}
        for index, child in enumerate(element.children):
            name = child.get("name")
            if name is None and child.tag in _OBJECT_TAGS:
                name = child.tag if child.tag not in found else f"{child.tag}#{index}"
            found[name or f"#{index}"] = child
        return found

    # -------------------------------------------------- transforms

    def transform_steps(self, element: Element) -> list[dict]:
        """A <transform> as spectrace transform steps, first step first (Mitsuba applies them in file order)."""
        steps = []
        for step in element.children:
            where = self.where(step)
            if step.tag == "translate":
                steps.append({"translate": self.vector(step)})
            elif step.tag == "scale":
                if step.get("value") is not None:
                    values = _numbers(self.attribute(step, "value"), where)
                    steps.append({"scale": values[0] if len(values) == 1 else values})
                else:
                    steps.append({"scale": self.vector(step, default=1.0)})
            elif step.tag == "rotate":
                angle = float(self.attribute(step, "angle", "0"))
                steps.append({"rotate": {"axis": self.vector(step), "angle": angle}})
            elif step.tag == "matrix":
                values = _numbers(self.attribute(step, "value"), where)
                if len(values) == 9:
                    values = values[0:3] + [0.0] + values[3:6] + [0.0] + values[6:9] + [0.0, 0.0, 0.0, 0.0, 1.0]
                if len(values) != 16:
                    raise SpectraceError("a matrix needs 16 (or 9) numbers", where=where)
                steps.append({"matrix": [values[i:i + 4] for i in range(0, 16, 4)]})
            elif step.tag == "lookat":
                steps.append({"matrix": self.look_at(step).tolist()})
            else:
                self.unsupported_plugin(step, " transform step")
        return steps

    def look_at(self, element: Element) -> np.ndarray:
        """Mitsuba's look_at: columns left = up × dir, up' = dir × left, dir, and the origin."""
        where = self.where(element)
        origin = np.array(_numbers(self.attribute(element, "origin"), where))
        target = np.array(_numbers(self.attribute(element, "target"), where))
        up = np.array(_numbers(self.attribute(element, "up", "0, 1, 0"), where))
        direction = target - origin
        left = np.cross(up, direction)
        if not (np.linalg.norm(direction) > 0 and np.linalg.norm(left) > 0):
            raise SpectraceError("lookat needs target != origin and up not parallel to the view", where=where)
        direction /= np.linalg.norm(direction)
        left /= np.linalg.norm(left)
        matrix = np.eye(4)
        matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = left, np.cross(direction, left), direction, origin
        return matrix

    def to_world(self, properties: dict[str, Element]) -> np.ndarray:
        element = properties.get("to_world")
        if element is None:
            return np.eye(4)
        return transform_matrix(self.transform_steps(element), where=self.where(element))

    # -------------------------------------------------- spectra

    def spectrum(self, element: Element, key: str) -> dict | None:
        """A spectrace spectrum table for a Mitsuba colour/spectrum property, or None (unsupported, recorded)."""
        element = self.resolve(element)
        where = self.where(element)
        if element.tag == "rgb":
            values = _numbers(self.attribute(element, "value"), where)
            return {"rgb": values * 3 if len(values) == 1 else values}
        if element.tag == "float":
            return {"value": self.number(element)}
        if element.tag == "spectrum":
            return self.spectrum_element(element)
        if element.tag == "texture":
            self.unsupported_plugin(element, f" as {key}")
            return None
        raise SpectraceError(f"'{key}' must be a colour or spectrum, got <{element.tag}>", where=where)

    def spectrum_element(self, element: Element) -> dict | None:
        where = self.where(element)
        kind = element.get("type")
        if kind is None:
            if element.get("filename") is not None:
                return {"values": self.spd_file(element)}
            if element.get("wavelengths") is not None:
                return {"values": self.pairs(element, "wavelengths", "values")}
            text = self.attribute(element, "value") or ""
            if ":" in text:
                pairs = [entry.split(":") for entry in text.split(",") if entry.strip()]
                return {"values": [[float(w), float(v)] for w, v in pairs]}
            return {"value": self.number(element)}
        properties = self.properties(element)
        if kind == "uniform":
            return {"value": self.number(properties["value"])} if "value" in properties else {"value": 1.0}
        if kind == "irregular":
            return {"values": self.pairs_from_strings(properties, where)}
        if kind == "regular":
            low = self.number(properties["wavelength_min"])
            high = self.number(properties["wavelength_max"])
            values = _numbers(self.attribute(properties["values"], "value"), where)
            return {"values": [[float(w), v] for w, v in zip(np.linspace(low, high, len(values)), values)]}
        if kind == "blackbody":
            from spectrace.spectral.blackbody import WIEN_DISPLACEMENT, planck_radiance

            temperature = self.number(properties["temperature"])
            # Mitsuba's black body is Planck's law in W/(m² sr nm); spectrace's is normalised to a peak of 1.
            peak = float(planck_radiance(np.array([WIEN_DISPLACEMENT / temperature * 1e9]), temperature)[0])
            return {"blackbody": temperature, "scale": peak}
        if kind == "d65":
            from spectrace.spectral.colorimetry import spectrum_to_xyz
            from spectrace.spectral.illuminants import cie_illuminant

            scale = self.number(properties["scale"]) if "scale" in properties else 1.0
            if "color" in properties:
                self.unsupported_plugin(element, " with a color")
                return None
            # Mitsuba's d65 has unit luminance, i.e. film Y = 1 in spectrace's convention.
            return {"spectrum": "cie:D65", "scale": scale / float(spectrum_to_xyz(cie_illuminant("D65"))[1])}
        if kind == "srgb" and "color" in properties:
            return self.spectrum(properties["color"], "color")
        self.unsupported_plugin(element)
        return None

    def pairs(self, element: Element, wavelengths_key: str, values_key: str) -> list[list[float]]:
        where = self.where(element)
        wavelengths = _numbers(self.attribute(element, wavelengths_key), where)
        values = _numbers(self.attribute(element, values_key), where)
        if len(wavelengths) != len(values):
            raise SpectraceError("wavelengths and values differ in length", where=where)
        return [[w, v] for w, v in zip(wavelengths, values)]

    def pairs_from_strings(self, properties: dict[str, Element], where: str) -> list[list[float]]:
        wavelengths = _numbers(self.attribute(properties["wavelengths"], "value"), where)
        values = _numbers(self.attribute(properties["values"], "value"), where)
        if len(wavelengths) != len(values):
            raise SpectraceError("wavelengths and values differ in length", where=where)
        return [[w, v] for w, v in zip(wavelengths, values)]

    def spd_file(self, element: Element) -> list[list[float]]:
        """An .spd file: lines 'wavelength value' (nm), '#' comments."""
        path = self.xml_path.parent / self.attribute(element, "filename")
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except OSError as error:
            raise SpectraceError(f"cannot read spectrum file '{path}' ({error.strerror or error})",
                                 where=self.where(element)) from None
        pairs = []
        for number, line in enumerate(lines, start=1):
            text = line.split("#", 1)[0].strip()
            if text:
                values = _numbers(text, f"{path}:{number}")
                if len(values) != 2:
                    raise SpectraceError("expected 'wavelength value'", where=f"{path}:{number}")
                pairs.append(values)
        return pairs

    # -------------------------------------------------- materials

    def material(self, element: Element | None, owner: str) -> str | None:
        """The name of the spectrace material for a (possibly referenced) bsdf, defining it on first use."""
        if element is None:
            if "default" not in self.materials:
                self.materials["default"] = {"type": "diffuse", "reflectance": {"value": 0.5}}  # Mitsuba's default
            return "default"
        bsdf = self.resolve(element)
        if id(bsdf) in self._material_of_element:
            return self._material_of_element[id(bsdf)]
        name = _unique_name(self.attribute(bsdf, "id") or f"{owner}_bsdf", self.materials)
        table = self.material_table(bsdf)
        if table is None:
            return None
        self.materials[name] = table
        self._material_of_element[id(bsdf)] = name
        return name

    def material_table(self, bsdf: Element) -> dict | None:
        kind = bsdf.get("type")
        properties = self.properties(bsdf)
        if kind == "twosided":
            nested = [self.resolve(child) for child in properties.values() if self.resolve(child).tag == "bsdf"]
            if len(nested) != 1:
                self.unsupported_plugin(bsdf, " with two different sides")
                return None
            return self.material_table(nested[0])
        if kind == "diffuse":
            reflectance = properties.get("reflectance")
            spectrum = self.spectrum(reflectance, "reflectance") if reflectance is not None else {"value": 0.5}
            return None if spectrum is None else {"type": "diffuse", "reflectance": spectrum}
        if kind in ("conductor", "roughconductor"):
            return self.conductor_table(bsdf, properties, rough=kind == "roughconductor")
        if kind in ("plastic", "roughplastic"):
            return self.plastic_table(bsdf, properties, rough=kind == "roughplastic")
        if kind in ("dielectric", "roughdielectric"):
            return self.dielectric_table(bsdf, properties, rough=kind == "roughdielectric")
        self.unsupported_plugin(bsdf, " (not yet in spectrace)" if kind in _PLANNED_BSDFS else "")
        return None

    def text(self, element: Element) -> str:
        return self.attribute(self.resolve(element), "value") or ""

    def roughness(self, bsdf: Element, properties: dict[str, Element]) -> float | None:
        """GGX α of a rough Mitsuba BSDF (its default 0.1); None when spectrace cannot represent it (recorded)."""
        if "alpha_u" in properties or "alpha_v" in properties:
            alpha_u = self.number(self.resolve(properties.get("alpha_u", properties.get("alpha_v"))))
            alpha_v = self.number(self.resolve(properties.get("alpha_v", properties.get("alpha_u"))))
            if alpha_u != alpha_v:
                self.unsupported_plugin(bsdf, " with anisotropic roughness")
                return None
            alpha = alpha_u
        elif "alpha" in properties:
            element = self.resolve(properties["alpha"])
            if element.tag == "texture":
                self.unsupported_plugin(element, " as alpha")
                return None
            alpha = self.number(element)
        else:
            alpha = 0.1
        distribution = self.text(properties["distribution"]) if "distribution" in properties else "beckmann"
        if distribution != "ggx":
            self.notes.append(f"line {bsdf.line}: {bsdf.label()} uses the {distribution} distribution; imported as "
                              f"GGX with the same alpha (spectrace has GGX only; highlights differ slightly)")
        if not 0.0 <= alpha <= 1.0:
            raise SpectraceError(f"alpha must lie in [0, 1] for spectrace, got {alpha}", where=self.where(bsdf))
        return alpha

    def conductor_table(self, bsdf: Element, properties: dict[str, Element], rough: bool) -> dict | None:
        tint = None
        if "specular_reflectance" in properties:
            tint = self.spectrum(properties["specular_reflectance"], "specular_reflectance")
            if tint is None:
                return None
        roughness = self.roughness(bsdf, properties) if rough else 0.0
        if roughness is None:
            return None
        if "eta" in properties or "k" in properties:
            if "eta" not in properties or "k" not in properties:
                raise SpectraceError("a conductor needs both eta and k", where=self.where(bsdf))
            eta, k = self.spectrum(properties["eta"], "eta"), self.spectrum(properties["k"], "k")
            if eta is None or k is None:
                return None
            if "rgb" in eta or "rgb" in k:
                self.unsupported_plugin(bsdf, " with eta or k given as rgb")
                return None
            table = {"type": "conductor", "eta": eta, "k": k}
        else:
            material = self.text(properties["material"]) if "material" in properties else "none"
            if material == "none":  # Mitsuba's default: a perfect mirror scaled by specular_reflectance
                if roughness > 0.0:
                    self.unsupported_plugin(bsdf, " with material 'none' and roughness")
                    return None
                return {"type": "mirror", "reflectance": tint or {"value": 1.0}}
            if material not in _CONDUCTOR_MATERIALS:
                self.unsupported_plugin(bsdf, f" with material '{material}' (spectrace has "
                                              f"{', '.join(_CONDUCTOR_MATERIALS)})")
                return None
            table = {"type": "conductor", "metal": material}
        if roughness > 0.0:
            table["roughness"] = roughness
        if tint is not None:
            table["specular_tint"] = tint
        return table

    def ior(self, bsdf: Element, properties: dict[str, Element], key: str, default: float) -> float:
        if key not in properties:
            return default
        element = self.resolve(properties[key])
        if element.tag == "string":
            name = self.text(element)
            if name.lower() not in _NAMED_IOR:
                raise SpectraceError(f"unknown {key} '{name}' (Mitsuba names: {', '.join(_NAMED_IOR)})",
                                     where=self.where(element))
            return _NAMED_IOR[name.lower()]
        return self.number(element)

    def plastic_table(self, bsdf: Element, properties: dict[str, Element], rough: bool) -> dict | None:
        reflectance = (self.spectrum(properties["diffuse_reflectance"], "diffuse_reflectance")
                       if "diffuse_reflectance" in properties else {"value": 0.5})
        if reflectance is None:
            return None
        if "specular_reflectance" in properties:
            specular = self.spectrum(properties["specular_reflectance"], "specular_reflectance")
            if specular is not None and specular != {"value": 1.0}:
                self.unsupported_plugin(bsdf, " with specular_reflectance other than 1")
                return None
        if "nonlinear" in properties and self.text(properties["nonlinear"]) == "true":
            self.unsupported_plugin(bsdf, " with nonlinear = true")
            return None
        ior = self.ior(bsdf, properties, "int_ior", 1.49) / self.ior(bsdf, properties, "ext_ior", 1.000277)
        if not 1.0 < ior <= 4.0:
            raise SpectraceError(f"int_ior / ext_ior = {ior:.4g}: spectrace's plastic needs a coat index in (1, 4]",
                                 where=self.where(bsdf))
        roughness = self.roughness(bsdf, properties) if rough else 0.0
        if roughness is None:
            return None
        self.notes.append(f"line {bsdf.line}: {bsdf.label()}: spectrace's plastic couples coat and base "
                          "differently from Mitsuba's (an energy-conserving symmetric "
                          "coupling instead of internal scattering; see docs/materials.md), so the brightness of "
                          "its diffuse part differs")
        table = {"type": "plastic", "reflectance": reflectance, "ior": round(ior, 6)}
        if roughness > 0.0:
            table["roughness"] = roughness
        return table

    def dielectric_table(self, bsdf: Element, properties: dict[str, Element], rough: bool) -> dict | None:
        """Mitsuba's dielectrics have one constant index per side (default bk7 inside, air outside): spectrace's ior
        is their ratio. One tint on both lobes stands for equal specular_reflectance and specular_transmittance."""
        ior = self.ior(bsdf, properties, "int_ior", _NAMED_IOR["bk7"]) / self.ior(bsdf, properties, "ext_ior",
                                                                                  _NAMED_IOR["air"])
        if ior < IOR_RANGE[0]:
            self.unsupported_plugin(bsdf, " with int_ior not above ext_ior (flip the shape's normals instead)")
            return None
        roughness = self.roughness(bsdf, properties) if rough else 0.0
        if roughness is None:
            return None
        tints = {key: self.spectrum(properties[key], key) for key in ("specular_reflectance", "specular_transmittance")
                 if key in properties}
        if None in tints.values():
            return None
        if len(tints) == 1 or (len(tints) == 2 and tints["specular_reflectance"] != tints["specular_transmittance"]):
            self.unsupported_plugin(bsdf, " with specular_reflectance different from specular_transmittance")
            return None
        table: dict = {"type": "dielectric", "ior": round(ior, 6)}
        if roughness > 0.0:
            table["roughness"] = roughness
        if tints:
            table["specular_tint"] = tints["specular_reflectance"]
        return table

    # -------------------------------------------------- scene parts

    def shape(self, element: Element, index: int) -> dict | None:
        kind = element.get("type")
        if kind not in SUPPORTED["shape"]:
            self.unsupported_plugin(element)
            return None
        properties = self.properties(element)
        name = element.get("id") or element.get("name") or f"{kind}{index}"
        table: dict = {"name": name}
        steps: list[dict] = []
        if kind in ("obj", "ply"):
            mesh_path = self.xml_path.parent / self.attribute(properties["filename"], "value")
            if not mesh_path.is_file():
                raise SpectraceError(f"mesh file '{mesh_path}' does not exist", where=self.where(element))
            table |= {"type": "mesh", "file": _relative_path(mesh_path, self.toml_folder)}
        else:
            table["type"] = kind
        if kind == "sphere":
            radius = self.number(properties["radius"]) if "radius" in properties else 1.0
            centre = self.vector(properties["center"]) if "center" in properties else [0.0, 0.0, 0.0]
            steps += [{"scale": radius}, {"translate": centre}]
        if "to_world" in properties:
            steps += self.transform_steps(properties["to_world"])
        flip = "flip_normals" in properties and self.attribute(properties["flip_normals"], "value") == "true"
        if flip:
            if kind != "rectangle":
                self.unsupported_plugin(element, " with flip_normals")
            steps.insert(0, {"scale": [1.0, 1.0, -1.0]})  # mirroring the flat square reverses its winding
        if steps:
            table["transform"] = steps
        bsdf = properties.get("bsdf") or next((c for c in properties.values() if self.resolve(c).tag == "bsdf"), None)
        table["material"] = self.material(bsdf, name)
        emitter = next((self.resolve(c) for c in properties.values() if self.resolve(c).tag == "emitter"), None)
        if emitter is not None:
            if emitter.get("type") != "area":
                self.unsupported_plugin(emitter, " on a shape")
            else:
                radiance = self.properties(emitter).get("radiance")
                if radiance is None:
                    raise SpectraceError("an area emitter needs radiance", where=self.where(emitter))
                spectrum = self.spectrum(radiance, "radiance")
                if spectrum is not None:
                    table["emitter"] = {"radiance": spectrum}
        return table if table["material"] is not None else None

    def light(self, element: Element) -> dict | None:
        kind = element.get("type")
        properties = self.properties(element)
        matrix = self.to_world(properties)
        white = {"rgb": [1.0, 1.0, 1.0]}  # Mitsuba's default emission: d65 with unit luminance
        if kind == "point":
            position = self.vector(properties["position"]) if "position" in properties else matrix[:3, 3].tolist()
            intensity = self.spectrum(properties["intensity"], "intensity") if "intensity" in properties else white
            return None if intensity is None else {"type": "point", "position": position, "intensity": intensity}
        if kind == "constant":
            radiance = self.spectrum(properties["radiance"], "radiance") if "radiance" in properties else white
            return None if radiance is None else {"type": "constant", "radiance": radiance}
        if kind == "directional":
            direction = (self.vector(properties["direction"]) if "direction" in properties
                         else (matrix[:3, :3] @ [0.0, 0.0, 1.0]).tolist())
            irradiance = self.spectrum(properties["irradiance"], "irradiance") if "irradiance" in properties else white
            return None if irradiance is None else {"type": "distant", "direction": direction, "irradiance": irradiance}
        self.unsupported_plugin(element)
        return None

    def sensor(self, element: Element, data: dict) -> None:
        if element.get("type") != "perspective":
            self.unsupported_plugin(element)
            return
        properties = self.properties(element)
        for key, child in properties.items():
            if key.startswith("principal_point_offset") and self.number(child) != 0.0:
                self.unsupported_plugin(element, f" with {key}")
        film = properties.get("film")
        width, height = MITSUBA_DEFAULT_FILM
        if film is not None:
            if film.get("type") not in SUPPORTED["film"]:
                self.unsupported_plugin(film)
            film_properties = self.properties(film)
            width = int(self.number(film_properties["width"])) if "width" in film_properties else width
            height = int(self.number(film_properties["height"])) if "height" in film_properties else height
            for key in film_properties:
                if key.startswith("crop_"):
                    self.unsupported_plugin(film, f" with {key}")
            rfilter = film_properties.get("rfilter")
            if rfilter is not None and rfilter.get("type") != "box":
                self.notes.append(f"line {rfilter.line}: reconstruction filter '{rfilter.get('type')}' not "
                                  "imported: spectrace averages the samples inside each pixel (a box filter)")
        data["film"] = {"width": width, "height": height}
        matrix = self.to_world(properties)
        linear = matrix[:3, :3]
        if np.linalg.det(linear) <= 0:
            self.unsupported_plugin(element, " with a mirroring to_world")
        origin = matrix[:3, 3]
        forward = linear @ [0.0, 0.0, 1.0]
        up = linear @ [0.0, 1.0, 0.0]
        data["camera"] = {
            "origin": origin.tolist(),
            "target": (origin + forward / np.linalg.norm(forward)).tolist(),
            "up": (up / np.linalg.norm(up)).tolist(),
            "fov": self.fov_x(properties, width / height, element),
            "fov_axis": "x",
        }
        sampler = properties.get("sampler")
        if sampler is not None:
            sampler_properties = self.properties(sampler)
            data["sampler"] = {}
            if "sample_count" in sampler_properties:
                data["sampler"]["spp"] = int(self.number(sampler_properties["sample_count"]))
            if "seed" in sampler_properties:
                data["sampler"]["seed"] = int(self.number(sampler_properties["seed"]))
            if sampler.get("type") != "independent":
                self.notes.append(f"line {sampler.line}: sampler '{sampler.get('type')}' not imported: spectrace "
                                  "uses its own sampler (same sample count)")

    def fov_x(self, properties: dict[str, Element], aspect: float, element: Element) -> float:
        """Horizontal field of view in degrees, as Mitsuba derives it from fov + fov_axis or focal_length."""
        if "fov" in properties:
            fov = self.number(properties["fov"])
            axis = self.attribute(properties["fov_axis"], "value") if "fov_axis" in properties else "x"
        else:
            focal = MITSUBA_DEFAULT_FOCAL_LENGTH_MM
            if "focal_length" in properties:
                text = self.attribute(properties["focal_length"], "value")
                focal = float(text.removesuffix("mm"))
            fov, axis = math.degrees(2.0 * math.atan(_FILM_DIAGONAL_MM / (2.0 * focal))), "diagonal"
        tan_half = math.tan(math.radians(fov) / 2.0)
        if axis == "smaller":
            axis = "y" if aspect > 1.0 else "x"
        elif axis == "larger":
            axis = "x" if aspect > 1.0 else "y"
        if axis == "y":
            tan_half *= aspect
        elif axis == "diagonal":
            tan_half *= aspect / math.hypot(aspect, 1.0)
        elif axis != "x":
            raise SpectraceError(f"unknown fov_axis '{axis}'", where=self.where(element))
        return math.degrees(2.0 * math.atan(tan_half))

    def integrator(self, element: Element, data: dict) -> None:
        kind = element.get("type")
        if kind not in SUPPORTED["integrator"]:
            self.unsupported_plugin(element)
            return
        properties = self.properties(element)
        settings = {"type": "path", "max_depth": -1}  # Mitsuba's path tracers default to unbounded depth
        if "max_depth" in properties:
            settings["max_depth"] = int(self.number(properties["max_depth"]))
        if "rr_depth" in properties:
            settings["rr_depth"] = int(self.number(properties["rr_depth"]))
        if kind == "direct":
            settings["max_depth"] = 2
            self.notes.append(f"line {element.line}: integrator 'direct' imported as path tracing with max_depth 2 "
                              "(emitters seen directly and direct light)")
        elif kind.startswith("volpath"):
            self.notes.append(f"line {element.line}: integrator '{kind}' imported as 'path' (spectrace has no media)")
        data["integrator"] = settings

    # -------------------------------------------------- the scene

    def run(self, root: Element) -> dict:
        for child in root.children:
            if child.tag == "default":
                self.parameters.setdefault(child.get("name"), child.get("value"))
        self._collect_ids(root)
        data: dict = {"integrator": {"type": "path", "max_depth": -1}}
        shapes, lights = [], []
        sensors = [c for c in root.children if c.tag == "sensor"]
        if not sensors:
            raise SpectraceError("the scene has no <sensor>; spectrace needs a camera", where=str(self.xml_path))
        if len(sensors) > 1:
            self.notes.append(f"line {sensors[1].line}: only the first of {len(sensors)} sensors is imported")
        self.sensor(sensors[0], data)
        for index, child in enumerate(root.children):
            if child.tag == "shape":
                if (table := self.shape(child, index)) is not None:
                    shapes.append(table)
            elif child.tag == "emitter":
                if (table := self.light(child)) is not None:
                    lights.append(table)
            elif child.tag == "integrator":
                self.integrator(child, data)
            elif child.tag in ("bsdf", "texture", "spectrum", "rgb", "default", "sensor", "alias"):
                continue  # declarations: imported where they are used
            elif child.tag in _OBJECT_TAGS or child.tag == "include":
                self.unsupported_plugin(child)
        if self.unsupported:
            supported = "; ".join(f"{tag} {', '.join(kinds)}" for tag, kinds in SUPPORTED.items())
            raise SpectraceError(f"unsupported Mitsuba 3 plugins: {', '.join(self.unsupported)} (spectrace imports "
                                 f"{supported})", where=str(self.xml_path))
        environments = [light for light in lights if light["type"] == "constant"]
        if len(environments) > 1:
            raise SpectraceError("more than one constant emitter; spectrace takes one environment light",
                                 where=str(self.xml_path))
        data["materials"] = self.materials
        data["shapes"] = shapes
        data["lights"] = lights
        return {key: data[key] for key in ("camera", "film", "integrator", "sampler", "materials", "shapes", "lights")
                if key in data and data[key] != []}

    def _collect_ids(self, element: Element) -> None:
        for child in element.children:
            if child.get("id") is not None and child.tag != "ref":
                self.ids[child.get("id")] = child
            self._collect_ids(child)


def _unique_name(base: str, taken: dict) -> str:
    name = re.sub(r"[^A-Za-z0-9_-]", "_", base) or "material"
    candidate, number = name, 2
    while candidate in taken:
        candidate, number = f"{name}_{number}", number + 1
    return candidate


def _relative_path(path: Path, folder: Path) -> str:
    try:
        return Path(os.path.relpath(path.resolve(), folder.resolve())).as_posix()
    except ValueError:  # another drive on Windows
        return path.resolve().as_posix()


# ---------------------------------------------------------------- public API


def mitsuba_scene_data(xml_path: str | Path, toml_folder: str | Path | None = None,
                       parameters: dict[str, str] | None = None) -> tuple[dict, list[str]]:
    """(scene data in the TOML format's structure, notes) for a Mitsuba 3 XML scene. Mesh paths are written relative
    to `toml_folder` (default: the XML's folder). `parameters` set `$name` values, as `mitsuba -D name=value`.
    Raises SpectraceError naming every unsupported plugin."""
    xml_path = Path(xml_path)
    importer = _Importer(xml_path, Path(toml_folder) if toml_folder else xml_path.parent, parameters or {})
    return importer.run(parse_xml(xml_path)), importer.notes


def import_mitsuba(xml_path: str | Path, toml_path: str | Path, parameters: dict[str, str] | None = None
                   ) -> list[str]:
    """Write the spectrace TOML scene for a Mitsuba 3 XML scene and check that it loads; returns the notes."""
    from spectrace.interop.toml_writer import dumps
    from spectrace.io.atomic import write_atomically
    from spectrace.scene import load_scene

    xml_path, toml_path = Path(xml_path), Path(toml_path)
    data, notes = mitsuba_scene_data(xml_path, toml_path.parent, parameters)
    header = "\n".join([f"Imported from the Mitsuba 3 scene {xml_path.name} by `spectrace import-mitsuba`.",
                        *(f"note: {note}" for note in notes)])
    text = dumps(data, header=header)
    try:
        write_atomically(toml_path, lambda temp: temp.write_text(text, encoding="utf-8"))
    except OSError as error:
        raise SpectraceError(f"cannot write the scene ({error.strerror or error})", where=str(toml_path)) from None
    load_scene(toml_path)
    return notes


def load_mitsuba_scene(xml_path: str | Path, parameters: dict[str, str] | None = None):
    """A `Scene` from a Mitsuba 3 XML file (through a temporary TOML file)."""
    from spectrace.scene import load_scene

    with tempfile.TemporaryDirectory(prefix="spectrace-mitsuba-") as folder:
        toml_path = Path(folder) / (Path(xml_path).stem + ".toml")
        import_mitsuba(xml_path, toml_path, parameters)
        return load_scene(toml_path).with_overrides(source=Path(xml_path))
