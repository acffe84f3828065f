"""The examples of the README and docs/ run as a reader would run them, page by page, in a folder of their own.

A fenced block whose info string ends in ` test` (```` ```sh test ````, ```` ```python test ````,
```` ```toml test ````) is run, in the page's order, in one temporary folder that holds the repository's `scenes`
and `tests` (linked) and an empty `docs/images`:

- a TOML or pbrt block whose first line is a comment opening with a file name (`# first.toml: ...`) is written to
  that file;
- each command of a shell block (lines joined at a trailing backslash) that starts with `spectrace` runs as
  `spectrace ...` would, through the command's entry point; the commands that render at a small size (`render`'s
  `--spp`, `--width`, `--height` replaced, `display metamerism`'s `--spp`);
- a Python block runs as a script of its own (fresh globals) in which `spectrace.render` renders at that small
  size; one marked ` test continues` (a fragment that goes on from the page's examples above) runs after those
  examples' code.

A page's blocks run one after another in one interpreter of their own, started for the page: a reader's commands
are separate processes, but what a process adds to them (start-up, imports, opening the device, reading the cached
kernels: 2-4 s a command, two thirds of the pages' time) is the same for every command, and the command line's own
process behaviour (exit statuses, signals, one-line errors) has tests of its own.

A block that needs a module spectrace does not install says so after its marker (```` ```python test needs: bpy ````,
names separated by commas): where one is missing the page is skipped, naming it, and where all are present the block
runs as any other.

Every command must exit 0. A shell or Python block that cannot run here says why in its info string
(```` ```sh no-test: needs your own scene.xml ````), so that a new example is run unless its page says otherwise.

`python -m tests.tooling.docs_examples PAGE...` runs pages at their full size and copies the pictures they write
under docs/images and show into the repository's docs/images: the docs' pictures are made by the commands the
pages show.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SMALL = {"--spp": "2", "--width": "32", "--height": "20"}
SMALL_RENDER = "spp=2, width=32, height=20"
# The commands that render, by their words, and the options that make them small (`display metamerism` renders
# with --scene; its --spp is otherwise unused).
SMALL_OPTIONS = {("render",): SMALL, ("display", "metamerism"): {"--spp": "2"}}
_FENCE = re.compile(r"^\s*```(\w*)(.*)$")  # indented too: a block inside a list item
COMMAND_LANGUAGES = ("sh", "bash", "console", "python")
# A command in a block of no language: a prompt, or spectrace, Python or pip after any environment variables.
_COMMAND_LINE = re.compile(r"^\s*(\$ |(\w+=\S* )*(spectrace|python3?|pip) )", re.MULTILINE)
_IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
_FILE_COMMENT = re.compile(r"^#\s*([\w.-]+\.(?:toml|pbrt))\b")

# A Python example's renders at the small size: the scene's size and samples replaced before it renders.
# The blocks of a page share one interpreter: the first block's prelude replaces the function, the others find it.
_PYTHON_PRELUDE = """
import spectrace, spectrace.api
if not hasattr(spectrace.api.render, "small"):
    def _small_render(scene, spp=None, *args, _render=spectrace.api.render, **options):
        small = dict({small})
        scene = scene.with_overrides(width=small["width"], height=small["height"])
        return _render(scene, small["spp"], *args, **options)
    _small_render.small = True
    spectrace.render = spectrace.api.render = _small_render
"""


@dataclass(frozen=True)
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    language: str
    text: str
    tested: bool = False
    continues: bool = False  # runs after the page's tested Python blocks above it
    untested_because: str | None = None  # the reason a `no-test:` marker gives; "" when it gives none
    needs: tuple[str, ...] = ()  # modules the block imports that spectrace does not install (`test needs: bpy`)

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
        end = next((k for k in range(index + 1, len(lines)) if lines[k].lstrip().startswith("```")), len(lines))
        marker, _, needed = match[2].strip().partition(" needs:")
        tested = marker in ("test", "test continues")
        needs = tuple(name.strip() for name in needed.split(",") if name.strip())
        reason = marker.removeprefix("no-test:").strip() if marker.startswith("no-test:") else None
        if tested or not tested_only:
            text = textwrap.dedent("\n".join(lines[index + 1 : end]) + "\n")
            found.append(Block(page, index + 1, match[1], text, tested, marker == "test continues", reason, needs))
        index = end + 1
    return found


def unmarked_blocks() -> list[str]:
    """Where a shell or Python block is neither run nor says why it cannot be."""
    return [
        block.where
        for page in PAGES
        for block in blocks(page, tested_only=False)
        if not block.tested
        and not block.untested_because
        and (block.language in COMMAND_LANGUAGES or (not block.language and _COMMAND_LINE.search(block.text)))
    ]


def pictures_made(page: Path) -> set[str]:
    """The names of the pictures the page shows that its tested blocks write: a block names the picture's
    docs/images path, or that of an image the picture is written beside (`booths.exr` for `booths.deltaE00.png`)."""
    written = "\n".join(block.text for block in blocks(page))
    return {
        path.name
        for _, path in image_references(page)
        if re.search(rf"docs/images/{re.escape(path.name.split('.')[0])}\.", written)
    }


def missing_modules(page: Path) -> list[str]:
    """The modules the page's tested blocks need (`test needs: NAME`) that cannot be imported here."""
    import importlib.util

    needed = dict.fromkeys(name for block in blocks(page) for name in block.needs)
    return [name for name in needed if importlib.util.find_spec(name) is None]


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
    """A rendering command's arguments with its small options (SMALL_OPTIONS) in place of its own."""
    options = next((o for words, o in SMALL_OPTIONS.items() if arguments[1 : 1 + len(words)] == list(words)), None)
    if options is None:
        return arguments
    kept, skip = [], False
    for argument in arguments:
        if skip:
            skip = False
        elif argument in options:
            skip = True
        else:
            kept.append(argument)
    return kept + [item for pair in options.items() for item in pair]


def prepare(folder: Path) -> None:
    for name in ("scenes", "tests", "spectra"):
        (folder / name).symlink_to(ROOT / name)
    (folder / "docs" / "images").mkdir(parents=True)


# The child interpreter that runs a page's steps, in order, in the page's folder: a step is ("file", where, name,
# [name, text]), ("cli", where, shown, argv) or ("python", where, shown, code). It stops at the first that fails,
# writing why to stderr and, last, which (the line run_page puts first, however long the traceback).
_PAGE_RUNNER = """
import json, sys, traceback
steps = json.loads(sys.stdin.read())
for kind, where, shown, payload in steps:
    try:
        if kind == "file":
            name, text = payload
            with open(name, "w", encoding="utf-8") as file:
                file.write(text)
        elif kind == "cli":
            sys.argv = ["spectrace", *payload]
            from spectrace.launch import main
            try:
                main()
            except SystemExit as exit_info:
                code = exit_info.code
                if code not in (0, None):
                    raise RuntimeError(f"exit status {code}") from None
        else:
            sys.argv = ["-c"]
            exec(compile(payload, where, "exec"), {"__name__": "__main__", "__builtins__": __builtins__})
    except BaseException:
        sys.stdout.flush()
        traceback.print_exc()
        print(f"{where}: `{shown}` failed", file=sys.stderr)
        sys.exit(1)
    sys.stdout.flush()
    sys.stderr.flush()
"""


def _steps(block: Block, reduced: bool, above: str) -> list[tuple[str, str, str, object]]:
    """What one block runs, as steps for _PAGE_RUNNER (a Python block that continues after the code `above`)."""
    if block.language in ("toml", "pbrt"):
        match = _FILE_COMMENT.match(block.text)
        assert match, f"{block.where}: a tested {block.language} block opens with a comment naming its file"
        return [("file", block.where, match[1], [match[1], block.text])]
    if block.language in ("sh", "bash", "console"):
        runs = [(small(c) if reduced else c, " ".join(c)) for c in commands(block)]
        assert runs, f"{block.where}: a tested shell block holds no spectrace command"
        return [("cli", block.where, shown, arguments[1:]) for arguments, shown in runs]
    if block.language == "python":
        prelude = _PYTHON_PRELUDE.format(small=SMALL_RENDER) if reduced else ""
        code = prelude + (above if block.continues else "") + block.text
        return [("python", block.where, f"the Python block at {block.where}", code)]
    raise AssertionError(f"{block.where}: cannot run a {block.language} block")


def run_page(page: Path, folder: Path, reduced: bool = True, timeout: float = 1800) -> None:
    """Run the page's tested blocks in `folder`, in one interpreter; an AssertionError naming the block and the
    command that failed, with its error."""
    prepare(folder)
    steps: list[tuple[str, str, str, object]] = []
    python_above = ""
    for block in blocks(page):
        steps += _steps(block, reduced, python_above)
        if block.language == "python":
            python_above += block.text
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "host"), os.environ.get("PYTHONPATH", "")])}
    result = subprocess.run(
        [sys.executable, "-c", _PAGE_RUNNER],
        input=json.dumps(steps),
        cwd=folder,
        capture_output=True,
        text=True,
        env=environment,
        timeout=timeout,
    )
    failed = result.stderr.rstrip().rpartition("\n")[2]
    assert result.returncode == 0, f"{failed}:\n{result.stderr[-3000:]}"


if __name__ == "__main__":
    import tempfile

    for name in sys.argv[1:]:
        page = (ROOT / name).resolve()
        with tempfile.TemporaryDirectory() as temporary:
            run_page(page, Path(temporary), reduced=False)
            shown = {path.name for _, path in image_references(page)}
            for picture in (Path(temporary) / "docs" / "images").iterdir():
                if picture.name not in shown:  # an image the page writes but does not show (an EXR beside its map)
                    continue
                shutil.copy2(picture, ROOT / "docs" / "images" / picture.name)
                print(f"wrote docs/images/{picture.name}")
