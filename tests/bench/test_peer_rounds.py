"""`spectrace bench peer`'s measurement: rounds that alternate the renderers, medians and spreads, ratios taken
round by round, and the load around the rounds with its warning. Fake contestants with given times stand for the
renderers, and the load is faked through bench_rounds.load_average, bench_rounds.others_runnable and
bench_rounds.cpu_times; speed is never asserted."""

import subprocess
import sys
import threading

import pytest

from spectrace.benchmarks import bench_rounds
from spectrace.benchmarks.bench_rounds import (
    BUSY_STEAL_SHARE,
    BUSY_WARNING,
    DEFAULT_ROUNDS,
    LoadCheck,
    PauseLoad,
    alternate_rounds,
    load_text,
    other_runnable_threads,
    paired_ratios,
    steal_share,
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


def test_a_pause_before_each_render_and_after_the_last():
    calls: list[str] = []
    ours = [FakeContestant("intel", "spectrace", [1.0] * 6, calls)]
    peers = [FakeContestant(n, "mitsuba", [1.0] * 3, calls) for n in ("llvm", "scalar")]
    alternate_rounds(ours, peers, 3, pause=lambda: calls.append("pause"))
    assert calls == ["pause", "intel", "pause", "llvm"] * 3 + ["pause", "intel", "pause", "scalar"] * 3 + ["pause"]


@pytest.mark.parametrize(
    ("loadavg", "own", "others"),
    [
        ("0.39 1.79 2.06 1/512 77", ["R", "S", "S"], 0),  # only the reading thread runs
        ("2.00 1.10 0.70 3/512 77", ["R", "R", "R", "S"], 0),  # the bench's own workers
        ("2.00 1.10 0.70 5/512 77", ["R", "R", "S"], 3),
        ("0.10 0.10 0.10 1/98 12", ["R", "R"], 0),  # a thread of ours began running after /proc/loadavg was read
    ],
)
def test_other_processes_runnable_threads_leave_out_the_bench_own(loadavg, own, others):
    assert other_runnable_threads(loadavg, own) == others


@pytest.mark.subprocess
def test_a_busy_process_beside_the_bench_is_counted_and_its_own_waiting_threads_are_not():
    """Sampled from /proc: a child process that spins is another process's runnable thread (at least one in every
    sample, whatever else the machine runs); this process's threads asleep in a wait are no one's."""
    if bench_rounds.others_runnable() is None:
        pytest.skip("no /proc/loadavg here: the bench falls back on the load average")
    assert "R" in bench_rounds._own_thread_states()  # the reading thread counts itself running
    stop = threading.Event()
    sleepers = [threading.Thread(target=stop.wait) for _ in range(4)]
    for thread in sleepers:
        thread.start()
    spin = "import time\nend = time.time() + 30\nwhile time.time() < end: pass"
    child = subprocess.Popen([sys.executable, "-c", spin])
    try:
        states = bench_rounds._own_thread_states()
        assert len(states) >= 5 and states.count("S") >= 4
        others = bench_rounds.others_runnable()
        assert others is not None and others >= 1.0
    finally:
        child.kill()
        child.wait()
        stop.set()
        for thread in sleepers:
            thread.join()


@pytest.mark.parametrize(
    ("others", "busy"), [(0.0, False), (0.4, False), (1.0, False), (1.01, True), (1.5, True), (6.0, True)]
)
def test_busy_when_other_processes_keep_more_than_half_a_thread_per_core_runnable(others, busy):
    """The bench's own threads lift the 1-minute load average (here to 1.9 after the rounds, on 2 cores): that alone
    does not make the machine busy; other processes' runnable threads between renders do."""
    pauses = PauseLoad([others] * 3)
    load = LoadCheck.of(0.2, 1.9, 2, pauses).as_dict()
    assert load["limit"] == 1.0 and load["busy"] is busy and load["pauses"] == 3
    text = load_text(load)
    assert text.startswith(BUSY_WARNING) is busy
    assert f"runnable threads {others:.2f} between renders (mean of 3 pauses), on 2 cores (quiet: at most 1.00)" in text
    assert "load average (1 min) before 0.20, after 1.90 (the bench's own threads included)" in text


@pytest.mark.parametrize(
    ("before", "after", "busy"),
    [(0.2, 0.3, False), (1.0, 1.0, False), (1.5, 0.2, True), (0.2, 1.01, True), (8.0, 12.0, True)],
)
def test_without_samples_the_load_average_decides_before_or_after(before, after, busy):
    load = LoadCheck.of(before, after, 2, PauseLoad()).as_dict()
    assert load["others"] is None and load["limit"] == 1.0 and load["busy"] is busy
    text = load_text(load)
    assert text.startswith(BUSY_WARNING) is busy
    assert f"before {before:.2f}, after {after:.2f}, on 2 cores" in text


# /proc/stat's "cpu" columns: user nice system idle iowait irq softirq steal guest guest_nice.
QUIET_START = [1000, 10, 200, 5000, 30, 0, 5, 40, 0, 0]


@pytest.mark.parametrize(
    ("delta", "share"),
    [
        ([900, 0, 50, 1000, 0, 0, 0, 50, 0, 0], 50 / 1000),  # the host took 5 % of the time the CPUs wanted
        ([900, 0, 50, 1000, 20, 0, 0, 0, 0, 0], 0.0),  # iowait is idle: not wanted time
        ([600, 0, 100, 9000, 0, 50, 50, 200, 300, 0], 200 / 1000),  # guest time is inside user: not counted twice
        ([0, 0, 0, 2000, 0, 0, 0, 0, 0, 0], None),  # nothing wanted the CPUs: no share to tell
    ],
)
def test_steal_share_is_the_hypervisors_part_of_the_time_the_cpus_wanted(delta, share):
    after = [a + d for a, d in zip(QUIET_START, delta, strict=True)]
    assert steal_share(QUIET_START, after) == (pytest.approx(share) if share is not None else None)
    assert steal_share(None, after) is None and steal_share(QUIET_START, None) is None


def test_cpu_times_reads_the_machine_s_cpu_line():
    """The real /proc/stat where there is one: at least the eight columns up to steal, whose sum goes forward while
    this test keeps a CPU busy (in clock ticks: a hundredth of a second or so)."""
    import os
    import time

    if not os.path.exists("/proc/stat"):
        assert bench_rounds.cpu_times() is None
        return
    first = bench_rounds.cpu_times()
    assert first is not None and len(first) >= 8
    deadline = time.monotonic() + 5.0
    second = bench_rounds.cpu_times()
    while second is not None and sum(second) <= sum(first) and time.monotonic() < deadline:
        second = bench_rounds.cpu_times()
    assert second is not None and len(second) == len(first) and sum(second) > sum(first)
    share = steal_share(first, second)
    assert share is None or 0.0 <= share <= 1.0


@pytest.mark.parametrize(("steal", "busy"), [(None, False), (0.0, False), (0.05, False), (0.051, True), (0.3, True)])
def test_busy_when_the_hypervisor_took_more_than_its_share(steal, busy):
    """No other process runnable here, but the host's other guests may still have had the CPUs: above
    BUSY_STEAL_SHARE of the wanted time the figures are flagged too, and the line says how much the host took."""
    assert BUSY_STEAL_SHARE == 0.05
    load = LoadCheck.of(0.1, 1.9, 2, PauseLoad([0.0] * 3), steal).as_dict()
    assert load["steal"] == steal and load["busy"] is busy
    text = load_text(load)
    assert text.startswith(BUSY_WARNING) is busy
    if steal is None:
        assert "hypervisor" not in text
    else:
        assert f"taken by the hypervisor: {100 * steal:.1f} % of the CPU time wanted (quiet: at most 5 %)" in text


def test_one_core_pins_every_thread_and_those_started_meanwhile_then_gives_the_cores_back():
    single_core = pytest.importorskip("spectrace.benchmarks.single_core")
    import os

    if not hasattr(os, "sched_setaffinity"):
        pytest.skip("this platform cannot pin threads")
    allowed = os.sched_getaffinity(0)
    stop = threading.Event()
    early = threading.Thread(target=stop.wait)
    early.start()
    seen: list[set[int]] = []
    try:
        with single_core.one_core() as core:
            assert core in allowed
            late = threading.Thread(target=lambda: seen.append(os.sched_getaffinity(0)))
            late.start()
            late.join()
            assert {frozenset(os.sched_getaffinity(t)) for t in single_core._thread_ids()} == {frozenset({core})}
            assert seen == [{core}]
        assert os.sched_getaffinity(0) == allowed and os.sched_getaffinity(early.native_id) == allowed
    finally:
        stop.set()
        early.join()


@pytest.mark.peer
@pytest.mark.parametrize("busy", [True, False])
def test_peer_bench_reports_load_rounds_and_the_busy_warning(monkeypatch, busy):
    """The real bench at 8x8 on Mitsuba's scalar variant with a faked load: the load it read, the rounds in
    alternation, and the warning in its notes and its tables when other processes kept the cores busy, none when
    only the bench's own threads lifted the load average. The quiet run is one core each: pinned meanwhile, every
    renderer's CPU time is at most its wall time."""
    pytest.importorskip("mitsuba", reason="the peer comparison needs `pip install spectrace[bench]`")
    import os

    from rich.console import Console

    from spectrace.benchmarks.peer_mitsuba import peer_tables, run_peer_bench

    loads = iter([0.1, 3.0])  # the bench's own threads lift the load average
    # Other processes' runnable threads in the pauses: mean 2.2 (busy on 4 cores), or none.
    others = iter([0.5, 2.5, 3.0, 2.0, 3.0] if busy else [0.0] * 5)
    monkeypatch.setattr(bench_rounds, "load_average", lambda: next(loads))
    monkeypatch.setattr(bench_rounds, "others_runnable", lambda: next(others))
    monkeypatch.setattr(bench_rounds, "core_count", lambda: 4)
    # Around the rounds the host took 2 % of the wanted time: below its limit, so only the runnable threads decide.
    times = iter([QUIET_START, [a + d for a, d in zip(QUIET_START, [900, 0, 80, 500, 0, 0, 0, 20, 0, 0], strict=True)]])
    monkeypatch.setattr(bench_rounds, "cpu_times", lambda: next(times))
    pin = not busy and hasattr(os, "sched_setaffinity")
    allowed = os.sched_getaffinity(0) if pin else None
    result = run_peer_bench(None, 8, 2, 2, None, False, variants=["scalar_spectral"], rounds=2, per_core=not busy)
    ours = result["spectrace"][0]["runtime"]
    assert result["load"] == {
        "before": 0.1,
        "after": 3.0,
        "cores": 4,
        "others": pytest.approx(2.2 if busy else 0.0),
        "pauses": 5,
        "limit": 2.0,
        "busy": busy,
        "steal": pytest.approx(0.02),
    }
    assert result["order"] == [f"spectrace {ours}", "mitsuba scalar_spectral"] * 2
    assert result["rounds"] == 2 and result["spectrace"][0]["rounds"] == result["mitsuba"][0]["rounds"] == 2
    assert any(note.startswith(BUSY_WARNING) for note in result["notes"]) is busy
    console = Console(width=300, record=True, markup=False)
    for table in peer_tables(result):
        console.print(table)
    text = " ".join(console.export_text().split())  # captions wrap at their table's width
    assert "2 alternated rounds: median (min-max)" in text
    assert (BUSY_WARNING in text) is busy
    assert f"other processes' runnable threads {2.2 if busy else 0.0:.2f} between renders (mean of 5 pauses)" in text
    assert "load average (1 min) before 0.10, after 3.00 (the bench's own threads included)" in text
    assert "taken by the hypervisor: 2.0 % of the CPU time wanted" in text
    for column in ("M samples/s", "wall s", "CPU s", "cores used", "wall clock", "per CPU second"):
        assert column in text
    if pin:
        assert result["core"] in allowed and f"one core each: every thread on core {result['core']}" in text
        assert os.sched_getaffinity(0) == allowed
        for row in (*result["spectrace"], *result["mitsuba"]):
            assert row["cpu_seconds"]["max"] <= row["seconds"]["max"] * 1.05 + 0.005
