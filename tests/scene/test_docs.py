"""The documentation keeps up with the code: every key of the scene format is in docs/scene-format.md, and the
README's gallery pictures exist."""

import re
import typing
from pathlib import Path

from pydantic import BaseModel

from spectrace.scene import schema

ROOT = Path(__file__).resolve().parents[2]


def _scene_keys(model: type[BaseModel], seen: set) -> typing.Iterator[tuple[str, str]]:
    if model in seen:
        return
    seen.add(model)
    for name, field in model.model_fields.items():
        yield model.__name__, name
        pending = [field.annotation]
        while pending:
            annotation = pending.pop()
            if isinstance(annotation, type) and issubclass(annotation, BaseModel):
                yield from _scene_keys(annotation, seen)
            pending.extend(typing.get_args(annotation))


def test_every_scene_key_is_documented():
    text = (ROOT / "docs" / "scene-format.md").read_text(encoding="utf-8")
    missing = [
        f"{model}.{key}"
        for model, key in _scene_keys(schema.SceneSpec, set())
        if not any(form in text for form in (f"`{key}`", f"{key} =", f"[{key}", f"[[{key}"))
    ]
    assert not missing, f"keys missing from docs/scene-format.md: {missing}"


def test_readme_pictures_exist():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", readme)
    assert pictures, "the README shows no pictures"
    for picture in pictures:
        path = ROOT / picture
        assert path.is_file(), picture
        assert path.stat().st_size < 400_000, f"{picture} is large for the repository"
