"""pydantic's validation errors in spectrace's words: "expected a whole number, got 'abc'" rather than pydantic's
"Input should be a valid integer, unable to parse string as an integer". The one place that turns a pydantic error
(its `type`, `ctx` and `input`, as `ValidationError.errors()` lists them) into the message part of our one-line
errors; the caller adds the file and key path. Error types: pydantic's documentation, "Validation Errors"."""

from collections.abc import Mapping
from typing import Any


def shown(value: object) -> str:
    """A value as a scene file or a command line would spell it (true, 'text', 1.5), cut to 100 characters."""
    text = str(value).lower() if isinstance(value, bool) else repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


def _bound(error: Mapping[str, Any], word: str, key: str) -> str:
    return f"must be {word} {error.get('ctx', {}).get(key)}, got {shown(error.get('input'))}"


_EXPECTED = {
    "int_type": "a whole number",
    "int_parsing": "a whole number",
    "int_from_float": "a whole number",
    "float_type": "a number",
    "float_parsing": "a number",
    "finite_number": "a finite number",
    "bool_type": "true or false",
    "bool_parsing": "true or false",
    "string_type": "text (a quoted string)",
    "list_type": "an array",
    "tuple_type": "an array",
    "dict_type": "a table",
    "model_type": "a table",
    "model_attributes_type": "a table",
}


def plain_message(error: Mapping[str, Any]) -> str:
    """The message for one pydantic error (an item of `ValidationError.errors()`), without its location."""
    kind, context, given = error.get("type", ""), error.get("ctx", {}) or {}, error.get("input")
    if kind in _EXPECTED:
        return f"expected {_EXPECTED[kind]}, got {shown(given)}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        word, key = {
            "greater_than": (">", "gt"),
            "greater_than_equal": ("≥", "ge"),
            "less_than": ("<", "lt"),
            "less_than_equal": ("≤", "le"),
        }[kind]
        return _bound(error, word, key)
    if kind == "literal_error":
        return f"must be one of {context.get('expected', '')}, got {shown(given)}"
    if kind == "union_tag_invalid":
        return (
            f"unknown {context.get('discriminator', 'type')} {shown(context.get('tag'))}".replace("'type'", "type")
            + f" (one of {context.get('expected_tags', '')})"
        )
    if kind in ("too_short", "too_long"):
        least = context.get("min_length") if kind == "too_short" else context.get("max_length")
        word = "at least" if kind == "too_short" else "at most"
        return f"expected {word} {least} values, got {context.get('actual_length', '?')}"
    if kind == "missing":
        return "required key is missing"
    message = str(error.get("msg", "invalid value")).removeprefix("Value error, ")
    if message.startswith("Input should be "):  # a type this table lacks: pydantic's sentence, in our form
        message = "must be " + message.removeprefix("Input should be ") + f", got {shown(given)}"
    return message
