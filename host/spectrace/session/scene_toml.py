"""A scene built in Python written as a scene file: its TOML, with each mesh shape's triangles as a PLY file in a
folder beside it, written all or nothing and loaded back before anything is replaced (the importers' writer,
spectrace.interop.toml_writer).

Materials, textures, lights, emitters and media are written from the arguments their API constructors were given
(spectrace.core.api_calls), under the scene file's names of those arguments, so the loader makes them through the
same checks and uplifts; a built-in or exact shape is written as its type placed by its matrix, any other shape as
its triangles (positions, normals and texture coordinates in doubles) with no transform; a spectrum given as
samples as its values on the 1 nm grid. An object that no API constructor made, or an argument that has no
scene-file form (an image given as an array), is refused in one line naming it.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from functools import partial
from numbers import Real
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spectrace.core.api_calls import call_of
from spectrace.errors import SpectraceError
from spectrace.geometry.curves import CurveSurface
from spectrace.geometry.sdf_grid import SdfGridSurface

if TYPE_CHECKING:
    from spectrace.scene.model import Scene


# The spectra among the arguments of the constructors spectrace.api defines itself (area_emitter, medium), whose
# scene-file keys have no parameter table.
_API_KINDS = {name: (name, "spectrum") for name in ("radiance", "sigma_a", "sigma_s", "emission")}


def _module_of(made: object) -> Any:
    import sys

    call = call_of(made)
    return None if call is None else sys.modules.get(call.constructor.__module__)


class _Writer:
    def __init__(self, scene: Scene, folder: Path, assets: str) -> None:
        self.scene, self.folder, self.assets = scene, folder, assets
        self.materials: dict[str, dict] = {}
        self.material_names: dict[int, str] = {}
        self.textures: dict[str, dict] = {}
        self.texture_names: dict[int, str] = {}
        self.files: dict[str, Callable[[Path], object]] = {}
        from spectrace.session.python_scene import materials_by_label

        # The names a live session's keys give the materials (materials.floor, materials.2).
        self.labels = {
            id(material): f"material_{label}" if label.isdigit() else label
            for label, material in materials_by_label(scene).items()
        }

    # ------------------------------------------------------------ values

    def _unique(self, taken: dict, name: str) -> str:
        name = name or "unnamed"
        found, i = name, 1
        while found in taken:
            i += 1
            found = f"{name}_{i}"
        return found

    def value(self, value: Any, kind: str, where: str) -> Any:
        """`value`, an argument of a constructor, as the scene file writes it for a key of type `kind`."""
        from spectrace.textures import is_texture

        if is_texture(value):
            return {"texture": self.texture(value, where)}
        if isinstance(value, (str, Path)) and kind == "file":
            return self.file_name(value)
        if isinstance(value, np.generic):
            value = value.item()
        if kind == "spectrum":
            if isinstance(value, bool):
                raise SpectraceError("is not a spectrum", where=where)
            if isinstance(value, Real):
                return {"value": float(value)}
            if isinstance(value, str):
                return {"spectrum": value}
            if isinstance(value, (list, tuple, np.ndarray)) and np.shape(value) == (3,):
                return {"rgb": [float(v) for v in np.asarray(value, np.float64)]}
            return self.samples(value, where)
        if isinstance(value, Path):
            return value.as_posix()
        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, tuple):
            return [self.value(v, "", where) for v in value]
        if isinstance(value, list):
            return [self.value(v, "", where) for v in value]
        if value is None or isinstance(value, (bool, int, float, str, dict)):
            return value
        raise SpectraceError(f"is a {type(value).__name__}, which a scene file cannot hold", where=where)

    def samples(self, value: Any, where: str) -> dict:
        """A spectrum given as samples (a Spectrum, a colour-science distribution, (wavelengths, values) arrays,
        pairs, a mapping) as the values on the 1 nm grid its constructor put it on: the loader's `values`, read at
        those wavelengths, gives back the same numbers."""
        from spectrace.spectral.grid import GRID_NM
        from spectrace.spectral.spectrum_input import spectrum

        try:
            made = spectrum(value)
        except (SpectraceError, TypeError, ValueError):
            raise SpectraceError(f"is a {type(value).__name__} that is no spectrum a scene file holds", where) from None
        return {"values": [[float(nm), float(v)] for nm, v in zip(GRID_NM, made.values)]}

    def file_name(self, value: str | Path) -> str:
        """A file an argument names, as the scene file finds it from its folder."""
        path = Path(value).resolve()
        return Path(os.path.relpath(path, self.folder.resolve())).as_posix()

    def table(self, made: Any, where: str, skip: tuple[str, ...] = ()) -> dict:
        """The table of an object made by an API constructor: its type, then each argument given (not None)."""
        call, module = call_of(made), _module_of(made)
        if call is None or module is None:
            raise SpectraceError(
                f"a {type(made).__name__} not made by one of spectrace's constructors (spectrace.diffuse, "
                "spectrace.point_light, spectrace.bitmap, ...): its parameters have no names to write",
                where=where,
            )
        kinds = {p.api_name or p.name: (p.name, p.type) for p in getattr(module, "PARAMETERS", ())}
        kinds = _API_KINDS | kinds
        out: dict[str, Any] = {"type": module.NAME} if hasattr(module, "NAME") else {}
        for argument, value in call.arguments.items():
            if value is None or argument in skip:
                continue
            name, kind = kinds.get(argument, (argument, ""))
            # An image texture's source, or a light's image file: a file, or pixels that no scene file can name.
            if argument == "source" or (name == "file" and not isinstance(value, (str, Path))):
                if not isinstance(value, (str, Path)):
                    raise SpectraceError(
                        f"is an image given as a {type(value).__name__}, which a scene file cannot hold: save the "
                        "image as a file and give its path",
                        where=where,
                    )
                name, kind = "file", "file"
            elif kind == "file" or (name in ("file", "filename") and isinstance(value, (str, Path))):
                kind = "file"
            elif argument == "materials":
                out[name] = [self.material(m, f"{where}.materials.{i}") for i, m in enumerate(value)]
                continue
            elif kind == "material":  # another material, as the scene file names it (a fluorescent dye's base)
                out[name] = self.material(value, f"{where}.{name}")
                continue
            out[name] = self.value(value, kind, f"{where}.{name}")
        return out

    def texture(self, texture: Any, where: str) -> str:
        if id(texture) not in self.texture_names:
            # Named after where it is first used: a texture type's own name would read as an inline texture.
            name = self._unique(self.textures, where.removeprefix("materials.").replace(".", "_"))
            self.texture_names[id(texture)] = name
            self.textures[name] = self.table(texture, where)
        return self.texture_names[id(texture)]

    def material(self, material: Any, where: str, label: str = "") -> str:
        if id(material) not in self.material_names:
            label = self.labels.get(id(material), label)
            name = self._unique(self.materials, label or getattr(_module_of(material), "NAME", "material"))
            self.material_names[id(material)] = name
            self.materials[name] = {}  # its place, before the parts a mix names
            self.materials[name] = self.table(material, f"materials.{name}")
        return self.material_names[id(material)]

    # ------------------------------------------------------------ shapes

    def shape(self, shape: Any, where: str, folder_name: str) -> dict:
        from spectrace.interop.pbrt.meshes import MeshData

        out: dict[str, Any] = {"name": shape.name} if shape.name else {}
        if isinstance(shape.analytic, SdfGridSurface):  # its samples as a volume file beside the scene
            file = f"{self.assets}/{folder_name}.vol"
            self.files[file] = partial(_write_vol, values=shape.analytic.values)
            out |= {"type": "sdfgrid", "file": file, "normals": shape.analytic.normals}
            out["transform"] = [{"matrix": np.asarray(shape.analytic.to_world).tolist()}]
        elif isinstance(shape.analytic, CurveSurface) and shape.analytic.curve_type == "ribbon":
            # A ribbon's normals have no place in a curve file: its one curve inline, a normal per point.
            lines, normals = shape.analytic.polylines(), shape.analytic.ribbon_normals
            if len(lines) != 1 or normals is None:
                raise SpectraceError("a ribbon curve shape of several curves: a scene file holds one per shape", where)
            out |= {"type": "curve", "points": lines[0].tolist(), "basis": "linear", "curve_type": "ribbon"}
            out["curve_normals"] = np.concatenate([normals[:, 0], normals[-1:, 1]]).tolist()
        elif isinstance(shape.analytic, CurveSurface):
            # Its segments as linear curves in a curve file, which read back as the same segments.
            file = f"{self.assets}/{folder_name}.txt"
            self.files[file] = partial(_write_curves, polylines=shape.analytic.polylines())
            out |= {"type": "curve", "file": file, "basis": "linear", "open_ends": shape.analytic.open_ends}
            if shape.analytic.curve_type != "tube":
                out["curve_type"] = shape.analytic.curve_type
            if not shape.analytic.pbrt_uv:
                out["uv_convention"] = "mitsuba"
        elif shape.analytic is not None:
            surface = shape.analytic
            out |= {"type": surface.kind, "transform": [{"matrix": np.asarray(surface.to_world).tolist()}]}
            if surface.flip_normals:
                out["flip_normals"] = True
            if surface.pbrt_uv:
                out["uv_convention"] = "pbrt"
            out |= surface.cut_keys()
        else:
            mesh = shape.mesh
            file = f"{self.assets}/{folder_name}.ply"
            uvs = None if mesh.uvs is None else np.column_stack([mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]])
            data = MeshData(np.asarray(mesh.vertices), np.asarray(mesh.faces), mesh.normals, uvs)
            self.files[file] = partial(_write_ply, mesh=data)
            out |= {"type": "mesh", "file": file}
        if shape.material is not None:
            out["material"] = self.material(shape.material, f"{where}.material", shape.name)
        if shape.emitter is not None:
            out["emitter"] = self.table(shape.emitter, f"{where}.emitter")
            out["emitter"].pop("type", None)
        if shape.interior is not None:
            out["interior"] = self.table(shape.interior, f"{where}.interior")
            out["interior"].pop("type", None)
        return out

    # ------------------------------------------------------------ the scene

    def document(self) -> dict:
        from spectrace.film.response import FilmResponse
        from spectrace.pixel_filters import BOX_FILTER
        from spectrace.session.session import _camera_table

        scene = self.scene
        if scene.pixel_filter != BOX_FILTER:
            raise SpectraceError("a pixel filter other than the box is not written to a scene file yet", "pixel_filter")
        film: dict[str, Any] = {"width": scene.width, "height": scene.height, "exposure": scene.exposure}
        default = FilmResponse()
        for field in dataclasses.fields(scene.film_response):
            value = getattr(scene.film_response, field.name)
            if value != getattr(default, field.name):
                film[field.name] = self.value(value, "", f"film.{field.name}")
        integrator = {
            "type": scene.integrator,
            "max_depth": scene.max_depth,
            "rr_depth": scene.rr_depth,
            "hide_environment": scene.hide_environment,
            "hide_emitters": scene.hide_emitters,
        }
        if not scene.count_thin_passes:
            integrator["count_thin_passes"] = False
        if scene.pixels_per_light_path is not None:
            integrator["pixels_per_light_path"] = scene.pixels_per_light_path
        # What makes a render polarised or adds images beside it (docs/polarization.md) is the scene's, not a plugin's.
        if scene.camera.lens_system is not None:  # a scene file names a lens file, which a lens made in Python lacks
            raise SpectraceError("a realistic camera is written by its lens_file: load its scene from a file", "camera")
        camera = _camera_table(scene.camera)
        if scene.camera.polarizer_angle is not None:
            camera["polarizer_angle"] = scene.camera.polarizer_angle
        if scene.polarized:
            integrator["polarized"] = True
        if scene.aovs:
            film["aovs"] = list(scene.aovs)
        shapes = [self.shape(s, f"shapes[{i}]", f"shape_{i}") for i, s in enumerate(scene.shapes)]
        objects: dict[str, dict] = {}
        object_names: dict[int, str] = {}
        instances = []
        for instance in scene.instances:
            obj = instance.object
            if id(obj) not in object_names:
                name = self._unique(objects, obj.name or "object")
                object_names[id(obj)] = name
                objects[name] = {
                    "shapes": [
                        self.shape(s, f"objects.{name}.shapes[{k}]", f"{name}_{k}") for k, s in enumerate(obj.shapes)
                    ]
                }
            placed: dict[str, Any] = {
                "object": object_names[id(obj)],
                "transform": [{"matrix": np.asarray(instance.to_world).tolist()}],
            }
            if instance.name:
                placed["name"] = instance.name
            instances.append(placed)
        lights = [self.table(light, f"lights[{i}]") for i, light in enumerate(scene.lights)]
        data: dict[str, Any] = {
            "camera": camera,
            "film": film,
            "integrator": integrator,
            "sampler": {"type": scene.sampler, "spp": scene.spp, "seed": scene.seed},
            "textures": self.textures,
            "materials": self.materials,
            "shapes": shapes,
            "lights": lights,
            "objects": objects,
            "instances": instances,
        }
        return {key: value for key, value in data.items() if value != [] and value != {}}


def _write_vol(path: Path, values: np.ndarray) -> None:
    """An SDF grid's samples as a float32 Mitsuba volume file (the grid's own precision)."""
    from spectrace.geometry.grid_volume import vol_bytes

    path.write_bytes(vol_bytes(values))


def _write_curves(path: Path, polylines: list) -> None:
    """A curve file (geometry/curves.py read_curve_file): `x y z radius` per line in shortest round-trip form, a
    blank line between curves."""
    text = "\n\n".join("\n".join(" ".join(repr(float(v)) for v in row) for row in line) for line in polylines)
    path.write_text(text + "\n", encoding="utf-8")


def _write_ply(path: Path, mesh: Any) -> None:
    """A binary PLY of doubles, which spectrace's mesh reader takes as stored: the model's float64 positions,
    normals and texture coordinates read back as the same numbers."""
    columns, names = [mesh.vertices], ["x", "y", "z"]
    if mesh.normals is not None:
        columns.append(mesh.normals)
        names += ["nx", "ny", "nz"]
    if mesh.uvs is not None:
        columns.append(mesh.uvs)
        names += ["u", "v"]
    vertices = np.ascontiguousarray(np.column_stack(columns), dtype="<f8")
    faces = np.zeros(len(mesh.faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"], faces["i"] = 3, mesh.faces
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(vertices)}"]
    header += [f"property double {name}" for name in names]
    header += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header", ""]
    with open(path, "wb") as handle:
        handle.write("\n".join(header).encode("ascii"))
        handle.write(vertices.tobytes())
        handle.write(faces.tobytes())


def scene_data(scene: Scene, toml_path: Path) -> tuple[dict, dict[str, Callable[[Path], object]]]:
    """The scene file's keys of `scene` (a scene built in Python) to be written as `toml_path`, and its files (name
    relative to the TOML's folder -> writer)."""
    writer = _Writer(scene, toml_path.parent, f"{toml_path.stem}_meshes")
    return writer.document(), writer.files


def save_scene(scene: Scene, path: str | Path, *, header: str = "") -> Path:
    """Write `scene`, built in Python with spectrace's constructors, as the scene file `path` (TOML, its mesh shapes
    as PLY files in the folder `<stem>_meshes` beside it), all or nothing: the file is loaded back from where it
    lies before it, or any file beside it, replaces what was there. Loading it renders the same image as `scene`
    (same seed, same bits). A failure is one SpectraceError naming the file or the object that cannot be written."""
    from spectrace.interop.toml_writer import lock_import, write_imported_scene
    from spectrace.io.output_files import check_output_file
    from spectrace.scene.model import Scene

    if not isinstance(scene, Scene):
        raise SpectraceError(f"save_scene() writes a spectrace.Scene, got {type(scene).__name__}")
    path = Path(path)
    if path.suffix.lower() != ".toml":
        raise SpectraceError(f"a scene file ends in .toml, got '{path.name}'", where=str(path))
    data, files = scene_data(scene, path)  # refused, naming what cannot be written, before any file is touched
    check_output_file(path, str(path), create_folders=True)

    def told_at(error: SpectraceError, temp: Path) -> SpectraceError:
        return SpectraceError(str(error).replace(str(temp), str(path)))

    with lock_import(path, str(path), "spectrace.save_scene"):
        write_imported_scene(
            path,
            data,
            header or "A scene built with spectrace's Python API",
            files,
            told_at,
            option=str(path),
            command="spectrace.save_scene",
        )
    return path
