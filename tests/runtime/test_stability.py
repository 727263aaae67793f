"""The sampled-data stability analysis: its output, and its predictions against simulation.

Prediction: ``runtime.stability.analysis`` (linearised one-sample map). Simulation: TDROC
with k̂ held, bisected between stable and diverging closed-loop runs
(``runtime.stability.verification``).
Conditions: Drishti, h = 0.1 s, K1 = K2 = 4 I, Q = I, nominal plant without friction or
payload, the circle; each sensing model with its matched estimator, and encoder-average
with the plain backward quotient (the estimator that made the old reproduction unstable).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.bindings.robots import resolve
from runtime.commands import stability as stability_command
from runtime.experiment.settings import Experiment, SensingSettings
from runtime.sim import loop, paths
from runtime.stability import analysis as stability
from runtime.stability import verification
from runtime.stability.checks import check_configuration
from runtime.stability.sampled_loop import UnstableConfiguration, refusal

CODE = load_robot_code("")  # Drishti's, and every [lumped] robot's, generated code
DRISHTI = dict(CODE.params)
SMALL_ROBOT = Path(__file__).resolve().parents[1] / "robots" / "small_robot.toml"  # users' case
SMALL = {"m": 2.0, "I": 0.016654, "K": 0.136, "Iw": 5.4e-5, "r": 0.033, "b": 0.16, "d": 0.05}


def experiment(velocity: str, estimator: str = "matched") -> Experiment:
    return replace(
        Experiment(), sensing=SensingSettings(velocity=velocity, accel_estimator=estimator)
    )


CASES = [
    ("sample-instant", "matched", "paper"),
    ("encoder-average", "matched", "paper"),
    ("encoder-average", "backward", "paper"),
    ("motor-encoder", "matched", "paper"),
    ("encoder-average", "backward", "minimal"),
]


@pytest.mark.parametrize(("velocity", "estimator", "formulation"), CASES)
def test_prediction_matches_simulated_boundary(
    velocity: str, estimator: str, formulation: str
) -> None:
    """Predicted largest stable k̂/ε within 15 % of the simulated boundary."""
    exp = experiment(velocity, estimator)
    predicted = stability.pencil(
        stability.setting(CODE, "tdroc", formulation, DRISHTI, exp)
    ).max_stable_gain()
    assert 1.0 < predicted < 1e3
    sim = verification.simulated_boundary(CODE, formulation, DRISHTI, exp, predicted)
    assert abs(sim.estimate - predicted) <= 0.15 * sim.estimate, (predicted, sim)


def test_estimator_decides_the_boundary() -> None:
    """With averaged rates the plain backward quotient leaves a far smaller stable gain than
    the matched estimate: the cause of the old 'TDROC unstable at ε = 0.1'."""
    g = {
        est: stability.pencil(
            stability.setting(CODE, "tdroc", "paper", DRISHTI,
                              experiment("encoder-average", est))
        ).max_stable_gain()
        for est in ("matched", "backward")
    }
    assert g["backward"] < 0.25 * g["matched"]


def test_gain_pencil_is_affine() -> None:
    """J(g) = J0 + g J1 exactly: the Jacobian at g = 3 equals the pencil's."""
    s = stability.setting(CODE, "tdroc", "minimal", DRISHTI, experiment("encoder-average"))
    loop = stability.ClosedLoop(s)
    j0, j1, j3 = (loop.jacobian(g) for g in (0.0, 1.0, 3.0))
    assert np.max(np.abs(j3 - (j0 + 3.0 * (j1 - j0)))) < 1e-6 * np.max(np.abs(j3))


def test_jacobian_is_the_same_along_the_circle() -> None:
    """In the reference's heading frame the linearisation does not depend on the sample
    (the loop's own steady motion, at samples k and k + 1)."""
    loop = stability.ClosedLoop(
        stability.setting(CODE, "tdc", "paper", DRISHTI, experiment("sample-instant"))
    )
    a, b = loop.jacobian(0.0, 0), loop.jacobian(0.0, 1)
    ix = np.ix_(loop.pencil().states, loop.pencil().states)
    assert np.max(np.abs(a[ix] - b[ix])) < 1e-5 * np.max(np.abs(a[ix]))


def test_json_output_has_the_fixed_keys(capsys: pytest.CaptureFixture[str]) -> None:
    assert stability_command.main(["--json", "--no-measure", "--no-delay"]) == 0
    data = json.loads(capsys.readouterr().out)
    rows = data["controllers"]
    assert {(r["controller"], r["formulation"]) for r in rows} == {
        (c.name, f) for c in CODE.controller_infos if not refusal(c) for f in c.formulations
    }
    for r in rows:
        assert {
            "controller",
            "formulation",
            "sensing",
            "max_stable_gain",
            "spectral_radius",
            "stable",
        } <= set(r)
        assert r["stable"] == (r["spectral_radius"] < 1.0)


def test_cli_rejects_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        stability_command.main(["--sensing", "telepathy"])
    assert stability_command.main(["--robot", "/nonexistent/robot.toml"]) == 2
    assert "robot.toml" in capsys.readouterr().err


def test_small_robot_paper_formulation_is_predicted_unstable() -> None:
    """small_robot.toml: the paper formulation diverges before any switching gain (ρ > 1)
    under both sensing models; the minimal formulation is stable."""
    for velocity in ("sample-instant", "encoder-average"):
        exp = experiment(velocity)
        paper = stability.pencil(stability.setting(CODE, "tdc", "paper", SMALL, exp))
        minimal = stability.pencil(stability.setting(CODE, "tdc", "minimal", SMALL, exp))
        assert paper.radius(0.0) > 1.05
        assert minimal.radius(0.0) < 0.95


def small_experiment() -> Experiment:
    """The paper's setting scaled to a 2 kg robot: no 6 + 3 kg payload, 1 N m torque, a ±10 %
    uncertainty box (±30 % and ±20 % contain robots with m I ≤ K², which the TDE check
    rejects)."""
    exp = experiment("sample-instant")
    return replace(
        exp,
        controller=replace(exp.controller, tau_max=1.0, uncertainty=0.1),
        plant=replace(
            exp.plant, fixed_payload=0.0, extra_payload=0.0, viscous=0.001, coulomb=0.005
        ),
        paths=replace(exp.paths, circle_duration=30.0),
    )


def test_small_robot_is_refused_in_paper_form_and_tracks_in_minimal_form() -> None:
    exp = small_experiment()
    ref = paths.circle(CODE, SMALL, exp)

    def run(name: str, form: str, check: bool = True) -> loop.Run:
        if check:  # what a reproduction checks before it runs (runtime.reproduction.runs)
            check_configuration(CODE, name, form, SMALL, exp)
        return loop.run(CODE, name, form, ref, SMALL, exp)

    # Refused in the paper formulation: ROC/ASMC by the sampled-loop analysis; TDC/TDROC
    # already by the TDE condition over the box (α ≈ 12: m I − K² is small, so M̃ of (14)
    # is far more sensitive to the parameters than Drishti's).
    for name in ("roc", "asmc"):
        with pytest.raises(UnstableConfiguration, match="minimal formulation is predicted stable"):
            run(name, "paper")
    for name in ("tdc", "tdroc"):
        with pytest.raises(ValueError, match="TDE condition"):
            run(name, "paper")
    # What the refusal prevents: the same configuration, unchecked, diverges.
    forced = run("tdc", "paper", check=False)
    assert forced.failed_at is not None or float(forced.position_error.max()) > 0.2
    # Minimal formulation: TDC/TDROC track to millimetres (their TDE absorbs the friction);
    # ROC/ASMC, whose model has no friction (here 15 % of the torque), drift by centimetres
    # in pose (the minimal form does not feed pose back) but stay bounded.
    for name, rms_limit in (("tdc", 0.01), ("tdroc", 0.01), ("roc", 0.15), ("asmc", 0.15)):
        r = run(name, "minimal")
        assert r.failed_at is None
        assert float(np.sqrt(np.mean(r.position_error**2))) < rms_limit, name
        assert float(r.position_error.max()) < 0.15 < float(forced.position_error.max())


def test_small_robot_file_loads() -> None:
    setup = resolve(SMALL_ROBOT)
    rows = stability.analyse_all(setup.code, setup.nominal, experiment("sample-instant"),
                                 measure=False)
    verdict = {(r.controller, r.formulation): r.stable for r in rows}
    assert not verdict[("tdc", "paper")] and verdict[("tdc", "minimal")]
