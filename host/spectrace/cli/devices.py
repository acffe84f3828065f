"""`spectrace devices`: the OpenCL platforms and devices found, and whether each builds the kernels."""

import json

from spectrace.cli.common import JsonOption


def devices(as_json: JsonOption = False) -> None:
    """List every OpenCL platform and device found, with the build probe's result or why it failed."""
    from dataclasses import asdict

    from spectrace.device import device_table, discover_devices

    reports = discover_devices()
    if as_json:
        print(json.dumps({"devices": [asdict(r) for r in reports]}, indent=2))
        return
    import sys

    print(device_table(reports, colour=sys.stdout.isatty()))
    if not any(r.ok for r in reports):
        from spectrace.device import NoWorkingDeviceError

        raise NoWorkingDeviceError(reports)
