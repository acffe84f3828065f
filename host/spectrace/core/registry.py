"""One registry shape for every kind of plugin (material, light, texture, camera, pixel filter, integrator).

A plugin is a module (or an object) that states its NAME and its properties, as Mitsuba 3's plugins open with their
parameters and pbrt-v4's BxDFs state their flags. A kind declares what its plugins hold with a `typing.Protocol`,
which mypy checks each registered module against, and lists them in a `Registry`: the one list from which the
scene schema, the API's constructors, the importers, the docs and the device codes are read. A plugin's position
in its registry is its device code (`codes`, `kernel_defines`), so the kernels' type constants and dispatch lists
are generated, never written twice.
"""

from collections.abc import Iterable, Iterator, Mapping
from typing import Generic, Protocol, TypeVar

from spectrace.core.parameters import Parameter
from spectrace.errors import SpectraceError


class Plugin(Protocol):
    """What every plugin states: the name the scene file, the API and the docs call it by."""

    @property
    def NAME(self) -> str: ...  # noqa: N802 (a module constant)


class TabledPlugin(Plugin, Protocol):
    """A plugin that opens with its parameter table, from which the scene schema, the API and the docs read its
    keys (spectrace.core.parameters)."""

    @property
    def PARAMETERS(self) -> tuple[Parameter, ...]: ...  # noqa: N802 (a module constant)


P = TypeVar("P", bound=Plugin, covariant=True)


class Registry(Mapping[str, P], Generic[P]):
    """The plugins of one `kind` by NAME, in the order given: that order is each plugin's device code and the order
    in which the schema and the docs list them."""

    def __init__(self, kind: str, plugins: Iterable[P]) -> None:
        self.kind = kind
        self._plugins: dict[str, P] = {}
        for plugin in plugins:
            if plugin.NAME in self._plugins:
                raise ValueError(f"two {kind} plugins are named {plugin.NAME!r}")
            self._plugins[plugin.NAME] = plugin

    def __getitem__(self, name: str) -> P:
        return self._plugins[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._plugins)

    def __len__(self) -> int:
        return len(self._plugins)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._plugins)})"

    def named(self, name: str, where: str = "") -> P:
        """The plugin called `name`; an unknown name is an error naming `where` (a file and key path) and the
        names there are."""
        try:
            return self._plugins[name]
        except KeyError:
            prefix = f"{where}: " if where else ""
            raise SpectraceError(f"{prefix}unknown {self.kind} {name!r} (one of {', '.join(self._plugins)})") from None

    @property
    def codes(self) -> dict[str, int]:
        """Each plugin's device code: its position."""
        return {name: code for code, name in enumerate(self._plugins)}

    def kernel_defines(self, prefix: str) -> dict[str, int]:
        """`<PREFIX>_<NAME>` for each plugin's code and `<PREFIX>_TYPE_COUNT`, the constants a kernel build is
        handed so that the kernels' switch cases and the host's rows agree."""
        defines = {f"{prefix}_{name.upper()}": code for name, code in self.codes.items()}
        return defines | {f"{prefix}_TYPE_COUNT": len(self._plugins)}

    def for_model(self, value: object) -> P:
        """The plugin whose MODEL (its resolved dataclass) is `value`'s type; another type is an unsupported kind."""
        for plugin in self._plugins.values():
            if getattr(plugin, "MODEL", None) is type(value):
                return plugin
        raise SpectraceError(f"unsupported {self.kind} {type(value).__name__}")
