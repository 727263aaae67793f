"""The sampled-data verdict on any generated robot (issue 29): the tractor-trailer, the
tractor with two trailers, a robot with a swivel caster (tests/robots/caster_robot.toml,
derived here in about 4 s), with a delay, with the torque limit.

* every controller and formulation of the trailer reported, with the fixed keys;
* ROC refused on the two-trailer train, with its reason (α ≥ 1 over the ±30 % box);
* the prediction against the simulated boundary (TDROC with k̂ held, bisection;
  ``runtime.stability.verification``) within 15 % per sensing model, trailer and caster;
* the delay: zero delay is the loop without one, bit for bit; the largest tolerated delay
  the analysis predicts separates simulated runs that stay on the path from runs that
  diverge; an experiment that states too much delay is refused naming the fields;
* the saturation verdict: a torque limit below the paths' demand predicted ``saturates``
  and seen clipping in simulation; the default limits ``ok``.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from functools import cache
from pathlib import Path

import pytest

from runtime.bindings.generated import load_robot_code
from runtime.commands import stability as stability_command
from runtime.experiment.settings import Experiment, ExperimentFileError, parse_experiment
from runtime.setting.robot import robot_setting
from runtime.stability import analysis as stability
from runtime.stability import verification
from runtime.stability.sampled_loop import (
    ClosedLoop,
    max_delay,
    operating_rates,
    pencil,
    setting,
)
from runtime.stability.saturation import saturation_verdict

ROOT = Path(__file__).resolve().parents[2]
TRAILER = ROOT / "modeling" / "robots" / "trailer" / "trailer.toml"
CASTER = ROOT / "tests" / "robots" / "caster_robot.toml"
DRISHTI = load_robot_code("")
SENSING = ("sample-instant", "encoder-average", "motor-encoder")


@pytest.fixture(scope="module")
def caster_code(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The caster robot's generated code (``wmr model``, about 4 s)."""
    from runtime.cli import main as wmr

    out = tmp_path_factory.mktemp("caster")
    assert wmr(["model", "--robot", str(CASTER), "--out", str(out)]) == 0
    return out


@cache
def scaled(robot: str, generated: str | None, velocity: str) -> tuple:  # type: ignore[type-arg]
    base = Experiment()
    base = replace(base, sensing=replace(base.sensing, velocity=velocity))
    s = robot_setting(robot, Path(generated) if generated else None, base)
    return s.robot.code, s.robot.nominal, s.experiment


def test_trailer_reports_every_controller_and_formulation(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert stability_command.main(["--robot", str(TRAILER), "--json", "--no-measure", "--no-delay",
                           "--no-saturation"]) == 0
    data = json.loads(capsys.readouterr().out)
    code = load_robot_code("trailer")
    rows = data["controllers"]
    assert data["robot"] == "trailer"
    assert {(r["controller"], r["formulation"]) for r in rows} == {
        (c.name, f) for c in code.controller_infos for f in c.formulations}
    keys = set(stability.Analysis.__dataclass_fields__)
    for r in rows:
        assert set(r) == keys
        assert r["stable"] == (r["spectral_radius"] != "inf" and r["spectral_radius"] < 1.0)
        assert r["stable"] == (r["reason"] == "")
    tdc = next(r for r in rows if r["controller"] == "tdc")
    assert tdc["stable"] and tdc["max_stable_gain"] == "inf"  # no switching term: no g bound
    tdroc = next(r for r in rows if r["controller"] == "tdroc")
    assert tdroc["stable"] and 50 < tdroc["max_stable_gain"] < 200


def test_roc_refused_on_two_trailers_with_its_reason() -> None:
    code = load_robot_code("trailer2")
    a = stability.analyse(code, "roc", "minimal", dict(code.params), Experiment(),
                          measure=False)
    assert not a.stable and math.isnan(a.gain_at_setting)
    assert a.reason.startswith("refused: ROC needs alpha < 1") and "got 1.9" in a.reason
    assert "BAD_BOUNDS" in a.reason
    assert a.max_stable_gain > 0  # the loop itself is fine; the bounds do not exist


@pytest.mark.parametrize("velocity", SENSING)
@pytest.mark.parametrize("robot", ["trailer", "caster"])
def test_prediction_matches_simulated_boundary(robot: str, velocity: str,
                                               caster_code: Path) -> None:
    """Predicted largest stable k̂/ε within 15 % of the simulated boundary (measured: within
    2.1 % for both robots and every sensing model)."""
    path, gen = (str(TRAILER), None) if robot == "trailer" else (str(CASTER), str(caster_code))
    code, nominal, exp = scaled(path, gen, velocity)
    assert code.nq > 5  # a towed body or a caster: coordinates by odometry beyond the pose
    predicted = pencil(setting(code, "tdroc", "minimal", nominal, exp)).max_stable_gain()
    assert 1.0 < predicted < 1e3
    sim = verification.simulated_boundary(code, "minimal", nominal, exp, predicted,
                                          rel_tol=0.04)
    assert abs(sim.estimate - predicted) <= 0.15 * sim.estimate, (predicted, sim)


def test_zero_delay_is_the_loop_without_one() -> None:
    exp = Experiment()
    s = setting(DRISHTI, "tdc", "minimal", dict(DRISHTI.params), exp)
    loop = ClosedLoop(s)
    assert loop.dim == ClosedLoop(replace(s, delay=1e-14)).dim  # below rounding: none
    # A delay of a microsecond goes through the commands in flight and the split sample,
    # and moves the spectrum by no more than that.
    tiny = replace(s, delay=1e-6)
    assert ClosedLoop(tiny).dim == loop.dim + DRISHTI.nu
    assert pencil(tiny).radius(0.0) == pytest.approx(pencil(s).radius(0.0), abs=1e-4)
    delayed = replace(exp, controller=replace(exp.controller, delay=0.5))
    s_half = setting(DRISHTI, "tdc", "minimal", dict(DRISHTI.params), delayed)
    assert s_half.delay == pytest.approx(0.05)
    assert ClosedLoop(s_half).dim == loop.dim + DRISHTI.nu  # one command in flight
    assert pencil(s_half).radius(0.0) > pencil(s).radius(0.0)


def test_tolerated_delay_separates_simulated_runs() -> None:
    """TDC (TDROC with k̂ held at 0) on Drishti: stable at 0.85 × the predicted largest
    delay, diverging at 1.2 ×, in the closed loop that applies the delay."""
    code, nominal = DRISHTI, dict(DRISHTI.params)
    exp = Experiment()
    d_max = max_delay(setting(code, "tdc", "minimal", nominal, exp), 0.0)
    assert 0.02 < d_max < 0.2

    def unstable(fraction: float) -> bool:
        e = replace(exp, controller=replace(exp.controller, delay_time=fraction * d_max))
        return verification.simulated_unstable(code, 0.0, "minimal", nominal, e)

    assert not unstable(0.85)
    assert unstable(1.2)


def test_too_much_delay_is_refused_naming_the_fields() -> None:
    with pytest.raises(ExperimentFileError, match=r"'controller\.delay', 'delay_time', 'jitter'"):
        parse_experiment("[controller]\ndelay = 3.5\njitter = 1.0\n", "x.toml")
    with pytest.raises(ExperimentFileError, match=r"'controller\.jitter_time' must be non-neg"):
        parse_experiment("[controller]\njitter_time = -0.01\n", "x.toml")
    exp = parse_experiment("[controller]\ndelay = 0.25\njitter_time = 0.005\n", "x.toml")
    assert exp.controller.delay_seconds() == pytest.approx(0.025)
    assert exp.controller.jitter_seconds() == pytest.approx(0.005)


def test_saturation_predicted_and_simulated() -> None:
    code, nominal = DRISHTI, dict(DRISHTI.params)
    ok = saturation_verdict(code, "tdroc", "minimal", nominal, Experiment())
    assert ok.verdict == "ok" and 1.0 < ok.demand < 10.0
    low = Experiment()
    low = replace(low, controller=replace(low.controller, tau_max=0.5 * ok.demand),
                  paths=replace(low.paths, circle_duration=8.0, lawnmower_duration=8.0))
    sat = saturation_verdict(code, "tdc", "minimal", nominal, low, simulate=True)
    assert sat.verdict == "saturates" and "> τ_max" in sat.reason
    assert sat.simulated_saturated is not None and sat.simulated_saturated > 0
    between = replace(low, controller=replace(low.controller,
                                              tau_max=ok.demand + 0.5 * ok.switching))
    assert saturation_verdict(code, "tdroc", "minimal", nominal, between).verdict == "winds up"


def test_pi_neutral_modes_are_the_ones_it_cannot_see() -> None:
    """The PI reads the odometry pose and the wheel rates, never the wheel angles: the loop
    keeps eigenvalues at exactly 1 that no gain moves (two on Drishti: the odometry
    invariant ℓ and a shift of the angles it cannot see), dropped as neutral; the radius
    left is below 1 and there is no switching gain to bound."""
    pen = pencil(setting(DRISHTI, "pi", "minimal", dict(DRISHTI.params), Experiment()))
    assert pen.neutral == 2
    assert pen.radius(0.0) < 1.0 and pen.max_stable_gain() == math.inf


def test_one_verdict_in_every_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                      ) -> None:
    """The trailer, one short experiment: `wmr stability`, the verdict `wmr reproduce` writes
    (its REPORT.md section), the boundary a campaign draws and the verdict `wmr freeze`
    writes in its header are the same numbers."""
    from runtime.campaign.prediction import predict
    from runtime.cli import main as wmr
    from runtime.commands.campaign import resolve_campaign
    from runtime.reproduction.robot_report import sampled_data_table

    experiment = tmp_path / "short.toml"
    experiment.write_text("[paths]\ncircle_duration = 6.0\nlawnmower_duration = 6.0\n")
    assert wmr(["stability", "--robot", str(TRAILER), "--experiment", str(experiment),
                "--json", "--no-delay", "--no-saturation"]) == 0
    rows = {r["controller"]: r for r in json.loads(capsys.readouterr().out)["controllers"]}
    from runtime.experiment.settings import load_experiment

    s = robot_setting(str(TRAILER), None, load_experiment(experiment))
    code = s.robot.code
    # reproduce: the table it writes is the command's, row for row
    rebuilt = stability.table([stability.Analysis(**{
        k: (math.inf if v == "inf" else math.nan if v == "nan" else v) for k, v in r.items()})
        for r in rows.values()], code)
    assert sampled_data_table(s, "sample-instant") == rebuilt
    # campaign: TDROC's ε boundary at the experiment's ε is the command's ε_min
    spec = tmp_path / "c.toml"
    spec.write_text('duration = 6.0\ncontrollers = ["tdroc"]\n')
    c, tgt = resolve_campaign(spec, TRAILER, 1)
    c = replace(c, experiment=s.experiment)
    (boundary,) = predict(c, tgt).boundaries.values()
    section, _, key = c.map_y.partition(".")
    y = float(getattr(getattr(s.experiment, section), key))
    assert boundary.eps_at(y) == pytest.approx(rows["tdroc"]["eps_min"], rel=1e-9)
    # freeze: the header's verdict is the command's spectral radius
    out = tmp_path / "frozen"
    assert wmr(["freeze", "--controller", "tdc", "--robot", str(TRAILER), "--experiment",
                str(experiment), "--out", str(out)]) == 0
    header = next(out.glob("*_tdc_frozen.h")).read_text()
    assert f"spectral radius {rows['tdc']['spectral_radius']:.3f}" in header
    assert "tdc/minimal stable" in header


def test_lawnmower_is_analysed_at_its_leg_and_turns() -> None:
    """--path lawnmower: the straight leg and both U-turns, each a steady motion; the worst
    decides and is named."""
    code, nominal = DRISHTI, dict(DRISHTI.params)
    a = stability.analyse(code, "tdc", "minimal", nominal, Experiment(), measure=False,
                          path="lawnmower")
    assert a.operating_point in ("leg", "left turn", "right turn")
    radii = [pencil(setting(code, "tdc", "minimal", nominal, Experiment(), rates=r)).radius(0)
             for _, r in operating_rates(code, nominal, Experiment(), "lawnmower")]
    assert len(radii) == 3 and a.spectral_radius == max(radii)


def test_saturation_the_prediction_misses_is_reported_from_simulation() -> None:
    """The small robot's ROC (minimal): predicted ok along the tracked path, but its loop is
    linearly unstable (k/ε = 800 > 99), leaves the path and clips its torque: the run
    decides the verdict, and the reason says why the prediction missed it."""
    small = ROOT / "tests" / "robots" / "small_robot.toml"
    code, nominal, exp = scaled(str(small), None, "sample-instant")
    v = saturation_verdict(code, "roc", "minimal", nominal, exp, simulate=True)
    assert v.simulated_saturated is not None and v.simulated_saturated > 0
    assert v.verdict == "saturates (simulated)" and "see the linear verdict" in v.reason
