"""What a material plugin is: the module's shape (`MaterialPlugin`, which mypy checks every module of the registry
against) and its resolved dataclass (the module's MODEL), the scene model's `Material`."""

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from spectrace.core.registry import TabledPlugin
from spectrace.spectral.table import SpectrumTable


@dataclass(frozen=True)
class Material:
    """A material of the scene model. Each states the flags the kernels' dispatch also states, as a class attribute
    or a property: is_delta (only delta lobes), has_transmission, is_dispersive; and is_diffuse (only Lambertian
    lobes, so no caustic hides behind it), which the host alone asks. `detail`: its normal or bump map
    and opacity (spectrace.materials.surface; None: none), a keyword every material's dataclass takes last."""

    detail: object = field(default=None, kw_only=True)

    @property
    def is_delta(self) -> bool:
        raise NotImplementedError

    @property
    def has_transmission(self) -> bool:
        raise NotImplementedError

    @property
    def is_dispersive(self) -> bool:
        raise NotImplementedError

    @property
    def is_diffuse(self) -> bool:
        # False unless a material says so: a glossy or delta lobe that goes unstated would only cost BDPT speed
        # (spectrace.integrators.bdpt.pixels_per_light_path), while a wrong True would cost its caustics.
        return False


class MaterialPlugin(TabledPlugin, Protocol):
    """What a material's module holds (spectrace.materials.MATERIALS lists them). Beside these, where they apply:
    SPEC_CHECKS (rules spanning several keys, for the scene schema), `from_mitsuba` or MITSUBA_NONE (why Mitsuba 3
    has no such BSDF), `to_mitsuba`, and for a composite (no BSDF of its own) COMPOSITE and its KERNEL_FILE."""

    # A Material subclass (tests/materials check it), typed loosely because a subclass states a flag such as
    # has_transmission either as a class attribute or as a property.
    @property
    def MODEL(self) -> type[Any]: ...  # noqa: N802

    @property
    def MITSUBA_PLUGINS(self) -> tuple[str, ...]: ...  # noqa: N802

    def from_spec(self, spec: Any, resolver: Any, key: str) -> Material:
        """The dataclass of a validated scene-file table at `key`, its spectra and textures resolved by `resolver`."""
        ...

    def make(self, *args: Any, **kwargs: Any) -> Material:
        """The Python API's constructor, `spectrace.<NAME>`."""
        ...

    def write_row(self, row: np.ndarray, material: Any, table: SpectrumTable) -> None:
        """Its fields of a Material row (kernels/types.h) but the type code, its spectra added to `table`."""
        ...
