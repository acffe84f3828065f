"""What every material's resolved dataclass (its module's MODEL) is: the scene model's `Material`."""

from dataclasses import dataclass, field


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
