"""Mitsuba variants are tried in a child process: one that aborts (Dr.Jit with an LLVM that cannot compile its
kernels) becomes a reason, and the answer is remembered. A stand-in child makes these run without Mitsuba."""

import subprocess

import pytest

from spectrace.benchmarks import mitsuba_runtime

pytestmark = pytest.mark.subprocess

ABORTS = r"""
import os, sys
print("libllvm: /opt/old/libLLVM-15.so.1", flush=True)
print("LLVM ERROR: Cannot select: 0x55d1c0de: f32 = fminimum 0x55d1c0df, 0x55d1c0e0", file=sys.stderr, flush=True)
os.abort()
"""


@pytest.fixture
def probe_env(tmp_path, monkeypatch):
    monkeypatch.setenv("SPECTRACE_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(tmp_path / "libLLVM-test.so"))
    calls = []
    real_run = subprocess.run

    def counting_run(*args, **kwargs):
        calls.append(args)
        return real_run(*args, **kwargs)

    monkeypatch.setattr(mitsuba_runtime.subprocess, "run", counting_run)
    return calls


def test_an_aborting_variant_is_a_reason_with_a_hint_and_is_cached(probe_env, monkeypatch):
    monkeypatch.setattr(mitsuba_runtime, "_PROBE_CODE", ABORTS)
    probe = mitsuba_runtime.probe_variant("llvm_ad_spectral")
    assert not probe.ok
    assert "SIGABRT" in probe.reason and "LLVM ERROR: Cannot select: f32 = fminimum" in probe.reason
    assert "0x55" not in probe.reason and "fminimum (with" in probe.reason  # addresses differ every run
    assert "/opt/old/libLLVM-15.so.1" in probe.reason and "libllvm19" in probe.reason
    assert len(probe_env) == 1
    again = mitsuba_runtime.probe_variant("llvm_ad_spectral")
    assert again == probe and len(probe_env) == 1  # the answer came from the cache, no second child


def test_another_libllvm_is_probed_again(probe_env, monkeypatch, tmp_path):
    monkeypatch.setattr(mitsuba_runtime, "_PROBE_CODE", ABORTS)
    mitsuba_runtime.probe_variant("llvm_ad_spectral")
    monkeypatch.setattr(mitsuba_runtime, "_PROBE_CODE", 'print("ok")')
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(tmp_path / "libLLVM-19.so.1"))
    assert mitsuba_runtime.probe_variant("llvm_ad_spectral").ok
    assert len(probe_env) == 2


def test_a_python_error_in_the_child_is_its_last_line(probe_env, monkeypatch):
    monkeypatch.setattr(mitsuba_runtime, "_PROBE_CODE", 'raise ImportError("libLLVM refused")')
    probe = mitsuba_runtime.probe_variant("scalar_spectral")
    assert not probe.ok and probe.reason == "loading it failed (exit status 1): ImportError: libLLVM refused"
