"""Value equality for dataclasses that hold NumPy arrays. A dataclass's own `__eq__` compares its fields as a
tuple, which asks an array comparison for one truth value and raises ValueError ("The truth value of an array with
more than one element is ambiguous"); `fields_equal`, set as a class's `__eq__`, compares arrays by shape and
values instead, so that two meshes, shapes or scenes of the same content compare equal."""

from dataclasses import fields, is_dataclass
from typing import Any

import numpy as np


def values_equal(first: Any, second: Any) -> bool:
    """Whether two field values are equal: arrays by shape and elements, lists, tuples and dicts item by item,
    anything else by its own `==`."""
    if first is second:
        return True
    if isinstance(first, np.ndarray) or isinstance(second, np.ndarray):
        return (
            isinstance(first, np.ndarray)
            and isinstance(second, np.ndarray)
            and first.shape == second.shape
            and bool(np.array_equal(first, second))
        )
    if isinstance(first, list | tuple):
        return (
            type(first) is type(second)
            and len(first) == len(second)
            and all(values_equal(a, b) for a, b in zip(first, second, strict=True))
        )
    if isinstance(first, dict):
        return (
            isinstance(second, dict)
            and first.keys() == second.keys()
            and all(values_equal(value, second[key]) for key, value in first.items())
        )
    return bool(first == second)


def fields_equal(self: Any, other: object) -> bool:
    """`__eq__` for a dataclass holding arrays: the same class and every compared field equal (values_equal)."""
    if other.__class__ is not self.__class__:
        return NotImplemented
    assert is_dataclass(self)
    return all(values_equal(getattr(self, f.name), getattr(other, f.name)) for f in fields(self) if f.compare)


# The hash of a class that compares by value but was hashed by identity (held in dicts and sets keyed by the object,
# as the device tables are built): still the object's own, since hashing arrays by value would cost as much as the
# comparison. Distinct objects then never share a hash, so a dict or set still finds only the object itself.
identity_hash = object.__hash__
