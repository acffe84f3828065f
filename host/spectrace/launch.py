"""The `spectrace` command's entry point. The command line's modules take a moment to import, and Ctrl-C then
would print Python's KeyboardInterrupt traceback: it gets the same one line and exit status as Ctrl-C later on.
Only the package's `__init__` (a few lines, no imports of note) runs before this."""

import os
import sys


def main() -> None:
    try:
        if pause := os.environ.get("SPECTRACE_STARTUP_PAUSE_S"):
            # For the tests only: hold start-up here so that a signal sent now arrives while importing.
            import time

            print("start-up paused", file=sys.stderr, flush=True)
            time.sleep(float(pause))
        from spectrace.cli import main as cli_main
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr, flush=True)
        sys.exit(130)
    cli_main()
