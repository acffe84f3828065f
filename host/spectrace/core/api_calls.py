"""Which Python API constructor made an object of the scene model, and with which arguments.

A scene built in Python holds resolved objects (a DiffuseMaterial's spectrum, not the `0.5` it was given), which
cannot be edited by a parameter's name. The API's constructors (`spectrace.diffuse`, `spectrace.point_light`,
`spectrace.bitmap`, `spectrace.medium`, `spectrace.area_emitter`, ...) therefore remember each object's call, so
that a live session can list an object's parameters as they were given and make the object again, through the same
constructor and so with the same checks, with one argument changed (spectrace.session.python_scene). The record
lasts as long as the object; an object made any other way (a module's own `make`, `dataclasses.replace`) has none.
"""

from __future__ import annotations

import functools
import inspect
import sys
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar, cast

F = TypeVar("F", bound=Callable[..., Any])


@dataclass(frozen=True)
class Call:
    """One constructor call: the constructor (as the API names it), its signature and every argument by name (the
    defaults filled in)."""

    constructor: Callable[..., Any]
    signature: inspect.Signature
    arguments: dict[str, Any]

    def again(self, arguments: dict[str, Any]) -> Any:
        """The object made by the same constructor from `arguments`, itself recorded."""
        bound = self.signature.bind_partial()
        bound.arguments.update(arguments)
        made = self.constructor(*bound.args, **bound.kwargs)
        remember(made, Call(self.constructor, self.signature, dict(arguments)))
        return made

    def aliases(self) -> dict[str, str]:
        """The scene file's name of each argument whose API name differs (a point light's `power` is `power_w`)."""
        module = sys.modules.get(getattr(self.constructor, "__module__", ""), None)
        parameters = getattr(module, "PARAMETERS", ())
        return {p.name: p.api_name for p in parameters if getattr(p, "api_name", None) in self.arguments}


# id(object) -> its call; a finalizer drops the entry when the object goes, before its id can be reused.
_CALLS: dict[int, Call] = {}


def remember(made: object, call: Call) -> None:
    key = id(made)
    if key not in _CALLS:
        try:
            weakref.finalize(made, _CALLS.pop, key, None)
        except TypeError:  # not weakly referable: it stays without a record
            return
    _CALLS[key] = call


def call_of(made: object) -> Call | None:
    """The call that made `made`, or None where no API constructor did."""
    return _CALLS.get(id(made))


def recorded(constructor: F) -> F:
    """`constructor` remembering each object it makes with its arguments (same signature, same documentation)."""
    signature = inspect.signature(constructor)

    @functools.wraps(constructor)
    def make(*args: Any, **kwargs: Any) -> Any:
        made = constructor(*args, **kwargs)
        bound = signature.bind(*args, **kwargs)  # the constructor took them: they bind
        bound.apply_defaults()
        remember(made, Call(constructor, signature, dict(bound.arguments)))
        return made

    return cast("F", make)
