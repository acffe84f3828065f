"""What an edit of a live session may change of a build's packing (spectrace.engine.scene_edits), kept before the
edit so that an edit failing part-way leaves the packing as it found it.

Re-packing appends spectra to the table, lets texture slots go and takes them again, rewrites the texels where a
slot is taken, and replaces the lights' power, the scene radius and the instances' placements. None of that is the
device's until the buffers are uploaded, but a later edit starts from the packing: left half-changed, it would give
a later light its pick probability from a power never uploaded, or a texture a slot it still holds. Every piece is
either replaced (kept by reference) or changed in place (a list or dict, kept as a shallow copy: the arrays in it
are never written in place, a taken slot's texels go into a new concatenated array)."""

from collections.abc import Callable

from spectrace.engine.scene_buffers import SceneBuffers


def _kept(owner: object) -> Callable[[], None]:
    """A function putting `owner`'s attributes back as they are now: each object it holds, and the items of each
    list and dict among them."""
    state = dict(vars(owner))
    items = {name: value.copy() for name, value in state.items() if isinstance(value, (list, dict))}

    def restore() -> None:
        for name in set(vars(owner)) - set(state):  # set since, as the instances' boxes are by a placement
            delattr(owner, name)
        for name, value in state.items():
            setattr(owner, name, value)
            if name in items:  # the same list or dict, which others may hold (LightRows shares texel_chunks)
                if isinstance(value, list):
                    value[:] = items[name]
                else:
                    value.clear()
                    value.update(items[name])

    return restore


def checkpoint(buffers: SceneBuffers) -> Callable[[], None]:
    """A function putting the packing of `buffers` back as it is now (nothing where they were built without it)."""
    packing = buffers.packing
    if packing is None:
        return lambda: None
    restores = [_kept(part) for part in (packing, packing.table, packing.textures, packing.objects)]

    def restore() -> None:
        for undo in restores:
            undo()

    return restore
