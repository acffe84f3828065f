"""`spectrace blender-addon`: where the Blender add-on lies (a folder to install into Blender)."""

from importlib.util import find_spec
from pathlib import Path


def blender_addon_command() -> None:
    """Print the folder of spectrace's Blender render-engine add-on (final renders, their progress and image shown in
    Blender), to install into a Blender whose Python imports spectrace (docs/blender.md)."""
    spec = find_spec("spectrace.interop.blender")
    assert spec is not None and spec.origin is not None
    print(Path(spec.origin).resolve().parent / "addon")
