"""Every working OpenCL runtime renders the same scene alike: the suite runs on one runtime, and a compiler fault
on another (Intel's CPU vectoriser once wrote BSDF pdf values to the wrong work-items in a test kernel) would pass
unseen there. Each other runtime's image is compared with the suite device's by independent replicas (different
seeds, so the two renders' noise is independent), block means and the whole image within 5 standard errors."""

import numpy as np
import pytest

from replica_agreement import assert_replicas_agree, spectrace_replicas
from spectrace.device import discover_devices, open_device
from spectrace.engine.renderer import Renderer
from spectrace.resources import scenes_dir
from spectrace.scene import load_scene

SIZE, BLOCK = 24, 8
REPLICAS, REPLICA_SPP = 8, 32


def _other_runtimes(device) -> list[str]:
    """Keys of the working devices of runtimes other than the suite's (one device each)."""
    ours = device.report.key.split(":")[0]
    keys: dict[str, str] = {}
    for report in discover_devices():
        runtime = report.key.split(":")[0]
        if report.ok and runtime != ours and runtime not in keys:
            keys[runtime] = report.key
    return list(keys.values())


@pytest.mark.slow
@pytest.mark.parametrize("scene_name", ["cornell_box", "teapot", "material_showcase"])
def test_other_runtimes_render_the_suite_devices_image(device, scene_name):
    others = _other_runtimes(device)
    if not others:
        pytest.skip(f"only one OpenCL runtime works here ({device.report.key}): nothing to compare it with")
    scene = load_scene(scenes_dir() / f"{scene_name}.toml").with_overrides(width=SIZE, height=SIZE, max_depth=5)
    ours = spectrace_replicas(Renderer(scene, device), REPLICAS, REPLICA_SPP)
    assert ours[..., 1].mean() > 1e-3  # a lit image
    for key in others:
        theirs = spectrace_replicas(Renderer(scene.with_overrides(seed=1), open_device(key)), REPLICAS, REPLICA_SPP)
        assert np.all(np.isfinite(theirs)), key
        assert_replicas_agree(theirs, ours, BLOCK)
