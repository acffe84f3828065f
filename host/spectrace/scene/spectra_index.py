"""Every spectrum a scene file defines, by its key path ("materials.white.reflectance", "spectra.light",
"shapes[3].emitter.radiance", "lights[0].intensity"), resolved as the loader resolves it: for plots and listings."""

from pathlib import Path

from pydantic import BaseModel

from spectrace.scene import schema
from spectrace.scene.loader import _Resolver, read_scene_spec
from spectrace.spectral.spectrum import Spectrum

# Spectra whose field name says they are reflectances (bounded by 1, RGB uplifted as a reflectance); every other
# spectrum (radiance, intensity, irradiance, an index of refraction, ...) is read without that bound.
_REFLECTANCE_WORDS = ("reflectance", "transmittance", "albedo", "tint", "color")  # color: a checkerboard side
# A medium's coefficients (1/scene unit): unbounded, RGB made into a spectrum of that colour, not an emission.
_MEDIUM_COEFFICIENTS = ("sigma_a", "sigma_s")


def _spectrum_specs(node: object, key: str):
    """(key path, SpectrumSpec) of every spectrum inside a validated spec, in file order."""
    if isinstance(node, schema.SpectrumSpec):
        yield key, node
    elif isinstance(node, BaseModel):
        for field in type(node).model_fields:
            yield from _spectrum_specs(getattr(node, field), f"{key}.{field}" if key else field)
    elif isinstance(node, (list, tuple)):
        for index, item in enumerate(node):
            yield from _spectrum_specs(item, f"{key}[{index}]")
    elif isinstance(node, dict):
        for name, item in node.items():
            yield from _spectrum_specs(item, f"{key}.{name}" if key else str(name))


def scene_spectra(path: str | Path) -> dict[str, Spectrum]:
    """{key path: Spectrum} for the `[spectra.NAME]` entries ("spectra.NAME") and every inline spectrum of the
    scene file at `path`; errors name the file and key as the loader's do."""
    path = Path(path)
    spec = read_scene_spec(path)
    resolver = _Resolver(path, spec)
    found = {f"spectra.{name}": resolver.named_spectrum(name, f"spectra.{name}") for name in spec.spectra}
    for key, spectrum_spec in _spectrum_specs(spec, ""):
        if key.startswith("spectra."):
            continue
        field = key.rsplit(".", 1)[-1]
        if field in _MEDIUM_COEFFICIENTS:  # as written, before the interior's own `scale`
            found[key] = resolver.coefficient(spectrum_spec, key, 1.0).scaled(1.0, name=key)
            continue
        emission = not any(word in field for word in _REFLECTANCE_WORDS)
        found[key] = resolver.spectrum(spectrum_spec, key, emission=emission).scaled(1.0, name=key)
    return found
