"""One reproduce driver for every robot (``runtime.reproduction.driver``): a configuration
the toolchain predicts will fail is refused the same way on every robot, through
``runtime.reproduction.runs.checked_run``: the configuration checks
(``runtime.stability.checks``) first, and a refused run is not simulated: its record has no
sample, says why, and its outcome is ``refused``. The paper's robot is a setting
(``Setting.is_paper_robot``), not another driver: it adds TDROC's ε sweep, and changes no
run and no number of the table.

The case: Drishti with a ±70 % uncertainty box, over which the TDE condition ‖M⁻¹M̂ − I‖ < 1
of (17) fails for the time-delay controllers (TDC, TDROC) and holds for the others.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.reproduction.driver import reproduce
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


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == b


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_the_paper_robot_is_a_setting_of_the_one_driver() -> None:
    sensing = ("sample-instant",)
    paper = robot_setting(None, None, WIDE)
    assert paper.is_paper_robot
    rep = reproduce(paper, sensing)
    refused = {(m.controller, m.formulation, m.path) for m in rep.table if m.status == "refused"}
    assert {r.refused is not None for r in rep.runs.values()} == {True, False}
    assert all((r.refused is not None) == (r.controller in TDE) for r in rep.runs.values())
    assert refused == {(m.controller, m.formulation, m.path) for m in rep.table
                       if m.controller in TDE}
    assert all(math.isnan(m.rms_error) for m in rep.table if m.status == "refused")
    assert rep.sweep and rep.sweep_runs  # the paper's extra

    # The same robot and numbers under another name is not the paper's robot: the same
    # driver runs the same runs to the same numbers, without the paper's extra.
    other = replace(paper, robot=replace(paper.robot, name="not-drishti"))
    assert not other.is_paper_robot
    alike = reproduce(other, sensing)
    assert not alike.sweep and not alike.sweep_runs
    assert [(m.sensing, m.controller, m.formulation, m.path, m.status) for m in alike.table] \
        == [(m.sensing, m.controller, m.formulation, m.path, m.status) for m in rep.table]
    assert all(_same(a.rms_error, b.rms_error) and _same(a.rms_torque, b.rms_torque)
               and _same(a.friction_needed, b.friction_needed)
               for a, b in zip(alike.table, rep.table, strict=True))
