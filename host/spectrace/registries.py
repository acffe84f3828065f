"""What the plugin registries hand every kernel build: their type codes and dispatch lists (GeneratedSources),
the materials' and the lights' together, since the kernels that render sample lights and evaluate materials."""

from spectrace import lights, materials
from spectrace.core.contract import GeneratedSources


def generated_sources() -> GeneratedSources:
    """Every registry's codes and generated headers, for a build of the kernels (spectrace.device)."""
    return materials.generated_sources() | lights.generated_sources()
