"""The loop's timing, sample by sample: when sample k starts on the plant's clock, how long
the plant runs until the next one (the period h_k) and how late the command computed at it
reaches the actuators (the latency D_k).

:class:`DrawnTiming` is the experiment's: the period h on the reference's time base and a
latency within ± the jitter bound of the delay, drawn by a seeded generator (the same run
every time). :class:`GivenTiming` is a stated sequence of (h_k, D_k), repeated: what the
jitter analysis' adversarial search finds (:mod:`runtime.stability.jitter`) replayed in the
closed loop. The loop (:func:`runtime.sim.loop.run`) reads either through :class:`Schedule`;
the law keeps its configured h and its reference sample k whatever the plant's period (a
controller that does not measure its period, as the analysis assumes).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

JITTER_SEED = 29  # the jitter's draws: the same run every time


class Schedule(Protocol):
    """Sample k's start on the plant's clock, its period, and its command's latency (the
    latency is asked once per command sent, in sample order)."""

    def start(self, k: int) -> float: ...

    def period(self, k: int) -> float: ...

    def latency(self, k: int) -> float: ...


class DrawnTiming:
    """The experiment's timing: sample k at ``times[k]`` (the reference's), period ``h``,
    latency ``delay`` ± a uniform draw within ``jitter`` (one draw per command sent)."""

    def __init__(self, times: NDArray[np.float64], h: float, delay: float, jitter: float) -> None:
        self.times, self.h, self.delay, self.jitter = times, h, delay, jitter
        self.rng = np.random.default_rng(JITTER_SEED)

    def start(self, k: int) -> float:
        return float(self.times[k])

    def period(self, k: int) -> float:
        return self.h

    def latency(self, k: int) -> float:
        d = self.delay
        if self.jitter > 0:
            d += float(self.rng.uniform(-self.jitter, self.jitter))
        return d


class GivenTiming:
    """A stated sequence of (period, latency) in s, repeated from sample 0 on; sample k
    starts at the sum of the periods before it."""

    def __init__(self, sequence: Sequence[tuple[float, float]]) -> None:
        if not sequence:
            raise ValueError("a timing sequence needs at least one (period, latency)")
        for h, d in sequence:
            if not (h > 0 and d >= 0):
                raise ValueError(f"a timing sample needs a period > 0 and a latency >= 0: "
                                 f"({h}, {d})")
        self.sequence = tuple((float(h), float(d)) for h, d in sequence)
        self.starts = [0.0]

    def start(self, k: int) -> float:
        while len(self.starts) <= k:
            self.starts.append(self.starts[-1] + self.period(len(self.starts) - 1))
        return self.starts[k]

    def period(self, k: int) -> float:
        return self.sequence[k % len(self.sequence)][0]

    def latency(self, k: int) -> float:
        return self.sequence[k % len(self.sequence)][1]

