"""Timed rounds that alternate renderers, their medians and spreads, and the machine's load around them.

A ratio of two renderers' speeds holds only when both ran under the same conditions. The rounds alternate
(each of ours, then the peer, then each of ours again, ...), so a load that comes and goes falls on both alike,
and every ratio is taken round by round (our render ÷ the peer's render of the same round), its median reported
with the smallest and largest. The 1-minute load average is read before the first round and after the last: above
half a runnable thread per core at either end, other work competed for the cores and the figures say so.
"""

from __future__ import annotations

import os
import statistics
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Protocol

DEFAULT_ROUNDS = 5
BUSY_LOAD_PER_CORE = 0.5
BUSY_WARNING = "machine busy: ratio not reliable"


def load_average() -> float:
    """The 1-minute load average (runnable threads, averaged); a seam the tests replace."""
    return os.getloadavg()[0]


def core_count() -> int:
    """The cores of the machine, which the load average is counted over (not this process's affinity)."""
    return os.cpu_count() or 1


@dataclass(frozen=True)
class LoadCheck:
    before: float
    after: float
    cores: int

    @property
    def limit(self) -> float:
        return BUSY_LOAD_PER_CORE * self.cores

    @property
    def busy(self) -> bool:
        return max(self.before, self.after) > self.limit

    def as_dict(self) -> dict:
        return {**asdict(self), "limit": self.limit, "busy": self.busy}


def load_text(load: dict) -> str:
    """One line: the load before and after, and the warning when either end was above the limit."""
    text = (
        f"load average (1 min) before {load['before']:.2f}, after {load['after']:.2f}, on {load['cores']} cores "
        f"(quiet: at most {load['limit']:.2f})"
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
) -> list[Timing]:
    """`rounds` rounds per peer, each ours in turn and then the peer; the peers one after another, each in a block
    of its own (Mitsuba re-traces its kernels when its variant changes). Without peers, ours alone."""
    timings = []
    blocks: list[Contestant | None] = [*peers] or [None]
    for peer in blocks:
        if peer is not None:
            before_block(peer)
        for index in range(1, rounds + 1):
            for contestant in [*ours, *([peer] if peer is not None else [])]:
                seconds, cpu = contestant.render_timed()
                timings.append(
                    Timing(contestant.renderer, contestant.name, peer.name if peer else "", index, seconds, cpu)
                )
                log(f"round {index}: {contestant.name} {seconds:.2f} s, CPU {cpu:.2f} s")
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
