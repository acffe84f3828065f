"""The README's and docs' examples run, and the pictures they show exist (tests/tooling/docs_examples.py: the
blocks marked ` test` run page by page at a small size, in a folder of their own)."""

import pytest

from tooling.docs_examples import PAGES, ROOT, blocks, commands, image_references, run_page, small, tested_pages


def test_every_picture_the_docs_show_exists():
    missing = [
        f"{page.relative_to(ROOT)}: {target}"
        for page in PAGES
        for target, path in image_references(page)
        if not path.is_file()
    ]
    assert not missing, f"pictures the docs show but the repository lacks: {missing}"


def test_the_tutorial_and_the_pages_with_pictures_of_their_own_are_tested():
    names = {page.name for page in tested_pages()}
    assert {"first-scene.md", "plots.md", "displays.md", "python-api.md", "sampling.md"} <= names


def test_a_render_command_is_made_small_and_other_commands_kept():
    (block,) = [b for b in blocks(ROOT / "docs" / "first-scene.md") if "--white-balance" in b.text]
    (command,) = commands(block)
    assert small(command)[-6:] == ["--spp", "2", "--width", "32", "--height", "20"]
    assert "--white-balance" in small(command)
    assert small(["spectrace", "spectra", "plot", "--width"]) == ["spectrace", "spectra", "plot", "--width"]


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("page", tested_pages(), ids=lambda page: page.name)
def test_the_pages_examples_run(page, tmp_path):
    run_page(page, tmp_path)
    written = {picture.name for picture in (tmp_path / "docs" / "images").iterdir()}
    shown = {path.name for _, path in image_references(page)}
    assert written <= shown | {p.name for p in (ROOT / "docs" / "images").iterdir()}
