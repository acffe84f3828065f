"""What every material's resolved dataclass (its module's MODEL) is: the scene model's `Material`."""

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Material:
    """A material of the scene model. Each states the flags the kernels' dispatch also states, as a class attribute
    or a property: is_delta (only delta lobes), has_transmission, is_dispersive. `detail`: its normal or bump map
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
