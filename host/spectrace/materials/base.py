"""What every material's resolved dataclass (its module's MODEL) is: the scene model's `Material`."""


class Material:
    """A material of the scene model. Each states the flags the kernels' dispatch also states, as a class attribute
    or a property: is_delta (only delta lobes), has_transmission, is_dispersive."""

    @property
    def is_delta(self) -> bool:
        raise NotImplementedError

    @property
    def has_transmission(self) -> bool:
        raise NotImplementedError

    @property
    def is_dispersive(self) -> bool:
        raise NotImplementedError
