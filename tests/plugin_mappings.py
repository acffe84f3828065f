"""What a plugin module states about its mapping from another renderer: the names it imports, with the function
that maps them, or, with none, a sentence saying why (the Mitsuba 3 and pbrt-v4 mappings of the material and light
modules)."""


def assert_declares_mapping(module, names: str, function: str, none: str) -> None:
    """`module.<names>` is a tuple of names; with any, `module.<function>` maps them and there is no `<none>`; with
    none, `module.<none>` says why and there is no `<function>`."""
    declared = getattr(module, names)
    assert isinstance(declared, tuple) and all(isinstance(name, str) and name for name in declared), declared
    if declared:
        assert callable(getattr(module, function, None)), f"{module.NAME} declares {names} but no {function}"
        assert not hasattr(module, none)
    else:
        reason = getattr(module, none, None)
        assert isinstance(reason, str) and reason.strip(), (
            f"{module.NAME}: {names} is empty and {none} does not say why"
        )
        assert not hasattr(module, function)
