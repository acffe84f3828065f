"""Timed rounds that alternate renderers, their medians and spreads, and the machine's load around them.

A ratio of two renderers' speeds holds only when both ran under the same conditions. The rounds alternate
(each of ours, then the peer, then each of ours again, ...), so a load that comes and goes falls on both alike,
and every ratio is taken round by round (our render ÷ the peer's render of the same round), its median reported
with the smallest and largest.

Whether other work competed for the cores is judged in the pauses before each render and after the last: the
threads the kernel counts runnable at that moment (/proc/loadavg's fourth field) less this process's own threads
in state R, a few samples each pause. The 1-minute load average cannot judge it: it trails the bench's own threads
for a minute (two busy threads for the 30 s of a bench lift it by about 0.8), so read after the rounds it called an
idle two-core machine busy. It is still read before the bench's first build and after its last render, and
printed; above half a runnable thread of other processes per core the figures say "machine busy".

In a virtual machine the host's other guests can slow both renderers without a runnable thread to show for it
here. Where the host reports it (/proc/stat's steal column), the share of the time the machine's CPUs wanted to run
during the rounds that the host gave to others is read too; above BUSY_STEAL_SHARE the figures say "machine busy"
as well. Neighbours that share the caches and memory without taking CPU time stay unseen.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Protocol

DEFAULT_ROUNDS = 5
BUSY_LOAD_PER_CORE = 0.5
BUSY_WARNING = "machine busy: ratio not reliable"
PAUSE_SAMPLES = 5  # samples of the runnable threads per pause, PAUSE_SAMPLE_SECONDS apart
PAUSE_SAMPLE_SECONDS = 0.01
# Above this share of the CPUs' wanted time taken by the hypervisor, a ratio's two sides may have run on different
# machines in effect: a share that comes and goes falls unevenly on alternated rounds.
BUSY_STEAL_SHARE = 0.05
_STEAL_FIELD = 7  # /proc/stat's "cpu" line: user nice system idle iowait irq softirq steal guest guest_nice
_IDLE_FIELDS = (3, 4)


def load_average() -> float:
    """The 1-minute load average (runnable threads, averaged); a seam the tests replace."""
    return os.getloadavg()[0]


def core_count() -> int:
    """The cores of the machine, which the load average is counted over (not this process's affinity)."""
    return os.cpu_count() or 1


def other_runnable_threads(loadavg: str, own_states: Iterable[str]) -> int:
    """Runnable threads of other processes: the runnable count of /proc/loadavg's text ("0.39 1.79 2.06 3/512 77",
    the reading thread among them) less this process's threads whose state is R."""
    runnable = int(loadavg.split()[3].split("/")[0])
    return max(0, runnable - sum(state == "R" for state in own_states))


def _own_thread_states() -> list[str]:
    states = []
    for task in os.listdir("/proc/self/task"):
        try:
            stat = Path(f"/proc/self/task/{task}/stat").read_text()
        except OSError:  # the thread ended meanwhile
            continue
        states.append(stat[stat.rindex(")") + 2])
    return states


def others_runnable() -> float | None:
    """Other processes' runnable threads now: the mean of PAUSE_SAMPLES samples, or None where /proc cannot tell.
    A seam the tests replace."""
    counts = []
    try:
        for index in range(PAUSE_SAMPLES):
            if index:
                time.sleep(PAUSE_SAMPLE_SECONDS)
            states = _own_thread_states()
            counts.append(other_runnable_threads(Path("/proc/loadavg").read_text(), states))
    except (OSError, ValueError, IndexError):
        return None
    return statistics.fmean(counts)


def cpu_times() -> list[int] | None:
    """The machine's CPU time by kind in clock ticks, /proc/stat's "cpu" line (user, nice, system, idle, iowait,
    irq, softirq, steal, ...); None where /proc cannot tell. A seam the tests replace."""
    try:
        with open("/proc/stat") as stat:
            fields = stat.readline().split()
        times = [int(value) for value in fields[1:]]
    except (OSError, ValueError):
        return None
    return times if fields[:1] == ["cpu"] and len(times) > _STEAL_FIELD else None


def steal_share(before: Sequence[int] | None, after: Sequence[int] | None) -> float | None:
    """Of the CPU time the machine wanted between two cpu_times() readings (all but idle and iowait), the share the
    hypervisor gave to other guests (steal); None without both readings or with no time wanted. The guest and
    guest_nice columns are already inside user and nice, so only the first eight columns are summed."""
    if before is None or after is None:
        return None
    delta = [b - a for a, b in zip(before[: _STEAL_FIELD + 1], after[: _STEAL_FIELD + 1], strict=True)]
    wanted = sum(delta) - sum(delta[i] for i in _IDLE_FIELDS)
    return max(0.0, delta[_STEAL_FIELD] / wanted) if wanted > 0 else None


@dataclass
class PauseLoad:
    """Other processes' runnable threads, sampled at each call (a pause between renders)."""

    samples: list[float] = field(default_factory=list)

    def __call__(self) -> None:
        if (value := others_runnable()) is not None:
            self.samples.append(value)


@dataclass(frozen=True)
class LoadCheck:
    before: float  # 1-minute load average before the bench's first build
    after: float  # the same after its last render (its own threads of the last minute included)
    cores: int
    others: float | None = None  # other processes' runnable threads, mean over the pauses (None: not sampled)
    pauses: int = 0
    steal: float | None = None  # share of the CPUs' wanted time the hypervisor took meanwhile (None: not reported)

    @classmethod
    def of(cls, before: float, after: float, cores: int, pauses: PauseLoad, steal: float | None = None) -> LoadCheck:
        others = statistics.fmean(pauses.samples) if pauses.samples else None
        return cls(before, after, cores, others, len(pauses.samples), steal)

    @property
    def limit(self) -> float:
        return BUSY_LOAD_PER_CORE * self.cores

    @property
    def busy(self) -> bool:
        # Without samples (no /proc) only the load average is left, which counts the bench's own threads.
        loaded = (self.others if self.others is not None else max(self.before, self.after)) > self.limit
        return loaded or (self.steal is not None and self.steal > BUSY_STEAL_SHARE)

    def as_dict(self) -> dict:
        return {**asdict(self), "limit": self.limit, "busy": self.busy}


class LoadWatch:
    """The load around a bench's timed part, as every bench judges it: made before the bench's builds (the load
    average then); start() before the first timed render (the hypervisor's share counts from there); pause() before
    each timed render and after the last; check() the verdict."""

    def __init__(self) -> None:
        self.before = load_average()
        self.pauses = PauseLoad()
        self.cpu_times_at_start: list[int] | None = None

    def start(self) -> None:
        self.cpu_times_at_start = cpu_times()

    def pause(self) -> None:
        self.pauses()

    def check(self) -> LoadCheck:
        steal = steal_share(self.cpu_times_at_start, cpu_times())
        return LoadCheck.of(self.before, load_average(), core_count(), self.pauses, steal)


def load_text(load: dict) -> str:
    """One line: other processes' runnable threads between renders, the load average before and after, the
    hypervisor's share where it is reported, and the warning when the machine was busy."""
    average = f"load average (1 min) before {load['before']:.2f}, after {load['after']:.2f}"
    quiet = f"on {load['cores']} cores (quiet: at most {load['limit']:.2f})"
    if load.get("others") is None:
        text = f"{average}, {quiet}"
    else:
        text = (
            f"other processes' runnable threads {load['others']:.2f} between renders (mean of {load['pauses']} "
            f"pauses), {quiet}; {average} (the bench's own threads included)"
        )
    if load.get("steal") is not None:
        text += (
            f"; taken by the hypervisor: {100 * load['steal']:.1f} % of the CPU time wanted "
            f"(quiet: at most {100 * BUSY_STEAL_SHARE:.0f} %)"
        )
    return f"{BUSY_WARNING}: {text}" if load["busy"] else text


class Contestant(Protocol):
    """A renderer ready to render its scene again: `name` its runtime or variant, `renderer` whose it is."""

    name: str
    renderer: str

    def render_timed(self) -> tuple[float, float]:
        """One render: (wall seconds, process CPU seconds)."""
        ...


@dataclass(frozen=True)
class Timing:
    renderer: str
    name: str
    block: str  # the peer whose rounds this render ran in ("" without a peer)
    round: int  # from 1
    seconds: float
    cpu_seconds: float


def alternate_rounds(
    ours: Sequence[Contestant],
    peers: Sequence[Contestant],
    rounds: int,
    log: Callable[[str], None] = lambda text: None,
    before_block: Callable[[Contestant], None] = lambda peer: None,
    pause: Callable[[], None] = lambda: None,
) -> list[Timing]:
    """`rounds` rounds per peer, each ours in turn and then the peer; the peers one after another, each in a block
    of its own (Mitsuba re-traces its kernels when its variant changes). Without peers, ours alone. `pause` is
    called before each render and after the last."""
    timings = []
    blocks: list[Contestant | None] = [*peers] or [None]
    for peer in blocks:
        if peer is not None:
            before_block(peer)
        for index in range(1, rounds + 1):
            for contestant in [*ours, *([peer] if peer is not None else [])]:
                pause()
                seconds, cpu = contestant.render_timed()
                timings.append(
                    Timing(contestant.renderer, contestant.name, peer.name if peer else "", index, seconds, cpu)
                )
                log(f"round {index}: {contestant.name} {seconds:.2f} s, CPU {cpu:.2f} s")
    pause()
    return timings


def spread(values: Sequence[float]) -> dict:
    """Median, smallest and largest, and (largest - smallest) / median."""
    median = statistics.median(values)
    low, high = min(values), max(values)
    return {
        "median": median,
        "min": low,
        "max": high,
        "relative_spread": (high - low) / median if median else 0.0,
        "n": len(values),
    }


def timing_summary(timings: Sequence[Timing], name: str, samples: int) -> dict:
    """One contestant's renders: wall and CPU seconds (median, spread), samples/s and per CPU second at the
    medians, and the cores it kept busy (CPU ÷ wall, median)."""
    own = [t for t in timings if t.name == name]
    wall = spread([t.seconds for t in own])
    cpu = spread([t.cpu_seconds for t in own])
    return {
        "rounds": len(own),
        "seconds": wall,
        "cpu_seconds": cpu,
        "samples_per_second": samples / wall["median"],
        "samples_per_cpu_second": samples / cpu["median"],
        "cores_used": statistics.median([t.cpu_seconds / t.seconds for t in own if t.seconds > 0] or [0.0]),
    }


def paired_ratios(timings: Sequence[Timing], ours: str, ours_samples: int, peer: str, peer_samples: int) -> dict:
    """Our samples/s ÷ the peer's, round by round within the peer's block (wall clock, and per CPU second)."""
    mine = {t.round: t for t in timings if t.name == ours and t.block == peer}
    theirs = {t.round: t for t in timings if t.name == peer and t.block == peer}
    rounds = sorted(mine.keys() & theirs.keys())
    wall = [(ours_samples / mine[r].seconds) / (peer_samples / theirs[r].seconds) for r in rounds]
    cpu = [(ours_samples / mine[r].cpu_seconds) / (peer_samples / theirs[r].cpu_seconds) for r in rounds]
    return {"spectrace": ours, "mitsuba": peer, "ratio": spread(wall), "cpu_time_ratio": spread(cpu)}
