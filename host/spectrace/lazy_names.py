"""Names a package loads on first use (PEP 562), so that importing it stays cheap; it imports nothing heavy itself."""

import importlib
import sys
from collections.abc import Callable, Mapping, Sequence


def lazy_names(
    package: str,
    where: Mapping[str, str],
    late: Callable[[], Mapping[str, str]] | None = None,
    public: Sequence[str] | None = None,
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The module-level `__getattr__` and `__dir__` of `package`, each name in `where` loading from the module named
    there on first use and then kept in the package's namespace. `late` gives more such names, those that come from
    a registry: it is asked only for a public name that `where` lacks, since answering imports the registry. With
    `public`, the package's `__all__` is those names and late's (so `import *` sees the registry's names too)."""

    def __getattr__(name: str) -> object:
        if name == "__all__" and public is not None:
            return [*public, *(late() if late is not None else ())]
        module = where.get(name)
        if module is None and late is not None and not name.startswith("_"):
            module = late().get(name)
        if module is None:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where) | set(late() if late is not None else ()))

    return __getattr__, __dir__
