"""`spectrace bench peer`'s measurement: rounds that alternate the renderers, medians and spreads, ratios taken
round by round, and the load average around the rounds with its warning. Fake contestants with given times stand
for the renderers, and the load is faked through bench_rounds.load_average; speed is never asserted."""

import pytest

from spectrace.benchmarks import bench_rounds
from spectrace.benchmarks.bench_rounds import (
    BUSY_WARNING,
    DEFAULT_ROUNDS,
    LoadCheck,
    alternate_rounds,
    load_text,
    paired_ratios,
    timing_summary,
)


class FakeContestant:
    def __init__(self, name: str, renderer: str, seconds: list[float], calls: list[str]):
        self.name, self.renderer = name, renderer
        self.seconds, self.calls = list(seconds), calls

    def render_timed(self) -> tuple[float, float]:
        self.calls.append(self.name)
        seconds = self.seconds.pop(0)
        return seconds, 2 * seconds  # two cores busy


def test_rounds_alternate_ours_and_each_peer_in_its_own_block():
    calls: list[str] = []
    ours = [FakeContestant(n, "spectrace", [1.0] * 10, calls) for n in ("intel", "pocl")]
    peers = [FakeContestant(n, "mitsuba", [1.0] * 5, calls) for n in ("llvm", "scalar")]
    blocks: list[str] = []
    timings = alternate_rounds(ours, peers, DEFAULT_ROUNDS, before_block=lambda peer: blocks.append(peer.name))
    assert DEFAULT_ROUNDS >= 5
    assert blocks == ["llvm", "scalar"]
    assert calls == ["intel", "pocl", "llvm"] * 5 + ["intel", "pocl", "scalar"] * 5
    assert [(t.block, t.round) for t in timings[:3]] == [("llvm", 1)] * 3
    assert [(t.block, t.round) for t in timings[-3:]] == [("scalar", 5)] * 3


def test_rounds_without_a_peer_time_ours_alone():
    calls: list[str] = []
    timings = alternate_rounds([FakeContestant("intel", "spectrace", [1.0] * 3, calls)], [], 3)
    assert calls == ["intel"] * 3 and {t.block for t in timings} == {""}


def test_medians_spreads_and_round_by_round_ratios():
    calls: list[str] = []
    # Round by round our render takes half the peer's, whatever the machine did meanwhile: the ratio is 2 each
    # round (equal samples), although the medians of the two series alone would give 3.0 / 1.2 = 2.5.
    ours = FakeContestant("intel", "spectrace", [1.0, 1.2, 4.0, 1.1, 0.5], calls)
    peer = FakeContestant("llvm", "mitsuba", [2.0, 2.4, 8.0, 2.2, 1.0], calls)
    timings = alternate_rounds([ours], [peer], 5)
    summary = timing_summary(timings, "intel", samples=1000)
    assert summary["rounds"] == 5
    assert summary["seconds"]["median"] == 1.1 and summary["seconds"]["min"] == 0.5 and summary["seconds"]["max"] == 4.0
    assert summary["seconds"]["relative_spread"] == pytest.approx((4.0 - 0.5) / 1.1)
    assert summary["samples_per_second"] == pytest.approx(1000 / 1.1)
    assert summary["cores_used"] == pytest.approx(2.0)
    ratio = paired_ratios(timings, "intel", 1000, "llvm", 1000)
    assert ratio["ratio"]["median"] == pytest.approx(2.0) and ratio["ratio"]["max"] == pytest.approx(2.0)
    assert ratio["cpu_time_ratio"]["median"] == pytest.approx(2.0)
    # A peer that rendered more samples per pixel (a sampler rounding its count) is credited for them.
    assert paired_ratios(timings, "intel", 1000, "llvm", 1500)["ratio"]["median"] == pytest.approx(2.0 / 1.5)


@pytest.mark.parametrize(
    ("before", "after", "busy"),
    [(0.2, 0.3, False), (1.0, 1.0, False), (1.5, 0.2, True), (0.2, 1.01, True), (8.0, 12.0, True)],
)
def test_busy_when_the_load_exceeds_half_a_thread_per_core_before_or_after(before, after, busy):
    load = LoadCheck(before, after, cores=2).as_dict()
    assert load["limit"] == 1.0 and load["busy"] is busy
    text = load_text(load)
    assert text.startswith(BUSY_WARNING) is busy
    assert f"before {before:.2f}, after {after:.2f}, on 2 cores" in text


@pytest.mark.peer
def test_peer_bench_reports_load_rounds_and_the_busy_warning(monkeypatch):
    """The real bench at 8x8 on Mitsuba's scalar variant with a faked load: the load it read before and after, the
    rounds in alternation, and the warning in its notes and its tables."""
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    from rich.console import Console

    from spectrace.benchmarks.peer_mitsuba import peer_tables, run_peer_bench

    loads = iter([3.0, 0.1])
    monkeypatch.setattr(bench_rounds, "load_average", lambda: next(loads))
    monkeypatch.setattr(bench_rounds, "core_count", lambda: 4)
    result = run_peer_bench(None, 8, 2, 2, None, False, variants=["scalar_spectral"], rounds=2)
    ours = result["spectrace"][0]["runtime"]
    assert result["load"] == {"before": 3.0, "after": 0.1, "cores": 4, "limit": 2.0, "busy": True}
    assert result["order"] == [f"spectrace {ours}", "mitsuba scalar_spectral"] * 2
    assert result["rounds"] == 2 and result["spectrace"][0]["rounds"] == result["mitsuba"][0]["rounds"] == 2
    assert any(note.startswith(BUSY_WARNING) for note in result["notes"])
    console = Console(width=200, record=True, markup=False)
    for table in peer_tables(result):
        console.print(table)
    text = console.export_text()
    assert "2 alternated rounds: median (min-max)" in text
    assert f"{BUSY_WARNING}: load average (1 min) before 3.00, after 0.10, on 4 cores" in text
    for column in ("M samples/s", "wall s", "CPU s", "cores used", "wall clock", "per CPU second"):
        assert column in text
