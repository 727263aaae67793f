"""One reproduce driver's rule for every robot: a configuration the toolchain predicts will
fail is refused, the same way on the paper's robot (``runtime.reproduction.paper``) and on
any other (``runtime.reproduction.robot``). Both run through
``runtime.reproduction.runs.checked_run``: the configuration checks
(``runtime.stability.checks``) first, and a refused run is not simulated: its record has no
sample, says why, and its outcome is ``refused``.

The case: Drishti with a ±70 % uncertainty box, over which the TDE condition ‖M⁻¹M̂ − I‖ < 1
of (17) fails for the time-delay controllers (TDC, TDROC) and holds for the others.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.reproduction.paper import reproduce
from runtime.reproduction.robot import reproduce_robot
from runtime.reproduction.runs import checked_run
from runtime.setting.robot import robot_setting
from runtime.sim import loop, paths
from runtime.sim.outcome import outcome

CODE = load_robot_code("")
SHORT = replace(Experiment(), paths=replace(Experiment().paths, circle_duration=2.0,
                                            lawnmower_duration=2.0))
WIDE = replace(SHORT, controller=replace(SHORT.controller, uncertainty=0.7))
TDE = {c.name for c in CODE.controller_infos if c.tde}


def test_a_refused_configuration_is_not_run() -> None:
    ref = paths.circle(CODE, CODE.params, WIDE)
    refused = checked_run(CODE, "tdc", "paper", ref, CODE.params, WIDE)
    assert refused.refused is not None and "TDE condition" in refused.refused
    assert len(refused.t) == 0
    result = outcome(refused, ref.scale)
    assert result.status == "refused" and result.detail == refused.refused
    # The loop itself runs whatever it is given: the check is the driver's.
    ran = loop.run(CODE, "tdc", "paper", ref, CODE.params, WIDE)
    assert ran.refused is None and len(ran.t) == len(ref.t)
    # An accepted configuration runs as the loop runs it.
    accepted = checked_run(CODE, "asmc", "paper", ref, CODE.params, WIDE)
    direct = loop.run(CODE, "asmc", "paper", ref, CODE.params, WIDE)
    assert accepted.refused is None and (accepted.tau == direct.tau).all()


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_both_drivers_refuse_the_same_runs() -> None:
    sensing = ("sample-instant",)
    paper = reproduce(WIDE, sensings=sensing)
    paper_refused = {(m.controller, m.formulation, m.path) for m in paper.table
                     if math.isnan(m.rms_error)}
    assert {r.refused is not None for r in paper.runs.values()} == {True, False}
    assert all((r.refused is not None) == (r.controller in TDE) for r in paper.runs.values())

    setting = robot_setting(None, None, WIDE)
    assert setting.is_paper_robot  # the same robot and experiment, by the other driver
    robot = reproduce_robot(setting, sensing)
    robot_refused = {(r.controller, r.formulation, r.path) for r in robot.rows
                     if r.status == "refused"}
    # The paper's driver runs the paper's two formulations; the robot's every one it has.
    assert robot_refused == {(c, f, p) for c, f, p in paper_refused}
    assert robot_refused == {(r.controller, r.formulation, r.path) for r in robot.rows
                             if r.controller in TDE}
