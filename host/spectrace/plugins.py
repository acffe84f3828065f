"""What the plugin registries hand every kernel build (spectrace.core.contract.GeneratedSources): each kind's type
codes, generated from its registry's order, and the dispatch lists generated from them (material_list.h,
light_list.h). The device layer reads no registry: whoever builds a program hands it `generated_sources()`."""

from spectrace import cameras, lights, materials, pixel_filters, textures
from spectrace.core.contract import GeneratedSources


def generated_sources() -> GeneratedSources:
    """The codes and headers of every registry (materials, lights, textures, cameras, pixel filters) together."""
    defines: dict[str, int] = {}
    headers: dict[str, str] = {}
    for part in (
        materials.generated_sources(),
        lights.generated_sources(),
        textures.generated_sources(),
        cameras.generated_sources(),
        pixel_filters.generated_sources(),
    ):
        if clash := (set(defines) & set(part.defines)) | (set(headers) & set(part.headers)):
            raise AssertionError(f"two registries generate {sorted(clash)}")
        defines |= part.defines
        headers |= part.headers
    return GeneratedSources(defines, headers)
