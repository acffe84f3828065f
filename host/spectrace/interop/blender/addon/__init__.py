"""spectrace as a Blender render engine: install this folder as an add-on (Edit > Preferences > Add-ons, or copy it
into Blender's scripts/addons; `spectrace blender-addon` prints where it is) in a Blender whose Python can import
spectrace, and choose "spectrace" as the render engine.

A final render (F12, or bpy.ops.render.render()) exports the evaluated scene of the render's depsgraph (modifiers at
their render levels) through spectrace.interop.blender, the same export as `spectrace import-blend`, into a
temporary folder; what it does not export is reported once per kind as a warning. It then renders the scene at the
Cycles sample count in a child process (spectrace.interop.blender.render_worker, so that Blender's libraries and
the OpenCL runtime never share a process), shows the samples done on the progress bar and in the status line after
each pass, the image so far in the Render Result as the worker sends it (after the first pass, then about once a
second), and the final image in its Combined pass. Esc stops the render after the pass in flight and shows the
image of the samples done. Viewport rendering is not implemented."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import bpy  # type: ignore[import-not-found, import-untyped, unused-ignore]  # Blender's, untyped; absent outside it

bl_info = {
    "name": "spectrace",
    "author": "spectrace",
    "version": (0, 2, 0),
    "blender": (4, 2, 0),
    "category": "Render",
    "description": "Render with spectrace, a spectral path tracer (final renders)",
}

_POLL_SECONDS = 0.1  # how often Esc is looked for while the child renders


def _lines(stream, found: queue.Queue) -> None:
    for line in stream:
        found.put(line)
    found.put(None)


class SpectraceRenderEngine(bpy.types.RenderEngine):
    bl_idname = "SPECTRACE"
    bl_label = "spectrace"
    bl_use_preview = False

    def render(self, depsgraph):
        from spectrace.errors import SpectraceError
        from spectrace.interop.blender.cameras import film
        from spectrace.interop.blender.importer import WARNING_PREFIX, write_blend_import

        scene = depsgraph.scene
        width, height = film(scene)
        spp = max(1, int(getattr(getattr(scene, "cycles", None), "samples", 16)))
        with tempfile.TemporaryDirectory(prefix="spectrace-blender-") as folder:
            toml, image = Path(folder) / "scene.toml", Path(folder) / "image.npy"
            blend = Path(bpy.data.filepath or "untitled.blend")
            self.update_stats("", "spectrace: exporting the scene")
            try:
                notes = write_blend_import(
                    bpy, scene, blend, toml, strict=False, option="the exported scene", depsgraph=depsgraph
                )
            except SpectraceError as error:
                self._fail(str(error))
                return
            for note in notes:
                if note.startswith(WARNING_PREFIX):
                    self.report({"WARNING"}, note[len(WARNING_PREFIX) :])
            if self.test_break():
                return
            self.update_stats("", "spectrace: building the scene on the device")
            result = self.begin_result(0, 0, width, height)
            failure = self._render_child(toml, image, spp, result)
            if failure is None:
                failure = self._show(result, image)
            self.end_result(result)
            if failure is not None:
                self._fail(failure)

    def _show(self, result, image: Path) -> str | None:
        """The worker's image file in the Render Result's Combined pass; None, or why it could not be shown."""
        import numpy as np

        rgb = np.load(image)[::-1]  # Blender's rows run bottom-up
        height, width = result.resolution_y, result.resolution_x
        if rgb.shape[:2] != (height, width):
            return f"the image is {rgb.shape[1]}x{rgb.shape[0]}, the render {width}x{height}"
        rgba = np.concatenate([rgb, np.ones((height, width, 1), dtype=np.float32)], axis=2)
        result.layers[0].passes["Combined"].rect = rgba.reshape(-1, 4)
        return None

    def _render_child(self, toml: Path, image: Path, spp: int, result) -> str | None:
        """Run the render worker, passing its progress and partial images on to Blender; None when it wrote the
        image, else why not."""
        from spectrace.interop.blender.render_worker import partial_path

        command = [sys.executable, "-m", "spectrace.interop.blender.render_worker", str(toml), str(image), str(spp)]
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        found: queue.Queue = queue.Queue()
        reader = threading.Thread(target=_lines, args=(child.stdout, found), daemon=True)
        reader.start()
        stopped = False
        while True:
            try:
                line = found.get(timeout=_POLL_SECONDS)
            except queue.Empty:
                if not stopped and self._stop_asked():
                    child.send_signal(signal.SIGINT)  # ends after the pass in flight, writing what it has
                    stopped = True
                continue
            if line is None:
                break
            words = line.split()
            if len(words) == 3 and words[0] == "progress":
                self._progress(int(words[1]), int(words[2]))
            elif len(words) == 2 and words[0] == "partial" and self._show(result, partial_path(image)) is None:
                self.update_result(result)
            elif len(words) == 3 and words[0] == "done":
                self.update_stats("", f"spectrace: {words[1]} samples per pixel in {float(words[2]):.2f} s")
        errors = child.stderr.read() if child.stderr is not None else ""
        if child.wait() != 0 or not image.is_file():
            lines = [line for line in errors.strip().splitlines() if line.strip()]
            return lines[-1] if lines else "the render failed"
        return None

    def _stop_asked(self) -> bool:
        """Esc pressed (Blender's test_break), asked every _POLL_SECONDS while the child renders."""
        return bool(self.test_break())

    def _progress(self, done: int, total: int) -> None:
        """A pass ended: `done` of `total` samples per pixel."""
        self.update_progress(done / max(total, 1))
        self.update_stats("", f"spectrace: {done}/{total} samples per pixel")

    def _fail(self, message: str) -> None:
        # shown in Blender's status bar, and on stderr for a render from the command line
        self.report({"ERROR"}, message)
        print(f"spectrace: {message}", file=sys.stderr)


def _panels():
    """Cycles' panels that also apply here (sampling, light and camera settings), shown for this engine too."""
    found = []
    for panel in bpy.types.Panel.__subclasses__():
        if "CYCLES" in getattr(panel, "COMPAT_ENGINES", set()):
            found.append(panel)
    return found


def register():
    bpy.utils.register_class(SpectraceRenderEngine)
    for panel in _panels():
        panel.COMPAT_ENGINES.add(SpectraceRenderEngine.bl_idname)


def unregister():
    bpy.utils.unregister_class(SpectraceRenderEngine)
    for panel in _panels():
        panel.COMPAT_ENGINES.discard(SpectraceRenderEngine.bl_idname)


def folder() -> Path:
    """Where this add-on lies: the folder to install into Blender."""
    return Path(__file__).resolve().parent
