"""The docs' tables of keys and the README's lists of names are what the registries give: every generated block,
written again in memory, is the text on the page. A plugin added, renamed or removed, or a key changed, without
`python -m tests.tooling.docs_tables` run afterwards fails here."""

import pytest

from tooling.docs_tables import COMMAND, END, _kinds, blocks, regenerate, stale


def test_the_generated_blocks_are_what_the_registries_give():
    problems = stale()
    assert not problems, f"the docs differ from the registries ({'; '.join(problems)}): run `{COMMAND}`"


def test_a_block_is_rewritten_and_text_around_it_kept():
    text = f"before\n<!-- generated: names -->\nold | text\n{END}\nafter <!-- generated: names -->\n\n{END}\n"
    fresh = regenerate(text, {"names": lambda: "| new |"})
    block = f"<!-- generated: names -->\n| new |\n{END}\n"
    assert fresh == f"before\n{block}after {block}"


def test_an_unknown_block_is_an_error_naming_it():
    with pytest.raises(ValueError, match="'nonsense'"):
        regenerate(f"<!-- generated: nonsense -->\n{END}\n", blocks(), "page.md")


@pytest.mark.parametrize("kind", ["materials", "lights", "textures", "cameras", "pixel filters", "integrators"])
def test_every_plugin_and_every_key_of_a_kind_is_in_the_generated_text(kind):
    """So a kind whose blocks left a plugin out, or a registry the generator no longer reads, fails too."""
    text = "\n".join(make() for make in blocks().values())
    for name, plugin in _kinds()[kind].items():
        assert f"`{name}`" in text or f'`"{name}"`' in text, name
        for parameter in plugin.PARAMETERS:
            assert f"| `{parameter.name}` | {parameter.doc_type()} |" in text.replace("\\|", "|"), (name, parameter)
