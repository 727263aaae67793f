"""The jitter part of ``wmr stability`` (:mod:`runtime.stability.jitter`): the verdict of
each stated timing range, the budget, and the adversarial sequences replayed in the closed
loop on a chosen plant, as lines or as JSON.

Ranges: ``[controller] jitter`` (latencies within ± J of the delay) and the measured
timing (``period_worst``, ``latency_worst``). With a replay plant, the adversarial search's
worst sequence in each stated range is run in the closed loop
(:func:`runtime.stability.jitter.replay`) on that plant, the model or MuJoCo; with the
budget, so are the worst sequence inside the proved budget and the growing one found at
the smallest destabilising jitter. A sequence inside a range proved that diverges
contradicts the proof: :attr:`Report.contradictions` counts them (the command fails).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.stability.analysis import Analysis
from runtime.stability.jitter import (
    Budget,
    JitterVerdict,
    Search,
    Timing,
    budget,
    delay_jitter,
    loop_for,
    measured,
    replay,
    verdict,
)
from runtime.stability.sampled_loop import setting


@dataclass(frozen=True)
class Replayed:
    """One sequence run in the closed loop: what it is, whether it lies inside a proved
    range, and the run's outcome."""

    what: str
    proved_inside: bool
    sequence: tuple[tuple[float, float], ...]
    plant: str
    diverged: bool
    growth: float

    @property
    def contradiction(self) -> bool:
        return self.proved_inside and self.diverged


@dataclass
class RowReport:
    """The jitter results of one analysed row (controller, formulation)."""

    controller: str
    formulation: str
    ranges: list[tuple[str, Timing, JitterVerdict | None, str]] = field(default_factory=list)
    budget: Budget | None = None
    replays: list[Replayed] = field(default_factory=list)


@dataclass
class Report:
    rows: list[RowReport]
    stated: bool  # whether the experiment states a jitter or a measured timing

    @property
    def contradictions(self) -> int:
        return sum(r.contradiction for row in self.rows for r in row.replays)


def stated_ranges(exp: Experiment) -> list[tuple[str, Timing]]:
    c = exp.controller
    out = []
    if c.jitter_seconds() > 0:
        out.append(("[controller] jitter", delay_jitter(c.h, c.delay_seconds(),
                                                        c.jitter_seconds())))
    if c.period_worst > 0 or c.latency_worst > 0:
        out.append(("measured timing", measured(c.h, max(c.h, c.period_worst),
                                                c.latency_worst)))
    return out


def report(rows: list[Analysis], code: RobotCode, robot: dict[str, float], exp: Experiment,
           plant: str, with_budget: bool, replay_on: str | None = None) -> Report:
    """The jitter results of every stable row; ``replay_on``: the plant model the
    adversarial sequences are replayed on (None: not replayed)."""
    ranges = stated_ranges(exp)
    out = Report([], bool(ranges))
    run_exp = exp if replay_on is None else replace(exp, plant=replace(exp.plant,
                                                                         model=replay_on))

    def run(row: RowReport, what: str, inside: bool, found: Search | None) -> None:
        if replay_on is None or found is None or not found.sequence:
            return
        r = replay(code, row.controller, row.formulation, robot, run_exp, found.sequence)
        row.replays.append(Replayed(what, inside, found.sequence, r.plant, r.diverged,
                                    r.growth))

    for a in rows:
        if not a.stable:
            continue
        row = RowReport(a.controller, a.formulation)
        out.rows.append(row)
        s = setting(code, a.controller, a.formulation, robot, exp, plant)
        loop = loop_for(s) if ranges else None
        for label, timing in ranges:
            assert loop is not None
            try:
                v = verdict(loop, a.gain_at_setting, timing, search=replay_on is not None)
            except ValueError as exc:
                row.ranges.append((label, timing, None, str(exc)))
                continue
            row.ranges.append((label, timing, v, ""))
            run(row, f"worst sequence found in {label}", v.verdict == "proved", v.search)
        if with_budget:
            row.budget = b = budget(s, a.gain_at_setting)
            run(row, f"worst sequence found inside the proved budget ±{b.proved * 1e3:.3g} ms",
                True, b.inside)
            run(row, "growing sequence found at the smallest destabilising jitter "
                f"±{b.destabilising * 1e3:.3g} ms", False, b.growing)
    return out


def _sequence_text(seq: tuple[tuple[float, float], ...]) -> str:
    text = ", ".join(f"({h * 1e3:.4g}, {d * 1e3:.4g})" for h, d in seq[:8])
    return f"[{text}{', …' if len(seq) > 8 else ''}] ms (period, latency), repeated"


def lines(rep: Report, with_budget: bool) -> list[str]:
    out = ["", "Jitter (a common quadratic Lyapunov function over the range, the gaps between "
           "grid points covered by a derived bound; runtime/stability/jitter.py):"]
    if not rep.stated and not with_budget:
        out.append("* no jitter stated ([controller] jitter, period_worst, latency_worst)")
    for row in rep.rows:
        name = f"{row.controller} {row.formulation}"
        for label, timing, v, error in row.ranges:
            out.append(f"* {name}, {label}: no verdict: {error}" if v is None else
                       f"* {name}, {label} ({timing.describe()}): {v.describe()}")
        b = row.budget
        if b is not None:
            why = f"; above it: {b.reason}" if b.reason else ""
            out.append(f"* {name}: delay jitter proved up to ±{b.proved * 1e3:.3g} ms, "
                       f"necessary boundary ±{b.necessary * 1e3:.3g} ms, destabilising "
                       f"switching found from ±{b.destabilising * 1e3:.3g} ms "
                       f"({b.seconds:.0f} s){why}")
        for r in row.replays:
            word = "diverged" if r.diverged else "bounded"
            flag = " — CONTRADICTS THE PROOF" if r.contradiction else ""
            out.append(f"  - replayed on {r.plant}: {r.what}, {_sequence_text(r.sequence)}: "
                       f"{word} (last third's error / middle third's {r.growth:.3g}){flag}")
    return out


def _num(x: float | None) -> float | str | None:
    if x is None:
        return None
    return x if math.isfinite(x) else str(x)


def as_json(rep: Report) -> list[dict[str, Any]]:
    out = []
    for row in rep.rows:
        ranges = []
        for label, t, v, error in row.ranges:
            item: dict[str, Any] = {"range": label, "h_min": t.h_min, "h_max": t.h_max,
                                    "d_min": t.d_min, "d_max": t.d_max}
            if v is None:
                item["error"] = error
            else:
                item.update(verdict=v.verdict, radius=v.radius, bound=_num(v.bound),
                            gap_bound=_num(v.delta), margin=_num(v.margin),
                            mismatch=_num(v.mismatch), reason=v.reason)
            ranges.append(item)
        b = row.budget
        out.append({
            "controller": row.controller, "formulation": row.formulation, "ranges": ranges,
            "budget": None if b is None else {
                "proved": b.proved, "necessary": _num(b.necessary),
                "destabilising": b.destabilising, "seconds": b.seconds, "reason": b.reason},
            "replays": [{"what": r.what, "plant": r.plant, "inside_proved": r.proved_inside,
                         "sequence": [list(p) for p in r.sequence], "diverged": r.diverged,
                         "growth": _num(r.growth), "contradiction": r.contradiction}
                        for r in row.replays],
        })
    return out
