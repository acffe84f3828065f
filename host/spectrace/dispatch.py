"""From a resolved scene object to the module that holds its host side (one module per light or material)."""

from collections.abc import Callable, Iterable
from typing import Any

from spectrace.errors import SpectraceError


def module_by_model(modules: Iterable[Any], kind: str) -> Callable[[object], Any]:
    """A function giving the module whose MODEL is an object's type, for `modules` each holding a MODEL; an object
    of no such type is an unsupported `kind`."""
    by_model = {module.MODEL: module for module in modules}

    def module_of(value: object) -> Any:
        module = by_model.get(type(value))
        if module is None:
            raise SpectraceError(f"unsupported {kind} {type(value).__name__}")
        return module

    return module_of
