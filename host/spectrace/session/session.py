"""`Session`: a scene built once (device, program, BVH, buffers), rendered a pass at a time and edited by key path.

An edit is checked as the scene file's key would be (the schema, then the loader's checks: one SpectraceError naming
the key path, and nothing applied), then carried out by the cheapest means that renders the same bits as a fresh
render of the edited scene: the camera and the seed go with each pass's render parameters; a material's, light's or
emitter's parameters re-pack those rows (spectrace.engine.scene_edits) and rewrite their device buffers; an
instance's transform rebuilds the instances' top level only; exposure, colour space and white balance apply to the
image, not to the samples, which are kept. Anything else (a shape's geometry, the film's size, the integrator) loads
the scene again from the edited file's keys and builds it anew, and the report says so. Every edit but the image's
starts the accumulation again.

Keys follow the scene file: `camera.fov`, `materials.red.reflectance`, `lights.0.power`,
`shapes.<name>.emitter.scale`, `instances.<name>.transform`, `film.exposure`, `sampler.seed`; an entry of an array of
tables ([[shapes]], [[lights]], [[instances]]) goes by its name or its index. A scene built in Python names its
materials, lights, emitters and media by their place and their parameters by their constructors' arguments
(spectrace.session.python_scene).
"""

from __future__ import annotations

import copy
import dataclasses
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from numbers import Real
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from spectrace.errors import SpectraceError
from spectrace.film.colour_output import Adaptation, ColourSpace, WhiteBalance
from spectrace.session import python_scene
from spectrace.session.python_scene import ModelEdits

if TYPE_CHECKING:
    from spectrace.device import Device
    from spectrace.engine.job import RenderJob
    from spectrace.engine.renderer import Renderer
    from spectrace.engine.scene_buffers import SceneBuffers
    from spectrace.film.image import Image
    from spectrace.scene.model import Scene

# What each kind of edit costs, in the order they are carried out.
IN_PLACE = "in place"  # rewritten device buffers or render parameters; the accumulation restarts
IMAGE_ONLY = "image only"  # applied to the image of the samples kept
REBUILT = "rebuilt"  # the scene loaded and built again
CHECKED = "checked"  # the edited keys checked by the schema and resolved, as the loader does (nothing applied yet)


@dataclass(frozen=True)
class UpdateStep:
    """One part of an update: what it changed (`what`: camera, materials, lights, instances, film, seed, program,
    scene), the keys that asked for it, how it was done (IN_PLACE, IMAGE_ONLY, REBUILT), what was redone or
    re-uploaded (`detail`) and the wall seconds it took."""

    what: str
    keys: tuple[str, ...]
    how: str
    detail: str
    seconds: float


@dataclass(frozen=True)
class UpdateReport:
    """What `Session.update` did: its steps, whether the accumulation restarted, and the seconds it took in all."""

    steps: tuple[UpdateStep, ...]
    restarted: bool
    seconds: float

    @property
    def rebuilt(self) -> bool:
        """Whether some part could not be done in place and the scene was built again."""
        return any(step.how == REBUILT for step in self.steps)

    def __str__(self) -> str:
        lines = []
        for step in self.steps:
            keys = f" ({', '.join(step.keys)})" if step.keys else ""
            lines.append(f"{step.what}{keys}: {step.how}, {step.detail}, {step.seconds * 1e3:.1f} ms")
        restart = "accumulation restarted" if self.restarted else "samples kept"
        return "\n".join([*lines, f"{restart}; {self.seconds * 1e3:.1f} ms in all"])


# Keys of the film that are the image's, not the scene file's (render options there).
_OUTPUT_KEYS = ("film.colour_space", "film.white_balance", "film.adaptation")
# Keys of [film] that change what the film responds to (its observers and sensor) and nothing of the scene's buffers.
_RESPONSE_KEYS = ("observer", "observers", "sensor", "sensor_white")
# Tables of arrays whose entries a key may name by their `name`.
_ARRAYS = ("shapes", "lights", "instances")


def _plain(value: object) -> object:
    """A value as TOML would give it: lists for tuples and arrays, Python numbers for NumPy's."""
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


def _camera_table(camera) -> dict[str, object]:
    """The [camera] table of a model camera (a scene built in Python), as a scene file would write it."""
    from spectrace.cameras import CAMERAS

    table: dict[str, object] = {
        "type": camera.type,
        "origin": list(camera.origin),
        "target": list(camera.target),
        "up": list(camera.up),
        "near_clip": camera.near_clip,
    }
    if camera.far_clip is not None:
        table["far_clip"] = camera.far_clip
    fields = {field.name for field in dataclasses.fields(camera)}
    for parameter in CAMERAS[camera.type].PARAMETERS:
        name = parameter.api_name or parameter.name
        if name in fields and parameter.name not in table:
            table[parameter.name] = _plain(getattr(camera, name))
    return table


def _film_response(response, key: str, value: object, where: str):
    """A Python scene's film response with `key` set to `value`, checked as FilmResponse checks its fields."""
    if key == "observers":
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise SpectraceError(f"expected a list of observers' names, got {value!r}", where=where)
        value = tuple(value)
    elif key in ("observer", "sensor_white") and not (
        isinstance(value, str) or (key == "sensor_white" and value is None)
    ):
        raise SpectraceError(f"expected a name, got {value!r}", where=where)
    try:
        return replace(response, **{key: value})
    except SpectraceError as error:
        raise SpectraceError(error.message, where=where) from None


class Session:
    """A live render of one scene: built once on the device, rendered a pass at a time (`step`), its image read
    at any time (`image`), and edited by key path (`update`), each edit rebuilding or re-uploading only what it
    changed. `Session(scene)` takes a Scene (or a scene file's path); device, spectral_bins, colour_space,
    white_balance, adaptation and aovs as for `spectrace.render`; `pass_spp` samples per pixel per `step()`.
    A context manager: `close()` at the end."""

    def __init__(
        self,
        scene: Scene | str | Path,
        *,
        device: Device | str | None = None,
        spectral_bins: int = 0,
        pass_spp: int = 1,
        colour_space: ColourSpace | str = ColourSpace.SRGB,
        white_balance: WhiteBalance | str | None = None,
        adaptation: Adaptation | str = Adaptation.BRADFORD,
        aovs: str | Sequence[str] | None = None,
    ) -> None:
        from spectrace.core import limits
        from spectrace.engine.job import RenderJob
        from spectrace.scene import load_scene
        from spectrace.scene.model import Scene

        if isinstance(scene, (str, Path)):
            scene = load_scene(scene)
        if not isinstance(scene, Scene):
            raise SpectraceError(f"Session() needs a spectrace.Scene, got {type(scene).__name__}")
        if problem := limits.pass_spp_problem(pass_spp):
            raise SpectraceError(problem, where="pass_spp")
        job = RenderJob.make(
            scene,
            spectral_bins=spectral_bins,
            aovs=aovs,
            colour_space=colour_space,
            white_balance=white_balance,
            adaptation=adaptation,
            device=device,
        )
        self._start(job, pass_spp)

    @classmethod
    def for_job(cls, job: RenderJob, pass_spp: int = 1) -> Session:
        """A session of a render job already checked (what `spectrace.render` renders through)."""
        session = cls.__new__(cls)
        session._start(job, pass_spp)
        return session

    def _start(self, job: RenderJob, pass_spp: int) -> None:
        from spectrace.device import Device, open_device

        self._lock = threading.RLock()
        self.pass_spp = pass_spp
        self._job = job
        self._outputs = job.outputs
        white = job.outputs.white_balance
        self._output_values: dict[str, object] = {
            "film.colour_space": ColourSpace(job.outputs.colour_space).value,
            "film.white_balance": white.label if white is not None else None,
            "film.adaptation": Adaptation(white.method).value if white is not None else Adaptation.BRADFORD.value,
        }
        self._device = job.device if isinstance(job.device, Device) else open_device(job.device)
        source = job.scene.source
        self._source = source if source is not None and source.suffix.lower() == ".toml" else None
        # The scene file's keys and its materials by name, read when first asked (an update, parameters()).
        self._read_data: dict | None = None
        self._read_materials: dict[str, Any] | None = None
        # Textures by their table: a material resolved again reuses its unchanged textures, rows and texels.
        self._texture_cache: dict[tuple[str, str], object] = {}
        self._renderer: Renderer | None = self._build(job.scene)

    @property
    def _data(self) -> dict:
        if self._read_data is None:
            scene = self._open().scene
            self._read_data = self._file_data(scene) if self._source is not None else self._model_data(scene)
        return self._read_data

    @_data.setter
    def _data(self, data: dict) -> None:
        self._read_data = data

    @property
    def _materials(self) -> dict[str, Any]:
        if self._read_materials is None:
            self._read_materials = self._named_materials(self._open().scene) if self._source is not None else {}
        return self._read_materials

    @_materials.setter
    def _materials(self, materials: dict[str, Any]) -> None:
        self._read_materials = materials

    # ------------------------------------------------------------------ rendering

    @property
    def scene(self) -> Scene:
        """The scene with every edit applied."""
        return self._open().scene

    @property
    def samples_done(self) -> int:
        return self._open().samples_done

    @property
    def renderer(self) -> Renderer:
        return self._open()

    def step(self, spp: int | None = None) -> None:
        """Render one more pass of `spp` samples per pixel (default: pass_spp) into the accumulation."""
        from spectrace.core import limits

        count = self.pass_spp if spp is None else spp
        if problem := limits.pass_spp_problem(count):
            raise SpectraceError(problem, where="spp")
        with self._lock:
            self._open().run_pass(count)

    def image(self) -> Image:
        """The image of the samples so far, in the session's colour space and white balance."""
        with self._lock:
            return self._outputs.apply(self._open().image())

    def _open(self) -> Renderer:
        if self._renderer is None:
            raise SpectraceError("the session is closed")
        return self._renderer

    def close(self) -> None:
        """Let the device buffers go; the session renders no more."""
        with self._lock:
            self._renderer = None

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ------------------------------------------------------------------ parameters

    def parameters(self) -> dict[str, object]:
        """The editable parameters by key path (as the scene file names them) with their current values."""
        data = self._data
        found: dict[str, object] = {}
        for key, value in data.get("camera", {}).items():
            if key != "type":
                found[f"camera.{key}"] = value
        found["film.exposure"] = data.get("film", {}).get("exposure", 0.0)
        found |= self._output_values
        found["sampler.seed"] = data.get("sampler", {}).get("seed", 0)
        for name, table in data.get("materials", {}).items():
            found |= {f"materials.{name}.{key}": value for key, value in table.items() if key != "type"}
        if self._source is None:
            found |= python_scene.parameters(self.scene)
        for array in _ARRAYS:
            for i, entry in enumerate(data.get(array, [])):
                label = self._label(array, i)
                keys = {"shapes": ("transform", "emitter"), "instances": ("transform",)}.get(array)
                for key, value in entry.items():
                    if key in ("name", "type") or (keys is not None and key not in keys):
                        continue
                    if isinstance(value, dict):
                        found |= {f"{array}.{label}.{key}.{inner}": v for inner, v in value.items()}
                    else:
                        found[f"{array}.{label}.{key}"] = value
        return copy.deepcopy(found)

    def _value(self, key: object, value: object) -> object:
        """A value as the edit takes it: a scene file's as TOML gives it; a Python scene's object's argument as the
        caller gave it (an image's array, a Spectrum) for its constructor."""
        if self._source is None and str(key).split(".")[0] in ("materials", "lights", "shapes"):
            return value
        return _plain(value)

    def _label(self, array: str, index: int) -> str:
        """How a key names entry `index` of `array`: its name where no other entry has it, else its index."""
        entries = self._data.get(array, [])
        name = entries[index].get("name")
        return name if name and sum(e.get("name") == name for e in entries) == 1 else str(index)

    def _data_key(self, key: str) -> str:
        """`key` with an array entry's name replaced by its index (the form the scene file's key paths take)."""
        part, _, rest = key.partition(".")
        if part not in _ARRAYS or not rest:
            return key
        entries = self._data.get(part, [])
        first = rest.split(".")[0]
        if first.isdigit() and int(first) < len(entries):
            return key  # by its index
        for i in range(len(entries)):
            label = self._label(part, i)
            if rest.startswith(label + ".") or rest == label:
                return f"{part}.{i}{rest[len(label) :]}"
        raise SpectraceError(f"the scene has no {part} entry named by '{rest.split('.')[0]}'", where=key)

    # ------------------------------------------------------------------ updates

    def update(self, changes: Mapping[str, object]) -> UpdateReport:
        """Apply `changes` (key path -> value, as the scene file would give it), all or none: a bad key or value
        raises a SpectraceError naming its key path and changes nothing. Returns what was done and how long each
        part took; the accumulation restarts unless only the image's settings (exposure, colour space, white
        balance) changed."""
        if not isinstance(changes, Mapping):
            raise SpectraceError(f"update() takes a mapping of key paths to values, got {type(changes).__name__}")
        started = time.perf_counter()
        with self._lock:
            self._open()
            steps = self._update(changes)
        restarted = any(step.how in (IN_PLACE, REBUILT) for step in steps)
        return UpdateReport(tuple(steps), restarted, time.perf_counter() - started)

    def _update(self, changes: Mapping[str, object]) -> list[UpdateStep]:
        from spectrace.film.output_options import RenderOutputOptions

        started = time.perf_counter()
        outputs = {key: _plain(value) for key, value in changes.items() if key in _OUTPUT_KEYS}
        edits = {
            self._data_key(str(key)): self._value(key, value)
            for key, value in changes.items()
            if key not in _OUTPUT_KEYS
        }
        given = {self._data_key(str(key)): str(key) for key in changes if key not in _OUTPUT_KEYS}
        steps: list[UpdateStep] = []
        new_outputs = None
        if outputs:
            values = self._output_values | outputs
            for key in ("film.colour_space", "film.adaptation"):
                if not isinstance(values[key], str):
                    raise SpectraceError(f"expected a name, got {values[key]!r}", where=key)
            white = values["film.white_balance"]
            if white is not None and not isinstance(white, str):
                raise SpectraceError(f"expected a white's name or None, got {white!r}", where="film.white_balance")
            new_outputs = RenderOutputOptions.parse(
                None,
                str(values["film.colour_space"]),
                white or None,
                str(values["film.adaptation"]),
                names=_OUTPUT_KEYS,
            )
        plan = _Plan(self, edits, given) if edits else None
        if plan is not None:
            steps.append(UpdateStep("keys", tuple(given.values()), CHECKED, "validated and resolved", 0.0))
        steps = [replace(step, seconds=time.perf_counter() - started) for step in steps]
        # Everything is checked: from here on it is applied, all or nothing (_undo).
        undo = self._undo()
        try:
            if new_outputs is not None:
                self._outputs = new_outputs
                self._output_values = self._output_values | outputs
                steps.append(UpdateStep("film", tuple(outputs), IMAGE_ONLY, "colour output", 0.0))
            if plan is not None:
                steps += plan.apply()
        except BaseException:
            undo(plan.uploading if plan is not None else set())
            raise
        return steps

    def _undo(self):
        """A function putting the session back as it is now, for an update that fails part-way (a texture over the
        budget, a program the device cannot build, an upload that fails): its renderer and the scene and buffers
        that renderer holds, the packing the next edit starts from, the keys and the image's settings. Handed the
        device buffers the update had begun to rewrite, it uploads them again from the buffers kept, so that the
        next pass renders the unedited scene bit for bit."""
        from spectrace.engine.packing_checkpoint import checkpoint

        renderer = self._open()
        scene, buffers = renderer.scene, renderer.buffers
        packing = checkpoint(buffers)
        kept = (self._outputs, self._output_values, self._read_data, self._read_materials)
        materials = dict(self._read_materials or {})

        def undo(uploading: set[str]) -> None:
            packing()
            self._renderer = renderer
            self._outputs, self._output_values, self._read_data, self._read_materials = kept
            if self._read_materials is not None:  # updated in place by a plan's commit
                self._read_materials.clear()
                self._read_materials.update(materials)
            if uploading:
                renderer.replace_scene(scene, buffers, uploading)
            renderer.scene, renderer.buffers = scene, buffers

        return undo

    # ------------------------------------------------------------------ building

    def _build(self, scene: Scene) -> Renderer:
        from spectrace.engine.scene_buffers import build_scene_buffers

        try:
            buffers = build_scene_buffers(scene, keep_packing=True)
        except SpectraceError as exc:
            if exc.where or scene.source is None:
                raise
            raise SpectraceError(exc.message, where=str(scene.source)) from None
        return self._renderer_of(scene, buffers)

    def _renderer_of(self, scene: Scene, buffers: SceneBuffers) -> Renderer:
        from spectrace.engine.wavefront import make_renderer

        job = self._job
        return make_renderer(scene, self._device, job.kernel, spectral_bins=job.spectral_bins, buffers=buffers)

    def _file_data(self, scene: Scene) -> dict:
        from spectrace.scene.loader import read_scene_data, set_key_path

        assert scene.source is not None
        data = read_scene_data(scene.source)
        for key, value in scene.notes.get("overrides", {}).items():  # the scene's: load_scene(path, overrides)
            set_key_path(data, key, value, where=f"{scene.source}: {key}")
        return data

    @staticmethod
    def _model_data(scene: Scene) -> dict:
        """The keys of a scene built in Python that a session edits, as a scene file would hold them."""
        return {
            "camera": _camera_table(scene.camera),
            "film": {"exposure": scene.exposure},
            "sampler": {"seed": scene.seed},
            # Names only: the keys of shapes and lights that a session edits are their objects' (python_scene).
            "shapes": [{"name": python_scene.shape_label(list(scene.shapes), i)} for i in range(len(scene.shapes))],
            "lights": [{} for _ in scene.lights],
            "instances": [
                {"name": instance.name, "transform": [{"matrix": _plain(np.asarray(instance.to_world))}]}
                for instance in scene.instances
            ],
        }

    def _named_materials(self, scene: Scene) -> dict[str, Any]:
        """The scene's material objects by the names its file gives them (those its shapes use)."""
        named: dict[str, Any] = {}
        for spec, shape in zip(self._data.get("shapes", []), scene.shapes):
            if spec.get("material") is not None and shape.material is not None:
                named[spec["material"]] = shape.material
        objects = {instance.object.name: instance.object for instance in scene.instances}
        for name, table in self._data.get("objects", {}).items():
            if name in objects:
                for spec, shape in zip(table.get("shapes", []), objects[name].shapes):
                    if spec.get("material") is not None and shape.material is not None:
                        named[spec["material"]] = shape.material
        return named


class _Plan:
    """One update checked and resolved: the edited scene, and which parts of the build it touches."""

    def __init__(self, session: Session, edits: dict[str, object], given: dict[str, str]) -> None:
        self.session = session
        self.given = given
        self.scene = session.scene
        self.kinds: dict[str, list[str]] = {}  # kind -> the keys (as given) that ask for it
        self.new_materials: dict[str, Any] = {}  # the materials resolved again, by name
        self.light_edits: tuple[set[int] | None, bool] = (None, True)  # the lights written again (None: all), emitters?
        self.uploading: set[str] = set()  # the device buffers apply() began to rewrite
        data = copy.deepcopy(session._data)
        source = session._source
        if source is None:
            self._model_edits(data, edits)
        else:
            self._file_edits(source, data, edits)
        self.data = data

    def _add(self, kind: str, key: str) -> None:
        self.kinds.setdefault(kind, []).append(self.given.get(key, key))

    # --------------------------------------------------------- a scene file's keys

    def _file_edits(self, source: Path, data: dict, edits: dict[str, object]) -> None:
        from spectrace.scene.loader import _Resolver, scene_from_spec, set_key_path, validate_scene_data

        for key, value in edits.items():
            set_key_path(data, key, value, where=f"{source}: {self.given.get(key, key)}")
        spec = validate_scene_data(source, data)
        emitters, lights, materials, instances, interiors = set(), set(), set(), set(), set()
        for key in edits:
            parts = key.split(".")
            head = parts[0]
            if head == "camera":
                self._add("camera", key)
            elif key == "film.exposure":
                self._add("exposure", key)
            elif key == "sampler.seed":
                self._add("seed", key)
            elif head == "film" and len(parts) >= 2 and parts[1] in _RESPONSE_KEYS:
                self._add("film response", key)
            elif head == "materials" and len(parts) > 2:
                materials.add(self._material_name(key, data))
                self._add("materials", key)
            elif head in ("textures", "spectra") and len(parts) > 2:
                self._add("shading", key)
            elif head == "lights" and len(parts) > 2:
                lights.add(int(parts[1]))
                self._add("lights", key)
            elif head == "shapes" and len(parts) > 3 and parts[2] == "emitter" and self._emits(int(parts[1]), spec):
                emitters.add(int(parts[1]))
                self._add("lights", key)
            elif head == "shapes" and len(parts) > 3 and parts[2] == "interior" and self._filled(int(parts[1]), spec):
                interiors.add(int(parts[1]))
                self._add("media", key)
            elif head == "instances" and len(parts) > 2 and parts[2] == "transform":
                instances.add(int(parts[1]))
                self._add("instances", key)
            else:
                self._add("scene", key)
        if "scene" in self.kinds:  # loaded again from the edited keys, as a fresh render would load them
            rebuilt = scene_from_spec(source, spec)
            self.scene = rebuilt.with_overrides(aovs=self.scene.aovs, spp=self.scene.spp)
            return
        if "shading" in self.kinds:
            materials = set(spec.materials)
            lights = set(range(len(spec.lights)))
            emitters = {i for i, s in enumerate(spec.shapes) if s.emitter is not None}
        resolver = _Resolver(source, spec)
        resolver.texture_cache = self.session._texture_cache
        scene = self.scene
        if "camera" in self.kinds:
            from spectrace.scene.loader import _check_camera, camera_from_spec

            camera = camera_from_spec(spec.camera, Path(source).parent)
            _check_camera(camera, source)
            scene = replace(scene, camera=camera)
        if "exposure" in self.kinds:
            scene = replace(scene, exposure=spec.film.exposure)
        if "seed" in self.kinds:
            scene = replace(scene, seed=spec.sampler.seed)
        if "film response" in self.kinds:
            from spectrace.scene.loader import _film_response

            scene = replace(scene, film_response=_film_response(spec.film, resolver))
        if materials:
            scene = self._materials(scene, spec, resolver, materials, source)
        if interiors:
            shapes = list(scene.shapes)
            for i in interiors:
                interior = spec.shapes[i].interior
                assert interior is not None  # _filled
                shapes[i] = replace(shapes[i], interior=resolver.interior(interior, f"shapes[{i}].interior"))
            scene = replace(scene, shapes=shapes)
        if lights or emitters:
            scene = self._lights(scene, spec, resolver, lights, emitters, source)
        self.light_edits = (None, True) if "shading" in self.kinds else (lights, bool(emitters))
        if instances:
            placed = list(scene.instances)
            for i in instances:
                matrix = resolver.instance_matrix(spec.instances[i], f"instances[{i}]", placed[i].object)
                placed[i] = replace(placed[i], to_world=matrix)
            scene = replace(scene, instances=placed)
        self.scene = scene

    def _emits(self, index: int, spec) -> bool:
        """Whether shape `index` emits before and after the edit (a light more or fewer is a rebuild)."""
        return spec.shapes[index].emitter is not None and self.scene.shapes[index].emitter is not None

    def _filled(self, index: int, spec) -> bool:
        """Whether shape `index` has a medium inside before and after the edit (one more or fewer is a rebuild)."""
        return spec.shapes[index].interior is not None and self.scene.shapes[index].interior is not None

    def _material_name(self, key: str, data: dict) -> str:
        rest = key.removeprefix("materials.")
        names = [name for name in data.get("materials", {}) if rest.startswith(name + ".")]
        return max(names, key=len)

    def _materials(self, scene: Scene, spec, resolver, names: set[str], source: Path) -> Scene:
        from spectrace.materials import uv_material_textures

        named = self.session._materials
        # A mix holds its parts: every mix is resolved again, from the parts as they are now.
        redo = set(names) | {name for name, table in spec.materials.items() if table.type == "mix"}
        resolver.named_materials.update({name: m for name, m in named.items() if name not in redo})
        new = {name: resolver.material_named(name, f"materials.{name}") for name in sorted(redo)}
        swap = {id(named[name]): material for name, material in new.items() if name in named}

        def swapped(shapes, specs):
            out = []
            for shape, shape_spec in zip(shapes, specs):
                material = swap.get(id(shape.material), shape.material)
                if material is not shape.material and shape.mesh.uvs is None and uv_material_textures(material):
                    raise SpectraceError(
                        f"shape '{shape.name}' has no texture coordinates, but material '{shape_spec.material}' "
                        f"has a texture ({', '.join(uv_material_textures(material))})",
                        where=f"{source}: materials.{shape_spec.material}",
                    )
                out.append(replace(shape, material=material))
            return out

        shapes = swapped(scene.shapes, spec.shapes)
        objects: dict[int, Any] = {}
        instances = []
        for instance in scene.instances:
            obj = instance.object
            if id(obj) not in objects:
                object_spec = spec.objects[obj.name]
                objects[id(obj)] = replace(obj, shapes=swapped(obj.shapes, object_spec.shapes))
            instances.append(replace(instance, object=objects[id(obj)]))
        self.new_materials = new
        return replace(scene, shapes=shapes, instances=instances)

    def _lights(self, scene: Scene, spec, resolver, lights: set[int], emitters: set[int], source: Path) -> Scene:
        from spectrace.lights import LIGHTS

        placed = list(scene.lights)
        for i in sorted(lights):
            placed[i] = LIGHTS[spec.lights[i].type].from_spec(spec.lights[i], resolver, f"lights[{i}]")
        shapes = list(scene.shapes)
        for i in sorted(emitters):
            emitter = resolver.emitter(spec.shapes[i].emitter, f"shapes[{i}].emitter")
            if emitter.image is not None and shapes[i].mesh.uvs is None:
                raise SpectraceError(
                    f"shape '{shapes[i].name}' has no texture coordinates, but its emitter shows an image",
                    where=f"{source}: shapes[{i}].emitter.radiance",
                )
            shapes[i] = replace(shapes[i], emitter=emitter)
        return replace(scene, lights=placed, shapes=shapes)

    # --------------------------------------------------------- a scene built in Python

    def _model_edits(self, data: dict, edits: dict[str, object]) -> None:
        from pydantic import TypeAdapter, ValidationError

        from spectrace.core import limits
        from spectrace.geometry.transforms import transform_matrix
        from spectrace.scene import schema
        from spectrace.scene.loader import camera_from_spec, set_key_path

        scene = self.scene
        objects = ModelEdits(scene)
        for key, value in edits.items():
            given = self.given.get(key, key)
            parts = key.split(".")
            placement = parts[0] == "instances" and len(parts) == 3 and parts[2] == "transform"
            if key in ("film.exposure", "sampler.seed") or (parts[0] == "camera" and len(parts) == 2) or placement:
                set_key_path(data, key, value, where=given)
            elif parts[0] in ("materials", "lights", "shapes") and len(parts) > 2:
                objects.stage(key, value, given)
                continue
            elif parts[0] == "film" and len(parts) == 2 and parts[1] in _RESPONSE_KEYS:
                scene = replace(scene, film_response=_film_response(scene.film_response, parts[1], value, given))
                self._add("film response", key)
                continue
            else:
                raise SpectraceError(
                    "a scene built in Python edits its camera, film.exposure, the film's observer, observers, sensor "
                    "and sensor_white, sampler.seed, instance transforms and the parameters of its materials, "
                    "lights, emitters and media (session.parameters() lists them); other keys name a scene file's "
                    "tables (load_scene)",
                    where=given,
                )
            if parts[0] == "camera":
                self._add("camera", key)
            elif key == "film.exposure":
                if isinstance(value, bool) or not isinstance(value, Real):
                    raise SpectraceError(f"expected a number of stops, got {value!r}", where=given)
                if problem := limits.exposure_problem(float(value)):
                    raise SpectraceError(problem, where=given)
                scene = replace(scene, exposure=float(value))
                self._add("exposure", key)
            elif key == "sampler.seed":
                if problem := limits.whole_number_problem("seed", value):
                    raise SpectraceError(problem, where=given)
                assert isinstance(value, int)
                if problem := limits.seed_problem(value):
                    raise SpectraceError(problem, where=given)
                scene = replace(scene, seed=value)
                self._add("seed", key)
            else:
                i = int(parts[1])
                matrix = transform_matrix(value, where=given)  # type: ignore[arg-type]
                placed = list(scene.instances)
                placed[i] = replace(placed[i], to_world=matrix)
                scene = replace(scene, instances=placed)
                self._add("instances", key)
        if "camera" in self.kinds:
            from spectrace.engine.job import check_camera

            try:
                camera_spec = TypeAdapter(schema.CameraSpec).validate_python(data["camera"])
            except ValidationError as exc:
                error = exc.errors()[0]
                where = ".".join(["camera", *(str(p) for p in error["loc"][1:] if isinstance(p, str))][:2])
                raise SpectraceError(error["msg"].removeprefix("Value error, "), where=where) from None
            scene = replace(scene, camera=camera_from_spec(camera_spec))
            check_camera(scene)
        if objects.kinds:
            scene, lights, emitters = objects.apply(scene)
            for kind, keys in objects.kinds.items():
                self.kinds.setdefault(kind, []).extend(keys)
            if lights or emitters:
                self.kinds.setdefault("lights", [])
            self.light_edits = (lights, emitters)
        self.scene = scene

    # --------------------------------------------------------- carrying it out

    def apply(self) -> list[UpdateStep]:
        from spectrace.engine import scene_edits

        session = self.session
        renderer = session._open()
        kinds = self.kinds
        every_key = tuple(key for keys in kinds.values() for key in keys)
        started = time.perf_counter()
        if "scene" in kinds:
            self._rebuild()
            return [UpdateStep("scene", every_key, REBUILT, "loaded and built again", time.perf_counter() - started)]
        steps: list[UpdateStep] = []
        buffers = renderer.buffers
        # Refused before anything of the session's buffers changes (the in-place edits keep the media's count).
        self._check(buffers)
        scene_edits.release_textures(renderer.scene, self.scene, buffers)  # their slots go to the edit's textures
        changed: set[str] = set()
        shading = kinds.get("shading", [])
        for kind, edit, detail in (
            ("materials", scene_edits.repack_materials, "material rows re-packed"),
            ("media", scene_edits.repack_media, "medium rows re-packed"),
            ("lights", self._repack_lights, "light rows and their distribution re-packed"),
            ("instances", scene_edits.place_instances, "top level of the BVH rebuilt"),
        ):
            if kind not in kinds and not (shading and kind in ("materials", "lights")):
                continue
            started = time.perf_counter()
            done = edit(self.scene, buffers)
            if done is None:  # a row more or fewer: the layout is not the one built
                started = time.perf_counter()
                self._rebuild()
                detail = f"{kind}: the rows' layout changed, built again"
                return [UpdateStep("scene", every_key, REBUILT, detail, time.perf_counter() - started)]
            buffers, more = done
            changed |= more
            keys = tuple(kinds.get(kind, []) + shading)
            seconds = time.perf_counter() - started
            steps.append(UpdateStep(kind, keys, IN_PLACE, f"{detail} ({', '.join(sorted(more))})", seconds))
        for kind in ("camera", "seed"):
            if kind in kinds:
                steps.append(UpdateStep(kind, tuple(kinds[kind]), IN_PLACE, "render parameters", 0.0))
        if "exposure" in kinds:
            steps.append(UpdateStep("film", tuple(kinds["exposure"]), IMAGE_ONLY, "exposure", 0.0))
        started = time.perf_counter()
        if "film response" in kinds:  # the film's table and channels are the program's: both made again
            session._renderer = session._renderer_of(self.scene, buffers)
            detail = "the film and its program built again over the same scene buffers"
            seconds = time.perf_counter() - started
            steps.append(UpdateStep("film", tuple(kinds["film response"]), REBUILT, detail, seconds))
        elif not renderer.program_fits(self.scene, buffers):
            session._renderer = session._renderer_of(self.scene, buffers)
            detail = "the scene's features changed: program and device buffers built again"
            steps.append(UpdateStep("program", every_key, REBUILT, detail, time.perf_counter() - started))
        elif set(kinds) - {"exposure"}:
            self.uploading = set(changed)  # from here the device's buffers may be part rewritten
            renderer.replace_scene(self.scene, buffers, changed)
            detail = f"uploaded {', '.join(sorted(changed)) or 'nothing'}; accumulation cleared"
            steps.append(UpdateStep("device", (), IN_PLACE, detail, time.perf_counter() - started))
        else:
            renderer.scene = self.scene  # the exposure alone is the image's: the samples stay
        self._commit()
        return steps

    def _repack_lights(self, scene: Scene, buffers: SceneBuffers):
        from spectrace.engine import scene_edits

        lights, emitters = self.light_edits
        return scene_edits.repack_lights(scene, buffers, lights, emitters)

    def _check(self, buffers: SceneBuffers) -> None:
        """What a renderer refuses of a scene it is built for, asked of the scene edited in place."""
        from spectrace.core import limits
        from spectrace.integrators import scene_settings_problem

        scene, renderer = self.scene, self.session._open()
        problem = (
            limits.scene_settings_problem(scene)
            or scene_settings_problem(scene)
            or renderer.integrator.problem(scene, buffers.medium_count, renderer.spectral_bins)
        )
        if problem:
            raise SpectraceError(problem, where=str(scene.source) if scene.source else None)

    def _rebuild(self) -> None:
        session = self.session
        session._renderer = session._build(self.scene)
        self._commit()
        session._materials = session._named_materials(self.scene) if session._source is not None else {}

    def _commit(self) -> None:
        self.session._data = self.data
        self.session._materials.update(self.new_materials)
