"""What a texture plugin is: the shape of a texture's module (`TexturePlugin`), which mypy checks every module of
spectrace.textures.TEXTURES against."""

from typing import Any, Protocol

from spectrace.core.registry import TabledPlugin


class TexturePlugin(TabledPlugin, Protocol):
    """What a texture's module holds. Beside these, where they apply: `device_texels` (an image texture's texels for
    one use), `from_mitsuba` or MITSUBA_NONE (why Mitsuba 3 has no such texture), `to_mitsuba`, and
    `from_pbrt(context, texture, uv)` for the pbrt-v4 textures of PBRT_TEXTURES or PBRT_NONE (why none maps here)."""

    @property
    def MODEL(self) -> type[Any]: ...  # noqa: N802

    @property
    def COMPOSITE(self) -> bool:  # noqa: N802
        """Made of other textures (sides, operands) rather than of texels: its operands are spectra and image
        textures only, as the kernel does not recurse."""
        ...

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    @property
    def PBRT_TEXTURES(self) -> tuple[str, ...]: ...  # noqa: N802

    @property
    def API_NAME(self) -> str:  # noqa: N802
        """The name of `make` in the Python API, `spectrace.<API_NAME>`."""
        ...

    def from_spec(self, spec: Any, resolver: Any, key: str) -> Any:
        """The dataclass of a validated scene-file table at `key`, its operands resolved by `resolver`."""
        ...

    def make(self, *args: Any, **kwargs: Any) -> Any:
        """The Python API's constructor, which takes any value the API takes (a spectrum in any form, an RGB
        triple) and checks it."""
        ...
