"""A skeleton of spectrace as a Blender render engine: install this folder as an add-on (Edit > Preferences >
Add-ons, or copy it into Blender's scripts/addons; `spectrace blender-addon` prints where it is) in a Blender whose
Python can import spectrace. Rendering exports the evaluated scene through spectrace.interop.blender (the same
import as `spectrace import-blend`), renders it with `python -m spectrace render` at the scene's Cycles sample count
and loads the image into Blender's render result. Progress within the render and viewport rendering are not
implemented yet."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import bpy  # type: ignore[import-not-found, import-untyped, unused-ignore]  # Blender's, untyped; absent outside it

bl_info = {
    "name": "spectrace",
    "author": "spectrace",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "category": "Render",
    "description": "Render with spectrace, a spectral path tracer (a skeleton: final renders only)",
}


class SpectraceRenderEngine(bpy.types.RenderEngine):
    bl_idname = "SPECTRACE"
    bl_label = "spectrace"
    bl_use_preview = False

    def render(self, depsgraph):
        from spectrace.errors import SpectraceError
        from spectrace.interop.blender.importer import write_blend_import

        scene = depsgraph.scene
        width = int(scene.render.resolution_x * scene.render.resolution_percentage / 100)
        height = int(scene.render.resolution_y * scene.render.resolution_percentage / 100)
        spp = int(getattr(getattr(scene, "cycles", None), "samples", 16))
        with tempfile.TemporaryDirectory(prefix="spectrace-blender-") as folder:
            toml, image = Path(folder) / "scene.toml", Path(folder) / "image.exr"
            blend = Path(bpy.data.filepath or "untitled.blend")
            try:
                write_blend_import(bpy, scene, blend, toml, strict=False, option="the exported scene")
            except SpectraceError as error:
                self._fail(str(error))
                return
            self.update_stats("", "spectrace: rendering")
            done = subprocess.run(
                [sys.executable, "-m", "spectrace", "render", str(toml), "-o", str(image), "--spp", str(spp)],
                capture_output=True,
                text=True,
            )
            if done.returncode != 0:
                self._fail(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "the render failed")
                return
            import numpy as np

            from spectrace.io.exr import read_exr

            rgb = read_exr(image)[0]["RGB"][::-1, :, :3]  # Blender's rows run bottom-up
            rgba = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,), dtype=rgb.dtype)], axis=2)
            result = self.begin_result(0, 0, width, height)
            result.layers[0].passes["Combined"].rect = rgba.reshape(-1, 4).astype(np.float32)
            self.end_result(result)

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
