"""Jitter, analysed and simulated: Drishti, TDC, minimal formulation, circle.

The stability analysis reads a delay D ± J as the worst of the constant delays D − J, D and
D + J (a necessary condition: ``runtime.stability.sampled_loop.delay_radius``). At 51 ms the
loop is stable; at 51 ± 26 ms the extreme 77 ms is not, so the verdict must read unstable,
with the spectral radius of the 77 ms loop, and the closed loop at that constant delay must
diverge (what the verdict rests on). An analysis that dropped the upper extreme read 0.893
here: stable. The loop itself must apply the jitter (a run with it differs from one
without) and stay on the path where the analysis says stable.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.sim import loop, paths
from runtime.sim.loop import Run
from runtime.stability import analysis
from runtime.stability.verification import linear_experiment

DRISHTI = load_robot_code("")
NOMINAL = dict(DRISHTI.params)
D, J = 0.051, 0.026  # s
DIVERGED = 1.0  # rad-scale error: far beyond the millimetres of a stable run


def experiment(delay: float, jitter: float) -> Experiment:
    exp = Experiment()
    return replace(exp, controller=replace(exp.controller, delay_time=delay, jitter_time=jitter))


def radius(delay: float, jitter: float) -> float:
    a = analysis.analyse(DRISHTI, "tdc", "minimal", NOMINAL, experiment(delay, jitter),
                         measure=False)
    assert a.stable == (a.spectral_radius < 1.0)
    return a.spectral_radius


@cache
def run(delay: float, jitter: float) -> Run:
    lin = linear_experiment(experiment(delay, jitter))
    return loop.run(DRISHTI, "tdc", "minimal", paths.circle(DRISHTI, NOMINAL, lin), NOMINAL,
                    lin)


def _late_error(r: Run) -> float:
    return float(np.max(r.error_norm[2 * len(r.error_norm) // 3:]))


def test_jitter_reads_the_worst_extreme() -> None:
    without, extreme, low = radius(D, 0.0), radius(D + J, 0.0), radius(D - J, 0.0)
    assert without < 1.0 < extreme, (without, extreme)
    assert low < 1.0
    with_jitter = radius(D, J)
    assert with_jitter == pytest.approx(max(without, extreme, low), rel=1e-12)
    assert with_jitter > 1.0


def test_the_extreme_delay_the_verdict_rests_on_diverges_in_the_loop() -> None:
    stable, unstable = run(D, 0.0), run(D + J, 0.0)
    assert stable.failed_at is None and _late_error(stable) < 0.01
    assert unstable.failed_at is not None or float(unstable.error_norm.max()) > DIVERGED


def test_the_loop_applies_the_jitter() -> None:
    """Each sample's delay is drawn within ± J: the torques the actuators get differ from
    the constant-delay run's, and the run stays bounded (random delays are not the worst
    sequence: the analysis' condition is necessary, not sufficient)."""
    jittered, constant = run(D, J), run(D, 0.0)
    assert not np.allclose(jittered.tau_applied, constant.tau_applied)
    assert jittered.failed_at is None and _late_error(jittered) < 0.01


def test_a_radius_just_above_one_reads_unstable() -> None:
    """Bisect the constant delay between 51 ms (stable) and 77 ms (unstable) to a loop whose
    spectral radius is within 0.5 % above 1: the verdict reads the radius as it is (a
    tolerance on 1 would call it stable)."""
    lo, hi = D, D + J
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        rho = radius(mid, 0.0)
        if rho < 1.0:
            lo = mid
        elif rho > 1.005:
            hi = mid
        else:
            break
    a = analysis.analyse(DRISHTI, "tdc", "minimal", NOMINAL, experiment(mid, 0.0),
                         measure=False)
    assert 1.0 < a.spectral_radius <= 1.005, a.spectral_radius
    assert not a.stable
