"""The sampled-loop spectrum (``runtime.stability.sampled_loop``, ``wmr stability``) checked by
another route, for Drishti and tests/robots/small_robot.toml.

What the analysis leaves out of the spectrum, and why (its docstrings):

* states nobody in the loop reads — the true pose (the controller sees odometry) and memory
  the configured estimator does not use: driven by the loop, never acting on it, "marginal
  by nature";
* ``Pencil.neutral``: eigenvalues at exactly 1 for every gain, a constant offset. In the
  paper formulation the loop reads the odometry pose and the encoder angles, and odometry
  ties them: its heading is the integral of r/b times the encoder difference, so
  ℓ(z) = θ_odo − (r/b)(φR_odo − φL_odo) never changes, whatever the law does. ℓ is a left
  eigenvector of the loop map at 1 for every gain: the neutral mode. The minimal
  formulation does not feed the pose back, so its loop has no such invariant.

The route here: the whole one-sample Jacobian at each gain (``ClosedLoop.jacobian(g)``, not
the pencil's J₀ + g J₁), the states that reach the torque found by powers of its sparsity
pattern, the neutral mode removed by restricting the map to ker ℓ (invariant, as ℓ is a left
eigenvector), and the eigenvalues of what remains computed with SciPy. Its largest modulus
must be the radius the analysis reports, and what the analysis drops must be ℓ's mode.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from numpy.typing import NDArray

from runtime.bindings.generated import load_robot_code
from runtime.commands import stability as stability_command
from runtime.experiment.settings import Experiment
from runtime.setting.robot import robot_setting
from runtime.stability import analysis as stability
from runtime.stability.sampled_loop import GAIN_CEILING

CODE = load_robot_code("")  # Drishti's, and the [lumped] small robot's, generated code
SMALL_ROBOT = Path(__file__).resolve().parents[1] / "robots" / "small_robot.toml"
TORQUE = ("law.tau[0]", "law.tau[1]")  # the generated controller's last torque (its state)
TRUE_POSE = ("plant_q[0]", "plant_q[1]", "plant_q[2]")
PLANT_MOTION = ("plant_q[3]", "plant_q[4]", "plant_eta[0]", "plant_eta[1]")
COMPARED = 0.5  # eigenvalues compared by modulus down to this (small ones are ill-posed)
Matrix = NDArray[np.float64]


@cache
def robot_and_experiment(name: str) -> tuple[dict[str, float], Experiment]:
    """The robot and the experiment ``wmr stability`` analyses it with."""
    if name == "drishti":
        return dict(CODE.params), Experiment()
    setting = robot_setting(SMALL_ROBOT, None, Experiment())
    return setting.robot.nominal, setting.experiment


SENSING = [("sample-instant", "matched"), ("encoder-average", "matched"),
           ("motor-encoder", "matched"), ("encoder-average", "central")]
# TDC and ROC: the analysis' two laws (time-delay estimate, nominal model); TDROC and
# ASMC share their loops.
CASES = [(r, c, f, v, e) for r in ("drishti", "small") for c in ("tdc", "roc")
         for f in ("paper", "minimal") for v, e in SENSING if c == "tdc" or e == "matched"]


def loop_setting(name: str, controller: str, formulation: str, velocity: str,
                 estimator: str | None = None) -> stability.LoopSetting:
    params, exp = robot_and_experiment(name)
    sensing = replace(exp.sensing, velocity=velocity,
                      accel_estimator=estimator or exp.sensing.accel_estimator)
    return stability.setting(CODE, controller, formulation, params,
                             replace(exp, sensing=sensing))


def reaches_torque(jac: Matrix, names: list[str]) -> list[int]:
    """States a change of which shows in the torque some samples later: columns of the
    torque rows of J, J², … (sparsity only: numbers a row ignores are exactly zero)."""
    dim = len(jac)
    acts = (np.abs(jac) > 1e-9 * np.abs(jac).max()).astype(int)
    seen = np.zeros(dim, dtype=bool)
    rows = np.zeros((len(TORQUE), dim), dtype=int)
    rows[np.arange(len(TORQUE)), [names.index(n) for n in TORQUE]] = 1
    for _ in range(dim):
        seen |= rows.any(axis=0)
        rows = np.minimum(rows @ acts, 1)
    seen[[names.index(n) for n in TORQUE]] = False  # an output: read by nobody
    return [int(i) for i in np.flatnonzero(seen)]


def odometry_invariant(states: list[int], params: dict[str, float], names: list[str]
                       ) -> NDArray[np.float64]:
    """ℓ over ``states``: θ_odo − (r/b)(φR_odo − φL_odo)."""
    coeff = {"odo_dependent[2]": 1.0, "odo_angles[0]": -params["r"] / params["b"],
             "odo_angles[1]": params["r"] / params["b"]}
    return np.array([coeff.get(names[i], 0.0) for i in states])


def remaining_eigenvalues(jac: Matrix, states: list[int], ell: Matrix | None
                          ) -> NDArray[np.complex128]:
    """Eigenvalues of the loop map on ``states``, restricted to ker ℓ (if ℓ is given)."""
    a = jac[np.ix_(states, states)]
    if ell is not None:
        basis = sla.null_space(ell[None, :])  # orthonormal, invariant under a
        a = basis.T @ a @ basis
    return np.asarray(sla.eigvals(a))


def independent_radius(loop: stability.ClosedLoop, params: dict[str, float], gain: float
                       ) -> float:
    """The spectral radius by this module's route, at ``gain``."""
    jac = loop.jacobian(gain)
    names = loop.layout.names()
    # A state held constant while linearised (ASMC's adapted gain, γ = 0: its row is its
    # own unit vector) is eigenvalue 1 by construction; the residual s of the operating
    # point (1e-8) lets it touch the torque. Left out here, as the analysis' neutral count.
    held = {i for i in range(len(jac)) if np.abs(jac[i] - np.eye(len(jac))[i]).max() < 1e-9
            and names[i].startswith("law.")}
    states = [i for i in reaches_torque(jac, names) if i not in held]
    # The paper formulation and the PI read the odometry pose: ℓ is conserved there.
    reads_pose = loop.s.formulation == "paper" or loop.s.controller == "pi"
    ell = odometry_invariant(states, params, names) if reads_pose else None
    return float(np.abs(remaining_eigenvalues(jac, states, ell)).max())


def largest_moduli(eigs: NDArray[np.complex128], n: int) -> NDArray[np.float64]:
    return np.sort(np.abs(eigs))[::-1][:n]


@pytest.mark.parametrize(("name", "controller", "formulation", "velocity", "estimator"), CASES)
def test_spectral_radius_by_another_route(name: str, controller: str, formulation: str,
                                          velocity: str, estimator: str) -> None:
    s = loop_setting(name, controller, formulation, velocity, estimator)
    params, _ = robot_and_experiment(name)
    pen = stability.pencil(s)
    loop = stability.ClosedLoop(s)
    g_max = pen.max_stable_gain()
    gains = [0.0, 3.0] + ([0.9 * g_max] if 0 < g_max < math.inf else [])
    for g in gains:
        jac = loop.jacobian(g)
        all_names = loop.layout.names()
        states = reaches_torque(jac, all_names)
        assert states == list(pen.states), g
        names = {all_names[i] for i in states}
        assert not names & set(TRUE_POSE) and set(PLANT_MOTION) <= names
        # Left out: only modes that neither grow nor decay (integrated pose, held memory)
        # or vanish (shifted memory).
        out = [i for i in range(len(jac)) if i not in states]
        left_out = np.abs(sla.eigvals(jac[np.ix_(out, out)]))
        assert np.all((left_out < 1e-3) | (np.abs(left_out - 1) < 1e-8)), left_out
        ell = (odometry_invariant(states, params, all_names) if formulation == "paper"
               else None)
        if ell is None:
            assert "odo_dependent[2]" not in names  # minimal: the pose is not fed back
        else:
            a = jac[np.ix_(states, states)]
            assert np.abs(ell @ a - ell).max() < 1e-8, g  # ℓ is conserved at every gain
        mine = remaining_eigenvalues(jac, states, ell)
        theirs = pen.eigenvalues(g)
        # Same count, same radius, and at moderate gains the same largest moduli (the
        # pencil's J0 + g J1 and the Jacobian at g differ by finite-difference noise, which
        # g multiplies and close pairs amplify).
        assert len(mine) == len(theirs), g
        if g <= 3.0:
            n = int(np.count_nonzero(np.abs(theirs) > COMPARED))
            np.testing.assert_allclose(largest_moduli(mine, n), largest_moduli(theirs, n),
                                       rtol=1e-4)
        assert pen.radius(g) == pytest.approx(float(np.abs(mine).max()), rel=1e-5), g


@pytest.mark.parametrize(("name", "controller", "formulation", "velocity", "estimator"), CASES)
def test_neutral_mode_is_the_odometry_invariant(name: str, controller: str, formulation: str,
                                                velocity: str, estimator: str) -> None:
    """The eigenvalue the analysis drops, shown by its eigenvectors: in the paper
    formulation one, at 1, whose left eigenvector is ℓ and whose right eigenvector is an
    offset the plant and the law do not act on (no wheel rate, no torque); ℓ is orthogonal to
    every kept mode. The minimal formulation drops nothing."""
    s = loop_setting(name, controller, formulation, velocity, estimator)
    params, _ = robot_and_experiment(name)
    pen = stability.pencil(s)
    states = list(pen.states)
    assert pen.neutral == (1 if formulation == "paper" else 0)
    for g in (0.0, 3.0, 30.0):
        eigs, right = sla.eig(pen.j0 + g * pen.j1)
        kept = list(pen.eigenvalues(g))
        dropped = []
        for i, lam in enumerate(eigs):  # match each eigenvalue to one the analysis kept
            j = int(np.argmin(np.abs(np.array(kept) - lam))) if kept else -1
            if kept and abs(kept[j] - lam) < 1e-9 * max(1.0, abs(lam)):
                kept.pop(j)
            else:
                dropped.append(i)
        assert not kept and len(dropped) == pen.neutral, g
        if formulation == "minimal":
            assert np.abs(eigs - 1).min() > 1e-3  # nothing near 1 either
            continue
        ell = odometry_invariant(list(range(len(states))), params, list(pen.names))
        (i,) = dropped
        assert abs(eigs[i] - 1) < 1e-8, eigs[i]
        v = right[:, i] / right[np.argmax(np.abs(right[:, i])), i]
        at = dict(zip(pen.names, v, strict=True))
        assert max(abs(at[n]) for n in ("plant_eta[0]", "plant_eta[1]",
                                        "law.u_prev[3]", "law.u_prev[4]") if n in at) < 1e-5
        assert abs(ell @ v) > 1e-3
        others = np.delete(right, i, axis=1)
        others = others / np.abs(others).max(axis=0)
        assert np.abs(ell @ others).max() < 1e-5


@pytest.mark.parametrize("name", ["drishti", "small"])
def test_wmr_stability_report_by_another_route(name: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """Each row of ``wmr stability --json --no-measure``: the spectral radius at the
    setting's gain, and the largest stable gain where the radius computed here crosses 1."""
    argv = ["--json", "--no-measure", "--no-delay"] + (
        ["--robot", str(SMALL_ROBOT)] if name == "small" else [])
    assert stability_command.main(argv) == 0
    rows = json.loads(capsys.readouterr().out)["controllers"]
    params, _ = robot_and_experiment(name)
    assert len(rows) == 9  # four laws of (18) in two formulations, the PI in one
    for row in rows:
        if row["controller"] == "pi":
            # The PI never reads the wheel angles: a shift of each wheel's true and odometric
            # angle together is neutral too, beyond ℓ; its radius is checked in
            # tests/runtime/test_stability_any_robot.py against the neutral count instead.
            continue
        loop = stability.ClosedLoop(loop_setting(name, row["controller"], row["formulation"],
                                                 row["sensing"]))
        where = (row["controller"], row["formulation"])
        if row["gain_at_setting"] == "nan":  # ROC has no gain there: no configuration
            assert row["spectral_radius"] == "inf" and row["controller"] == "roc", where
            assert not row["stable"]
        else:
            radius = independent_radius(loop, params, row["gain_at_setting"])
            assert row["spectral_radius"] == pytest.approx(radius, rel=1e-5), where
            assert row["stable"] == (radius < 1.0)
        g_max = row["max_stable_gain"]
        if g_max == 0:
            assert independent_radius(loop, params, 0.0) >= 1.0, where
        elif g_max == "inf":
            assert independent_radius(loop, params, GAIN_CEILING) < 1.0, where
        else:
            assert independent_radius(loop, params, 0.999 * g_max) < 1.0, where
            assert independent_radius(loop, params, 1.001 * g_max) >= 1.0, where
    if name == "small":  # the case the file was added for: paper form unstable, minimal not
        verdict = {(r["controller"], r["formulation"]): r["stable"] for r in rows}
        assert not verdict[("tdc", "paper")] and verdict[("tdc", "minimal")]
