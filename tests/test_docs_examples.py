"""The README's and docs' examples run, and the pictures they show exist (tests/tooling/docs_examples.py: the
blocks marked ` test` run page by page at a small size, in a folder of their own)."""

import pytest

from tooling.docs_examples import (
    PAGES,
    ROOT,
    blocks,
    commands,
    image_references,
    missing_modules,
    pictures_made,
    run_page,
    small,
    unmarked_blocks,
)
from tooling.docs_examples import tested_pages as pages_with_tests  # not collected as a test


def test_every_picture_the_docs_show_exists():
    missing = [
        f"{page.relative_to(ROOT)}: {target}"
        for page in PAGES
        for target, path in image_references(page)
        if not path.is_file()
    ]
    assert not missing, f"pictures the docs show but the repository lacks: {missing}"


def test_every_shell_and_python_block_runs_or_says_why_not():
    unmarked = unmarked_blocks()
    assert not unmarked, f"blocks whose fence says neither ` test` nor ` no-test: <why>`: {', '.join(unmarked)}"


def test_an_unmarked_block_is_found(tmp_path, monkeypatch):
    page = tmp_path / "page.md"
    page.write_text(
        "```sh\nspectrace devices\n```\n"
        "```\nspectrace render x.toml -o x.png\n```\n"
        "```python no-test:\nimport spectrace\n```\n"
        "```python no-test: needs your own scene.toml\nimport spectrace\n```\n"
        "```toml\n# a fragment\n```\n"
        "```\nscene.toml:3: an error message\n```\n"
        "```\nSPECTRACE_DEVICE=pocl python -m pytest\n```\n",
        encoding="utf-8",
    )
    monkeypatch.setattr("tooling.docs_examples.PAGES", [page])
    monkeypatch.setattr("tooling.docs_examples.ROOT", tmp_path)
    assert unmarked_blocks() == ["page.md:1", "page.md:4", "page.md:7", "page.md:19"]


@pytest.mark.subprocess
def test_a_fragment_marked_continues_runs_after_the_examples_above_it(tmp_path, monkeypatch):
    monkeypatch.setattr("tooling.docs_examples.ROOT", tmp_path)
    (tmp_path / "run").mkdir()
    page = tmp_path / "page.md"
    page.write_text(
        "```python test\nx = 2\n```\n```python test continues\nassert x == 2\n```\n```python test\nx\n```\n",
        encoding="utf-8",
    )
    with pytest.raises(AssertionError, match=r"(?s)page.md:7.*NameError"):
        run_page(page, tmp_path / "run", reduced=False)  # the third, not continuing, does not see x


def test_every_picture_the_docs_show_is_made_by_a_tested_block():
    made = set().union(*(pictures_made(page) for page in PAGES))
    unmade = [
        f"{page.relative_to(ROOT)}: {path.name}"
        for page in PAGES
        for _, path in image_references(page)
        if path.name not in made
    ]
    assert not unmade, f"pictures the docs show that no tested block writes: {unmade}"


def test_the_tutorial_and_the_pages_with_pictures_of_their_own_are_tested():
    names = {page.name for page in pages_with_tests()}
    tutorial_and_pictures = {"first-scene.md", "plots.md", "displays.md", "python-api.md", "sampling.md"}
    assert tutorial_and_pictures | {"gltf.md", "blender.md"} <= names


def test_a_block_names_the_modules_it_needs_and_its_page_is_skipped_without_them(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "```python test needs: json, no_such_module_anywhere\nimport json\n```\n"
        "```python test continues needs: colorsys\nprint(1)\n```\n```python test\nprint(2)\n```\n"
    )
    first, second, third = blocks(page)
    assert (first.tested, first.needs) == (True, ("json", "no_such_module_anywhere"))
    assert (second.tested, second.continues, second.needs) == (True, True, ("colorsys",))
    assert (third.tested, third.needs) == (True, ())
    assert missing_modules(page) == ["no_such_module_anywhere"]
    page.write_text("```python test needs: json\nimport json\n```\n")
    assert missing_modules(page) == []


def test_a_render_command_is_made_small_and_other_commands_kept():
    (block,) = [b for b in blocks(ROOT / "docs" / "first-scene.md") if "--white-balance" in b.text]
    (command,) = commands(block)
    assert small(command)[-6:] == ["--spp", "2", "--width", "32", "--height", "20"]
    assert "--white-balance" in small(command)
    assert small(["spectrace", "spectra", "plot", "--width"]) == ["spectrace", "spectra", "plot", "--width"]
    metamerism = ["spectrace", "display", "metamerism", "--spp", "1024", "--scene", "s.toml"]
    assert small(metamerism) == ["spectrace", "display", "metamerism", "--scene", "s.toml", "--spp", "2"]


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("page", pages_with_tests(), ids=lambda page: page.name)
def test_the_pages_examples_run(page, tmp_path):
    missing = missing_modules(page)
    if missing:
        pytest.skip(f"{page.name}'s examples need {', '.join(missing)}, not installed")
    run_page(page, tmp_path)
    written = {picture.name for picture in (tmp_path / "docs" / "images").iterdir()}
    assert pictures_made(page) <= written
