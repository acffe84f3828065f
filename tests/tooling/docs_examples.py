"""The examples of the README and docs/ run as a reader would run them, page by page, in a folder of their own.

A fenced block whose info string ends in ` test` (```` ```sh test ````, ```` ```python test ````,
```` ```toml test ````) is run, in the page's order, in one temporary folder that holds the repository's `scenes`
and `tests` (linked) and an empty `docs/images`:

- a TOML block whose first line is a comment opening with a file name (`# first.toml: ...`) is written to that file;
- each command of a shell block (lines joined at a trailing backslash) that starts with `spectrace` runs as
  `python -m spectrace ...`; `render` commands at a small size (their `--spp`, `--width`, `--height` replaced);
- a Python block runs in a fresh interpreter in which `spectrace.render` renders at that small size.

Every command must exit 0. `python -m tests.tooling.docs_examples PAGE...` runs pages at their full size and copies
the pictures they write under docs/images into the repository's docs/images: the docs' pictures are made by the
commands the pages show.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SMALL = {"--spp": "2", "--width": "32", "--height": "20"}
SMALL_RENDER = "spp=2, width=32, height=20"
_FENCE = re.compile(r"^```(\w+)(?: (test))?\s*$")
_IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
_FILE_COMMENT = re.compile(r"^#\s*([\w.-]+\.toml)\b")

# A Python example's renders at the small size: the scene's size and samples replaced before it renders.
_PYTHON_PRELUDE = """
import spectrace, spectrace.api
_render = spectrace.api.render
def _small_render(scene, spp=None, *args, **options):
    small = dict({small})
    return _render(scene.with_overrides(width=small["width"], height=small["height"]), small["spp"], *args, **options)
spectrace.render = spectrace.api.render = _small_render
"""


@dataclass(frozen=True)
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    language: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path, tested_only: bool = True) -> list[Block]:
    """The page's fenced code blocks (only those marked ` test`, unless `tested_only` is False)."""
    found: list[Block] = []
    lines = page.read_text(encoding="utf-8").splitlines()
    index = 0
    while index < len(lines):
        match = _FENCE.match(lines[index])
        if match is None:
            index += 1
            continue
        end = next((k for k in range(index + 1, len(lines)) if lines[k].startswith("```")), len(lines))
        if match[2] or not tested_only:
            found.append(Block(page, index + 1, match[1], "\n".join(lines[index + 1 : end]) + "\n"))
        index = end + 1
    return found


def tested_pages() -> list[Path]:
    return [page for page in PAGES if blocks(page)]


def image_references(page: Path) -> list[tuple[str, Path]]:
    """(as written, the file it names) of each image the page shows from this repository."""
    text = page.read_text(encoding="utf-8")
    return [
        (target, (page.parent / target).resolve())
        for target in _IMAGE.findall(text)
        if not re.match(r"[a-z]+://", target)
    ]


def commands(block: Block) -> list[list[str]]:
    """The `spectrace` commands of a shell block, as argument lists."""
    joined = re.sub(r"\\\n\s*", " ", block.text)
    return [shlex.split(line, comments=True) for line in joined.splitlines() if line.strip().startswith("spectrace ")]


def small(arguments: list[str]) -> list[str]:
    """A render command's arguments with SMALL's options in place of its own."""
    if arguments[1:2] != ["render"]:
        return arguments
    kept, skip = [], False
    for argument in arguments:
        if skip:
            skip = False
        elif argument in SMALL:
            skip = True
        else:
            kept.append(argument)
    return kept + [item for pair in SMALL.items() for item in pair]


def prepare(folder: Path) -> None:
    for name in ("scenes", "tests", "spectra"):
        (folder / name).symlink_to(ROOT / name)
    (folder / "docs" / "images").mkdir(parents=True)


def run_block(block: Block, folder: Path, reduced: bool = True, timeout: float = 600) -> None:
    """Run one block in `folder`; an AssertionError naming the block and the command when it fails."""
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "host"), os.environ.get("PYTHONPATH", "")])}
    if block.language == "toml":
        match = _FILE_COMMENT.match(block.text)
        assert match, f"{block.where}: a tested TOML block opens with a comment naming its file (# name.toml)"
        (folder / match[1]).write_text(block.text, encoding="utf-8")
        return
    if block.language in ("sh", "bash", "console"):
        runs = [(small(c) if reduced else c, " ".join(c)) for c in commands(block)]
        assert runs, f"{block.where}: a tested shell block holds no spectrace command"
        calls = [([sys.executable, "-m", "spectrace", *arguments[1:]], shown) for arguments, shown in runs]
    elif block.language == "python":
        prelude = _PYTHON_PRELUDE.format(small=SMALL_RENDER) if reduced else ""
        calls = [([sys.executable, "-c", prelude + block.text], f"the Python block at {block.where}")]
    else:
        raise AssertionError(f"{block.where}: cannot run a {block.language} block")
    for call, shown in calls:
        result = subprocess.run(call, cwd=folder, capture_output=True, text=True, env=environment, timeout=timeout)
        assert result.returncode == 0, f"{block.where}: `{shown}` failed:\n{result.stderr[-3000:]}"


def run_page(page: Path, folder: Path, reduced: bool = True) -> None:
    prepare(folder)
    for block in blocks(page):
        run_block(block, folder, reduced)


if __name__ == "__main__":
    import tempfile

    for name in sys.argv[1:]:
        page = (ROOT / name).resolve()
        with tempfile.TemporaryDirectory() as temporary:
            run_page(page, Path(temporary), reduced=False)
            for picture in (Path(temporary) / "docs" / "images").iterdir():
                shutil.copy2(picture, ROOT / "docs" / "images" / picture.name)
                print(f"wrote docs/images/{picture.name}")
