"""The sufficient jitter budget (``runtime.stability.jitter``, issue 46) on Drishti, TDC in the
minimal formulation, sample-instant rates, h = 0.1 s, no nominal delay (constant-delay
boundary 64 ms): latencies varying every sample within [0, J].

* J = 20 ms is proved (a common quadratic Lyapunov function, the gaps between grid points
  covered by the derived bound of ``runtime.stability.gap``), and no sequence inside it
  diverges: not the adversarial search's worst switching (linear), not that sequence nor
  random ones on the nonlinear model plant;
* J = 62 ms: every constant latency is stable (the boundary is 64 ms) but switching
  between them destabilises from 60.9 ms, so no common P exists: "not proved (necessary
  condition holds)";
* J = 80 ms, beyond the necessary boundary: "unstable", and the adversarial search finds a
  sequence whose run on the nonlinear model plant grows (so the search can fail the first
  test).
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.stability import jitter as jt
from runtime.stability.sampled_loop import ClosedLoop, setting

CODE = load_robot_code("")


@cache
def loop() -> ClosedLoop:
    exp = Experiment()
    exp = replace(exp, sensing=replace(exp.sensing, velocity="sample-instant"))
    return jt.loop_for(setting(CODE, "tdc", "minimal", dict(CODE.params), exp), tail=400)


def timing(j: float) -> jt.Timing:
    return jt.delay_jitter(0.1, 0.0, j)


def test_sequences_inside_a_proved_budget_never_diverge() -> None:
    v = jt.verdict(loop(), 0.0, timing(0.02), search=True)
    assert v.verdict == "proved" and v.bound is not None and v.bound < 1.0
    assert v.search is not None and v.search.rate < 1.0
    assert jt.sequence_growth(loop(), 0.0, v.search.sequence, repeats=2) < 1.0
    rng = np.random.default_rng(7)
    for _ in range(3):
        seq = tuple((0.1, float(d)) for d in rng.choice([0.0, 0.02], size=20))
        assert jt.sequence_growth(loop(), 0.0, seq, repeats=3) < 1.0


def test_not_proved_where_only_the_necessary_condition_holds() -> None:
    v = jt.verdict(loop(), 0.0, timing(0.062))
    assert v.radius < 1.0 and v.verdict == "not proved (necessary condition holds)"


def test_search_finds_a_divergent_sequence_beyond_the_boundary() -> None:
    v = jt.verdict(loop(), 0.0, timing(0.08), search=True)
    assert v.verdict == "unstable" and v.search is not None and v.search.rate > 1.0
    assert jt.sequence_growth(loop(), 0.0, v.search.sequence, repeats=2) > 1.0


def test_latency_beyond_the_period_is_refused() -> None:
    with pytest.raises(ValueError, match="latency below the period"):
        jt.verdict(loop(), 0.0, jt.Timing(0.1, 0.1, 0.0, 0.1))


def test_wmr_stability_prints_the_jitter_verdicts() -> None:
    """``wmr stability --jitter``'s lines: the experiment's [controller] jitter and the
    measured timing (worst period, worst latency), each with its word."""
    from runtime.commands.stability import jitter_lines
    from runtime.experiment.settings import parse_experiment
    from runtime.stability.analysis import analyse

    exp = parse_experiment("[sensing]\nvelocity = 'sample-instant'\n[controller]\n"
                           "jitter_time = 0.02\nperiod_worst = 0.1\nlatency_worst = 0.08\n")
    row = analyse(CODE, "tdc", "minimal", dict(CODE.params), exp, measure=False)
    lines = jitter_lines([row], CODE, dict(CODE.params), exp, "nominal", False)
    assert any("[controller] jitter" in line and ": proved (" in line for line in lines), lines
    assert any("measured timing" in line and ": unstable (" in line for line in lines), lines
