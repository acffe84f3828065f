"""What the commands share: the message console (stderr) and the options several of them take."""

from typing import Annotated

import typer
from rich.console import Console

console = Console(stderr=True, soft_wrap=True, markup=False)  # messages with long paths stay on one line

DeviceOption = Annotated[
    str | None,
    typer.Option("--device", "-d", help="Device key or substring (see `spectrace devices`); env SPECTRACE_DEVICE."),
]
JsonOption = Annotated[bool, typer.Option("--json", help="One JSON object on stdout.")]
