"""Command line: `spectrace render | view | devices | bench | validate | display | spectra | sweep | import-mitsuba |
import-pbrt | import-gltf | import-blend | blender-addon`, one module per command group in this package. Errors
print as one line and exit non-zero."""

import importlib
import sys
from typing import Annotated

import typer
from typer.core import TyperGroup

from spectrace.cli import bench, devices, render, validate
from spectrace.cli.common import (
    GROUP_SETTINGS,
    PlainHelpFlagCommand,
    click_exceptions,
    console,
    help_flag_defaulting_to_false,
    help_width,
    strict_number_options,
)
from spectrace.errors import SpectraceError

# Sub-commands whose modules import colour-science, SciPy or the Mitsuba importer: listed in `--help` from these
# lines and imported only when run. name -> (module, attribute: a Typer app or a command function, help line).
LAZY_COMMANDS = {
    "view": (
        "spectrace.cli.view",
        "view_command",
        "Show a scene rendering in the browser, pass by pass, with controls and a pixel's spectrum (docs/viewer.md).",
    ),
    "display": (
        "spectrace.cli.display",
        "display_app",
        "Displays as spectral emitters: the same RGB on LCD, OLED and CRT displays.",
    ),
    "spectra": (
        "spectrace.cli.spectra",
        "spectra_app",
        "Spectra: list the library's and a scene's spectra, and plot any of them.",
    ),
    "import-mitsuba": (
        "spectrace.cli.import_mitsuba",
        "import_mitsuba_command",
        "Convert a Mitsuba 3 XML scene to a spectrace TOML scene (docs/mitsuba.md).",
    ),
    "sweep": (
        "spectrace.cli.sweep",
        "sweep_command",
        "Run a grid of display computations or renders (here or on a Dask cluster) into one results table.",
    ),
    "import-pbrt": (
        "spectrace.cli.import_pbrt",
        "import_pbrt_command",
        "Convert a pbrt-v4 scene to a spectrace TOML scene (docs/pbrt.md).",
    ),
    "import-gltf": (
        "spectrace.cli.import_gltf",
        "import_gltf_command",
        "Convert a glTF 2.0 file (.gltf, .glb) to a spectrace TOML scene (docs/gltf.md).",
    ),
    "import-blend": (
        "spectrace.cli.import_blend",
        "import_blend_command",
        "Convert a Blender file (.blend, through Blender's module bpy) to a spectrace TOML scene (docs/blender.md).",
    ),
    "blender-addon": (
        "spectrace.cli.blender_addon",
        "blender_addon_command",
        "Print where spectrace's Blender render-engine add-on lies, to install into Blender (docs/blender.md).",
    ),
}


def _load_command(name: str):
    module, attribute, _ = LAZY_COMMANDS[name]
    target = getattr(importlib.import_module(module), attribute)
    if not isinstance(target, typer.Typer):
        target, function = typer.Typer(**GROUP_SETTINGS), target
        target.command(name)(function)
    return typer.main.get_command(target)


class _LazyGroup(TyperGroup):
    """The top-level group: the lazy sub-commands stand as placeholders (name and help line) until one is run."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, (_, _, help_line) in LAZY_COMMANDS.items():
            self.add_command(typer.core.TyperCommand(name, help=help_line), name)

    def get_help_option(self, ctx):
        return help_flag_defaulting_to_false(super().get_help_option(ctx))

    def resolve_command(self, ctx, args):
        name, command, rest = super().resolve_command(ctx, args)
        if name in LAZY_COMMANDS:
            command = self.commands[name] = _load_command(name)
        return name, strict_number_options(command), rest


app = typer.Typer(
    cls=_LazyGroup,
    help="spectrace: a physically based spectral path tracer (OpenCL on CPU or GPU).",
    no_args_is_help=True,
    context_settings={"max_content_width": 200},
    **GROUP_SETTINGS,
)


def _print_version(asked: bool) -> None:
    if asked:
        from spectrace import __version__

        print(f"spectrace {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_print_version, is_eager=True, help="Print the version and exit."),
    ] = False,
) -> None:
    """spectrace: a physically based spectral path tracer (OpenCL on CPU or GPU)."""


# The light command modules (typer and rich at import) register at once, in the order `--help` lists them.
app.command("render")(render.render)
app.command("devices", cls=PlainHelpFlagCommand)(devices.devices)
app.add_typer(bench.bench_app, name="bench")
app.command("validate")(validate.validate)


def _usage_error_type() -> type[Exception]:
    """Click's UsageError (bad option values, unknown options, missing arguments)."""
    return click_exceptions().UsageError


def _usage_error_line(exc: Exception) -> str:
    """One line, like every other error: the option, what is wrong with its value, and where the help is."""
    param, reason = getattr(exc, "param", None), getattr(exc, "message", "")
    cause = exc.__cause__
    if cause is not None and callable(getattr(cause, "errors", None)):  # typer's pydantic check of the value
        from spectrace.scene.validation_messages import plain_message

        reason = plain_message(cause.errors()[0])  # type: ignore[attr-defined]  # pydantic's, checked above
    if param is not None and param.opts and reason:
        message = f"{param.opts[0]}: {reason}"
    else:  # unknown options, missing arguments: click's own sentence names them
        message = exc.format_message()  # type: ignore[attr-defined]  # a click UsageError, by the caller
    message = " ".join(message.split())
    context = getattr(exc, "ctx", None)
    if context is not None:
        message += f" (see `{context.command_path} --help`)"
    return f"error: {message}"


def _memory_advice(arguments: list[str]) -> str:
    """What would need less host memory: the film, for the commands that render; the input, for the importers
    (a film size would not help an import that ran out reading its meshes)."""
    command = next((argument for argument in arguments if not argument.startswith("-")), "")
    if command.startswith("import-"):
        return "the scene's meshes, images and included files are more than this machine holds"
    return "a smaller film, --width/--height, needs less"


def main() -> None:
    try:
        usage_error = _usage_error_type()
        # Not standalone, so that a bad option value reaches the handler below instead of click's framed box.
        status = app(standalone_mode=False, terminal_width=help_width())
        sys.exit(status if isinstance(status, int) else 0)
    except KeyboardInterrupt:  # first: `usage_error` is unbound if Ctrl-C came before it was
        console.print("interrupted", highlight=False)
        sys.exit(130)
    except usage_error as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":  # a group run without a command: its help, as click would
            print(exc.format_message(), file=sys.stderr)  # type: ignore[attr-defined]  # a click UsageError
        else:
            console.print(_usage_error_line(exc), highlight=False, markup=False, soft_wrap=True)
        sys.exit(getattr(exc, "exit_code", 2))
    except typer.Abort:
        console.print("aborted", highlight=False)
        sys.exit(1)
    except SpectraceError as exc:
        console.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        sys.exit(2)
    except MemoryError:
        console.print(f"error: out of host memory ({_memory_advice(sys.argv[1:])})", highlight=False, markup=False)
        sys.exit(2)
    except Exception as exc:
        opencl = sys.modules.get("pyopencl")
        if opencl is None or not isinstance(exc, opencl.Error):
            raise
        from spectrace.engine.opencl_errors import describe_opencl_error

        console.print(
            f"error: {describe_opencl_error(exc, 'running', 'the OpenCL device')}",
            highlight=False,
            markup=False,
            soft_wrap=True,
        )
        sys.exit(2)


if __name__ == "__main__":
    main()
