"""The payload schedule, as each plant takes it: the generated-model plant through its
parameters (``plant_params_at``: the robot's mass plus what is on board), MuJoCo through
the masses at the two payload points (``payload_masses``). Both must follow the same
schedule: the fixed payload always, the extra one from ``extra_on_at`` for half of every
``extra_period``. A plant that carried the extra payload all the time passed the MuJoCo
tracking test (its tolerance is a millimetre); these instants cannot be confused.
"""

from __future__ import annotations

import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.sim.payload import payload_mass, payload_masses, plant_params_at

CODE = load_robot_code("")
EXP = Experiment()
PL = EXP.plant
BEFORE, ON, OFF = PL.extra_on_at - 1.0, PL.extra_on_at + 1.0, \
    PL.extra_on_at + 0.5 * PL.extra_period + 1.0


@pytest.mark.parametrize(("t", "extra"), [(0.0, False), (BEFORE, False), (ON, True),
                                          (OFF, False), (OFF + 0.5 * PL.extra_period, True)])
def test_both_plants_follow_one_schedule(t: float, extra: bool) -> None:
    assert PL.extra_on(t) == extra
    fixed, extra_mass = payload_masses(EXP, t)
    assert fixed == PL.fixed_payload
    assert extra_mass == (PL.extra_payload if extra else 0.0)
    assert payload_mass(EXP, t) == pytest.approx(fixed + extra_mass)
    base = {**CODE.plant_defaults, **CODE.params}
    # the generated plant's parameters carry the same mass as the engine's two points
    assert plant_params_at(CODE, EXP, t, base)["m"] == pytest.approx(
        base["m"] + fixed + extra_mass, rel=1e-12)
