"""Numbers written as text: command-line values, the numbers inside an option's string (`--filter
gaussian:stddev=0.5`, `--white-balance 3200K`) and those of spectrum files and strings.

ASCII digits, an optional sign, a point and an exponent; nothing else. Python's int() and float(), and pydantic's
lax parsing of text, accept more that nobody typing a number means: '0_2' is 2 (a digit separator), '16.0' is an
integer to pydantic, other scripts' digits ('５') are digits to them, and 'nan' and 'inf' are floats. None of the
numbers read this way has a meaning for NaN or infinity, so both are refused with the reason.
"""

import math
import re

DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
INTEGER = re.compile(r"[+-]?[0-9]+")
NOT_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


def _underscore_hint(text: str, pattern: re.Pattern) -> str:
    return " ('_' is not a digit separator here)" if "_" in text and pattern.fullmatch(text.replace("_", "")) else ""


def integer_problem(text: str) -> str | None:
    """Why `text` is not a whole number, as a phrase to follow the option or key it was given to; or None."""
    text = text.strip()
    if INTEGER.fullmatch(text):
        return None
    return f"must be a whole number, got {text!r}{_underscore_hint(text, INTEGER)}"


def number_problem(text: str) -> str | None:
    """Why `text` is not a finite number, as a phrase to follow the option or key it was given to; or None."""
    text = text.strip()
    if NOT_FINITE.fullmatch(text):
        return f"must be a finite number, got {text}"
    if not DECIMAL.fullmatch(text):
        return f"must be a number, got {text!r}{_underscore_hint(text, DECIMAL)}"
    if not math.isfinite(float(text)):  # e.g. 1e999
        return f"must be a finite number, got {text} (beyond the range of a float)"
    return None
