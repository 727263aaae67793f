"""Grip in the verdict (issue 45): the saturation verdict compares each driven wheel's
torque with what the floor can react, μ N r (μ: the experiment's ``[plant] friction``, N
from ``modeling.contact_loads`` with load transfer), along the tracked path and in the
monitored simulation, and ``wmr stability`` never prints "stable" where a wheel is
predicted to lose grip.

* The done-when case: Drishti, h = 0.25 s, TDROC in the paper formulation on a μ = 1
  floor. The linear verdict is stable (ρ = 0.966) and the tracked path's torque is far
  under τ_max and μ N r; in closed loop k̂ grows and the simulated wheel needs μ = 2.2 from
  3.25 s (both MuJoCo plants slip from about 3.3 s): ``slips``, with the time, wheel and
  margin, and the traction limit that keeps grip (``traction_mu`` = 1).
* No false alarm: the same controller at the paper's h = 0.1 s keeps grip (``ok``).
* On a μ = 0.1 floor the circle itself needs about 0.21: predicted (not simulated) slip.
* The switching term's bound is a risk, not a slip: ROC on μ = 0.3 keeps grip.
About 10 s on one core.
"""

from __future__ import annotations

from dataclasses import replace

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.stability.analysis import analyse, table
from runtime.stability.saturation import saturation_verdict

DRISHTI = load_robot_code("")
NOMINAL = dict(DRISHTI.params)


def _exp(h: float, friction: float = 1.0) -> Experiment:
    exp = Experiment()
    return replace(exp, controller=replace(exp.controller, h=h),
                   plant=replace(exp.plant, friction=friction))


def test_tdroc_at_a_quarter_second_is_flagged_as_slipping() -> None:
    row = analyse(DRISHTI, "tdroc", "paper", NOMINAL, _exp(0.25), saturation=True)
    assert row.stable and row.spectral_radius < 1.0  # the linear verdict alone says stable
    assert row.saturation == "slips" and row.verdict == "slips", row
    assert "loses grip at t = " in row.saturation_reason
    assert "traction_mu = 1" in row.saturation_reason and "keeps grip" in row.saturation_reason
    line = next(x for x in table([row], DRISHTI).splitlines() if x.startswith("| TDROC"))
    assert "| yes |" not in line and "**no: slips**" in line
    sat = saturation_verdict(DRISHTI, "tdroc", "paper", NOMINAL, _exp(0.25), simulate=True)
    assert sat.slip is not None and sat.slip.simulated
    assert 2.5 <= sat.slip.t <= 4.0 and sat.slip.margin < 0
    assert sat.slip.wheel in ("right", "left")
    assert sat.friction_needed is not None and sat.friction_needed > 1.5
    assert sat.traction_mu == 1.0


def test_a_slip_on_the_long_path_is_found() -> None:
    """ASMC (minimal) at h = 0.25 s on μ = 1: the circle keeps grip (μ needed 0.24), but
    over the lawn mower's long run its gain grows until a wheel needs 2.8 (MuJoCo: slips
    from 45.75 s); the verdict simulates grip on every path."""
    sat = saturation_verdict(DRISHTI, "asmc", "minimal", NOMINAL, _exp(0.25), simulate=True)
    assert sat.verdict == "slips" and sat.slip is not None, sat.reason
    assert sat.slip.path == "lawnmower" and 40.0 <= sat.slip.t <= 50.0, sat.slip


def test_the_paper_sampling_keeps_grip() -> None:
    sat = saturation_verdict(DRISHTI, "tdroc", "paper", NOMINAL, _exp(0.1), simulate=True)
    assert sat.verdict == "ok" and sat.slip is None, sat.reason
    assert sat.friction_needed is not None and 0.15 < sat.friction_needed < 0.5
    assert sat.grip_margin > 0


def test_the_switching_bound_is_a_risk_not_a_slip() -> None:
    """ROC at h = 0.1 s on μ = 0.3: its switching torque's bound ‖M̂‖ k (3.6 N m) would
    exceed the grip, but it is reached only while ‖s‖ ≥ ε; the simulated loop needs
    μ = 0.2 and MuJoCo keeps grip: ``ok``, the risk said in the reason."""
    sat = saturation_verdict(DRISHTI, "roc", "paper", NOMINAL, _exp(0.1, friction=0.3),
                             simulate=True)
    assert sat.verdict == "ok" and sat.slip is None, sat.reason
    assert "rests on the loop's error" in sat.reason
    assert sat.friction_needed is not None and sat.friction_needed < 0.3


def test_a_low_floor_is_predicted_to_slip_on_the_tracked_path() -> None:
    sat = saturation_verdict(DRISHTI, "tdc", "paper", NOMINAL, _exp(0.1, friction=0.1))
    assert sat.verdict == "slips", sat.reason
    assert sat.slip is not None and not sat.slip.simulated and sat.grip_margin < 0
    assert "predicted" in sat.reason and "μ = 0.1" in sat.reason


def test_the_flagged_case_slips_on_the_engine_and_agrees() -> None:
    """The done-when case on MuJoCo (``runtime.stability.agreement``, the table of
    docs/MUJOCO.md): the verdict ``slips`` meets a wheel that slips on the engine."""
    from runtime.plant_comparison import engine_outcome
    from runtime.setting.robot import robot_setting
    from runtime.stability import agreement

    setting = robot_setting(None, None, Experiment())
    found = agreement.cases(setting.robot.code, setting.robot.nominal, setting.experiment,
                            lambda e, path, form, ctrl:
                            engine_outcome(setting, e, path, form, ctrl),
                            hs=(0.25,), frictions=(1.0,), only=[("tdroc", "paper")])
    assert len(found) == 1
    case = found[0]
    assert case.verdict == "slips" and case.outcome == "slips" and case.agrees, case
    assert "circle: slips from" in case.detail
    lines = agreement.markdown(found, {"tdroc": "TDROC"})
    assert "Agreement: **1 of 1** (100%)." in lines


def test_the_reproductions_tables_say_where_a_run_slips() -> None:
    """``wmr reproduce``'s metrics: a run whose μ needed (the slip monitor's) is above the
    experiment's floor is marked as slipping; one under it, or not monitored, is not."""
    from runtime.paper.reproduction_tables import fmt_mu

    assert fmt_mu(0.212, 0.1) == "**0.212 > μ: slips**"
    assert fmt_mu(0.212, 1.0) == fmt_mu(0.212) == "0.212"
    assert fmt_mu(float("nan"), 0.1) == "—"
