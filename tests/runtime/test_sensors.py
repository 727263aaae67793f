"""What the controllers measure (runtime/sim/sensors.py), each sensing model on its own,
computed here by hand from the encoder's definition: whole counts of 4 × ppr (× the gear
ratio on the motor side) per wheel revolution, floored; the rate at the instant, over the
sample (Δθ/h) or over the motor-encoder's window; the pose by odometry through (31).

Drishti, from rest at the origin; one sample in which both wheels turn by the same angle
(a straight line: the pose advances by r Δθ along x, the heading stays) and one in which
they turn apart.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.sim.sensors import Sensors

CODE = load_robot_code("")
PARAMS = dict(CODE.params)
ACT = list(CODE.actuated)
TRUE_RATES = np.array([2.0, 1.5])


def sensors(velocity: str) -> tuple[Sensors, Experiment]:
    exp = Experiment()
    exp = replace(exp, sensing=replace(exp.sensing, velocity=velocity))
    return Sensors(CODE, np.zeros(CODE.nq), exp, PARAMS), exp


def counts(angle: np.ndarray, exp: Experiment) -> np.ndarray:
    per_rad = exp.sensing.counts_per_wheel_rev() / (2 * math.pi)
    return np.floor(angle * per_rad) / per_rad


@pytest.mark.parametrize("velocity", ["sample-instant", "encoder-average", "motor-encoder"])
def test_each_sensing_model_by_hand(velocity: str) -> None:
    s, exp = sensors(velocity)
    h = exp.controller.h
    angles = np.array([0.123456, 0.2345678])
    window_start = angles - 0.01 * TRUE_RATES
    q, qdot = s.measure(angles, TRUE_RATES, window_start)
    np.testing.assert_array_equal(q[ACT], counts(angles, exp))
    expected = {
        "sample-instant": TRUE_RATES,
        "encoder-average": (counts(angles, exp) - 0.0) / h,
        "motor-encoder": (counts(angles, exp) - counts(window_start, exp))
        / exp.sensing.window,
    }[velocity]
    np.testing.assert_allclose(qdot[ACT], expected, rtol=1e-14, atol=1e-14)
    if velocity != "sample-instant":  # a measured rate is quantised, never the true one
        assert not np.allclose(qdot[ACT], TRUE_RATES, rtol=1e-3)


def test_odometry_of_a_straight_step() -> None:
    s, exp = sensors("encoder-average")
    step = counts(np.array([0.5, 0.5]), exp)
    q, _ = s.measure(step, TRUE_RATES)
    r = PARAMS["r"]
    x, y, theta = q[:3]
    assert x == pytest.approx(r * step[0], rel=1e-12)
    assert abs(y) < 1e-15 and abs(theta) < 1e-15


def test_odometry_turns_the_way_the_wheels_do() -> None:
    """The right wheel (the first driven one) ahead of the left turns the robot left."""
    s, _ = sensors("encoder-average")
    q, _ = s.measure(np.array([0.6, 0.4]), TRUE_RATES)
    assert q[2] > 0.0
    s2, _ = sensors("encoder-average")
    q2, _ = s2.measure(np.array([0.4, 0.6]), TRUE_RATES)
    assert q2[2] == pytest.approx(-q[2], rel=1e-12)
