"""The process-level memos of the references (``runtime.sim.reference.integrate``), of the
grip along a path (``runtime.stability.saturation.grip_along``), of the saturation verdict
(``saturation_verdict``) and of the measured switching gain
(``runtime.stability.analysis.measured_gain``): a repeated request returns what a fresh
computation returns, bit for bit (arrays as a copy of their own); a request that differs in
anything the computation reads is computed anew."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.settings import Experiment
from runtime.sim import paths, reference
from runtime.stability import analysis, saturation


@pytest.fixture(scope="module")
def code() -> RobotCode:
    return load_robot_code("")


def _short() -> Experiment:
    exp = Experiment()
    return replace(exp, paths=replace(exp.paths, circle_duration=3.0, lawnmower_duration=4.0))


def test_a_repeated_reference_is_the_fresh_one_and_a_copy(code: RobotCode) -> None:
    exp = _short()
    reference._memo.clear()
    first = paths.circle(code, code.params, exp)
    first.q[:] = np.nan  # a caller that writes into its reference harms no other caller
    again = paths.circle(code, code.params, exp)
    fresh = reference._integrate(code, "circle", reference.WheelProfile(
        (reference.START_AT,), (paths.circle_rates(paths.robot_scale(code, code.params),
                                                   exp.paths),)),
        again.q[0], code.params, exp.controller.h, exp.paths.circle_duration, again.scale)
    for name in ("t", "q", "qdot", "qddot"):
        assert np.array_equal(getattr(again, name), getattr(fresh, name)), name
    assert len(reference._memo) == 1


def test_a_reference_with_other_parameters_is_computed_anew(code: RobotCode) -> None:
    """The same wheel-rate profile on a robot with larger wheels: another motion."""
    profile = reference.WheelProfile((reference.START_AT,), ((2.0, 1.0),))
    start = np.zeros(code.nq)
    bigger = {**code.params, "r": code.params["r"] * 1.1}
    a, b = (reference.integrate(code, "wheels", profile, start, p, 0.1, 3.0)
            for p in (code.params, bigger))
    assert not np.array_equal(a.qdot, b.qdot)


def test_the_grip_memo_returns_the_fresh_grip(code: RobotCode) -> None:
    exp = _short()
    monitor = saturation.slip_monitor(code, exp, code.params)
    assert monitor is not None
    ref = paths.circle(code, code.params, exp)
    saturation._grip_memo.clear()
    need, _ = saturation.grip_along(monitor, code.params, exp, ref)
    need[:] = np.nan
    again = saturation.grip_along(monitor, code.params, exp, ref)
    fx, fy, n = monitor.along(ref, code.params, exp)
    r = np.array([{w.name: w.radius for w in monitor.robot.wheels}[w] for w in monitor.driven])
    assert np.array_equal(again[0], r * np.hypot(fx, fy))
    assert np.array_equal(again[1], exp.plant.friction * n * r)
    # another path's samples: computed anew, not the circle's
    slower = paths.lawnmower(code, code.params, exp)
    other = saturation.grip_along(monitor, code.params, exp, slower)
    assert other[0].shape[0] == len(slower.t) != len(ref.t)


def test_a_repeated_saturation_verdict_is_the_fresh_one(code: RobotCode) -> None:
    """The verdict memo (``wmr freeze`` asks for the same simulated verdict on every run): the
    fresh verdict again; an experiment that differs only in its file's name is the same
    request; one that differs in τ_max is computed anew (another verdict)."""
    exp = _short()
    saturation._verdict_memo.clear()
    first = saturation.saturation_verdict(code, "tdroc", "paper", code.params, exp)
    fresh = saturation._saturation_verdict(code, "tdroc", "paper", code.params, exp,
                                           "payload", False)
    assert first == fresh
    again = saturation.saturation_verdict(code, "tdroc", "paper", code.params,
                                          replace(exp, source="elsewhere.toml"))
    assert again is first and len(saturation._verdict_memo) == 1
    low = replace(exp, controller=replace(exp.controller, tau_max=0.5 * fresh.demand))
    other = saturation.saturation_verdict(code, "tdroc", "paper", code.params, low)
    assert other.tau_max == low.controller.tau_max and other.verdict == "saturates"
    assert len(saturation._verdict_memo) == 2


def test_a_repeated_measured_gain_is_the_fresh_one(code: RobotCode) -> None:
    exp = _short()
    analysis._gain_memo.clear()
    first = analysis.measured_gain(code, "tdroc", "paper", code.params, exp)
    assert first == analysis._measured_gain(code, "tdroc", "paper", code.params, exp)
    assert analysis.measured_gain(code, "tdroc", "paper", code.params,
                                  replace(exp, source="elsewhere.toml")) == first
    assert len(analysis._gain_memo) == 1
    # another window discount: another loop, another median gain
    other = replace(exp, controller=replace(exp.controller, a=0.5))
    assert analysis.measured_gain(code, "tdroc", "paper", code.params, other) != first
    assert len(analysis._gain_memo) == 2
