"""The slip monitor's per-wheel arithmetic on left–right asymmetric loads and forces.

With the extra payload on board (off the robot's axis, to the left) Drishti's two driven
wheels carry different loads, and on a turn they transmit different forces. The friction a
sample needs is the largest ratio |F_w| / N_w over the wheels (the wheel nearest to
slipping), the margin is per wheel, and the lateral shares follow each wheel's load. A
monitor that took the smallest ratio, the mean load, or one wheel's load for both would
pass every symmetric case; these inputs tell them apart.
"""

from __future__ import annotations

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.setting.layout import robot_layout
from runtime.sim.slip_monitor import SlipMonitor

CODE = load_robot_code("")
EXP = Experiment()
BOTH_ON = np.array([EXP.plant.fixed_payload, EXP.plant.extra_payload])


def monitor() -> SlipMonitor:
    return SlipMonitor(CODE, robot_layout(CODE, CODE.plant_defaults), EXP)


def test_the_loads_are_asymmetric_with_the_extra_payload_on() -> None:
    m = monitor()
    right, left = m.normal_loads(BOTH_ON)
    assert left > right > 0  # the extra payload sits to the left (extra_payload_y > 0)
    fixed_only = m.normal_loads(np.array([EXP.plant.fixed_payload, 0.0]))
    assert fixed_only[0] == pytest.approx(fixed_only[1], rel=1e-12)
    shares = m.shares(BOTH_ON)
    assert shares == pytest.approx([right / (right + left), left / (right + left)], rel=1e-12)


@pytest.mark.parametrize("forces", [(30.0, 10.0), (10.0, 30.0), (-25.0, 5.0)])
def test_friction_needed_is_the_worst_wheels(forces: tuple[float, float]) -> None:
    m = monitor()
    loads = m.normal_loads(BOTH_ON)
    f = np.array(forces)
    ratios = np.abs(f) / loads
    assert m.friction_needed(f, BOTH_ON) == pytest.approx(float(ratios.max()), rel=1e-12)
    assert m.friction_needed(f, BOTH_ON) > float(ratios.min())
    mu = float(ratios.mean())  # between the two: one wheel slips, the other grips
    margin = m.margin(f, mu, BOTH_ON)
    assert margin == pytest.approx(mu * loads - np.abs(f), rel=1e-12)
    assert (margin < 0).sum() == 1
