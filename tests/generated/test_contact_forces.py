"""The generated wheel contact forces (``<prefix>_wheel_contact_forces``, from the multipliers
of (9); ``codegen.contact_forces``), for Drishti, the trailer (staged forms) and the small
robot (a ``[lumped]`` file):

* C (double), NumPy and CasADi agree at random states (measured: 1e-15 relative);
* they are the multipliers of a numeric KKT solve of (9) with A q̈ + Ȧ q̇ = 0, row by row,
  in newtons with the stated signs (F_x = s λ, F_y = −s λ);
* the longitudinal forces are the independent route F = (τ − J θ̈)/r of the wheel's own
  row (θ̈ from the generated minimal forward dynamics);
* bad input returns the contract's statuses (non-finite input, bad parameters) in C and
  raises in Python, naming the status;
* ``<prefix>_traction_check`` (the firmware's optional check after a step, on the forces
  ``wheel_contact_forces`` wrote) returns OK and the margins μ N − √(F_x² + (s F_y)²) where
  every wheel keeps grip, ``<P>_WARN_TRACTION``
  (2, writing nothing) where one does not, in C and Python alike, at the slip monitor's
  loads and shares; ``<prefix>_traction_margins`` writes the margins whatever their sign.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from codegen.contact_forces import contact_rows
from modeling.robot_file import load_robot_model
from runtime.bindings.robots import resolve
from runtime.sim.plant import spin_inertia_keys
from runtime.tooling.crosscheck import generated_functions as gf
from runtime.tooling.crosscheck.bindings import CModel
from runtime.tooling.crosscheck.targets import Target, target_of

ROOT = Path(__file__).resolve().parents[2]
ROBOTS = {
    "drishti": ROOT / "modeling" / "robots" / "drishti" / "drishti.toml",
    "trailer": ROOT / "modeling" / "robots" / "trailer" / "trailer.toml",
    "small_robot": ROOT / "tests" / "robots" / "small_robot.toml",
}
NAME = "wheel_contact_forces"


def _target(name: str) -> Target:
    return target_of(resolve(ROBOTS[name]).code.folder)


def _function(target: Target) -> gf.Function:
    return next(f for f in gf.functions(target) if f.name == NAME)


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_c_python_and_casadi_agree(name: str) -> None:
    """At the robot's own parameters (a lumped file runs the paper's generated code with its
    numbers: the small robot is 2 kg, r = 33 mm), each ±10 %, random states and torques
    (measured: 1e-15 of the largest force)."""
    setup = resolve(ROBOTS[name])
    target = _target(name)
    fn = _function(target)
    assert [a.name for a in fn.outputs] == ["longitudinal", "lateral"]
    cm = CModel(target, False)
    rng = np.random.default_rng(5)
    worst = {"c64": 0.0, "casadi": 0.0}
    for _ in range(40):
        p = {k: v * rng.uniform(0.9, 1.1) for k, v in setup.nominal.items()}
        q = rng.uniform(-3.0, 3.0, target.code.nq)
        values = {"p": p, "q": q, "wheel_rates": rng.uniform(-8.0, 8.0, target.code.nu),
                  "tau": rng.uniform(-5.0, 5.0, target.code.nu)}
        ref = np.concatenate(gf._python(fn, values))
        assert np.all(np.isfinite(ref)) and np.max(np.abs(ref)) > 0.1
        for impl, got in (("c64", gf._c(cm, fn, values)),
                          ("casadi", gf._casadi(target, fn, values))):
            err = np.max(np.abs(np.concatenate(got) - ref)) / np.max(np.abs(ref))
            worst[impl] = max(worst[impl], float(err))
    assert max(worst.values()) < 1e-10, worst


def _kkt(name: str) -> tuple[Any, Any, Any, Any]:
    """Numeric M, H, A, Ȧq̇ of the robot's model (its own symbolic system, lambdified)."""
    model, _ = load_robot_model(None if name == "drishti" else ROBOTS[name])
    s = model.system
    syms = [*s.q, *s.qdot, *(p.symbol for p in model.params)]
    return (model, *(sp.lambdify(syms, e, "numpy") for e in (
        s.mass_matrix, s.bias, s.constraint_matrix, s.constraint_rate_term)))


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_the_forces_are_the_kkt_multipliers_and_the_wheel_row(name: str) -> None:
    """λ of [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇] in newtons (rolling rows: s λ,
    no-side-slip rows: −s λ, s = 1 for these rows), and F = (τ − J θ̈)/r per driven wheel."""
    setup = resolve(ROBOTS[name])
    code = setup.code
    model, m_f, h_f, a_f, adot_f = _kkt(name)
    rows = contact_rows(model)
    keys = spin_inertia_keys(code)
    assert keys is not None
    rng = np.random.default_rng(11)
    for _ in range(10):
        p = {k: v * rng.uniform(0.9, 1.1) for k, v in setup.nominal.items()}
        q = rng.uniform(-2.0, 2.0, code.nq)
        eta = rng.uniform(-6.0, 6.0, code.nu)
        tau = rng.uniform(-20.0, 20.0, code.nu)
        qdot = code.velocities(q, eta, p)
        args = [*q, *qdot, *(p[k.key] for k in model.params)]
        mm, hh, aa = (np.asarray(f(*args), dtype=np.float64) for f in (m_f, h_f, a_f))
        rate = np.asarray(adot_f(*args), dtype=np.float64).ravel()
        n, k = code.nq, aa.shape[0]
        bt = np.zeros(n)
        bt[list(code.actuated)] = tau
        lhs = np.block([[mm, aa.T], [aa, np.zeros((k, k))]])
        lam = np.linalg.solve(lhs, np.concatenate([bt - hh.ravel(), -rate]))[n:]
        fx, fy = (np.asarray(o, dtype=np.float64) for o in
                  code.model.wheel_contact_forces(q, eta, tau, p))
        scale = np.max(np.abs(lam))
        assert np.allclose(fx, lam[list(rows.rolling)], atol=1e-9 * scale), (fx, lam)
        assert np.allclose(fy, -lam[list(rows.lateral)], atol=1e-9 * scale), (fy, lam)
        # The wheel's own row: J θ̈ = τ − r F.
        accel = np.asarray(code.model.minimal_forward_dynamics(q, eta, tau, p), dtype=np.float64)
        radii = np.array([p["r"] if "r" in p else p[f"radius_{w}"] for w in rows.driven])
        spin = np.array([p[key] for key in keys])
        assert np.allclose(fx, (tau - spin * accel) / radii, rtol=1e-9, atol=1e-9), fx


def test_the_rows_are_the_wheels_and_axles() -> None:
    model, _ = load_robot_model(ROBOTS["trailer"])
    rows = contact_rows(model)
    assert rows.driven == ("right", "left")
    assert rows.lateral_wheels == (("right", "left"), ("cart_right", "cart_left"))
    drishti, _ = load_robot_model(None)
    assert contact_rows(drishti).lateral_wheels == (("right", "left"),)


@pytest.mark.parametrize("name", ["drishti", "trailer"])
def test_bad_input_returns_its_status(name: str) -> None:
    target = _target(name)
    fn = _function(target)
    cm = CModel(target, False)
    prefix = target.prefix.upper()
    header = (target.c_dir / f"{target.prefix}_types.h").read_text()
    statuses = {n: int(v) for n, v in re.findall(r"(\w+_ERR_\w+) = (-?\d+)", header)}
    sample = gf.random_samples(target, np.random.default_rng(3), 1)[0]
    good = gf._inputs(target, fn, sample, "ref", {}, False)
    radius = next(k for k in target.code.params if k == "r" or k.startswith("radius_"))
    inertia = next(k for k in target.code.params if k in ("Iw",) or k.startswith("J_theta_"))
    cases = [("q", {**good, "q": np.where(np.arange(target.code.nq) == 2, math.nan,
                                           good["q"])}, "ERR_NONFINITE_INPUT"),
             ("tau", {**good, "tau": np.array([math.inf, *good["tau"][1:]])},
              "ERR_NONFINITE_INPUT"),
             ("p", {**good, "p": {**good["p"], radius: 0.0}}, "ERR_BAD_PARAMS"),
             ("p", {**good, "p": {**good["p"], inertia: -100.0 * abs(good["p"][inertia])}},
              "ERR_BAD_PARAMS")]
    for what, values, status in cases:
        with pytest.raises(RuntimeError,
                           match=f"returned {statuses[f'{prefix}_{status}']}$") as err:
            gf._c(cm, fn, values)
        with pytest.raises(ValueError, match=f"{prefix}_{status}"):
            gf._python(fn, values)
        assert what, err


@pytest.mark.parametrize("name", ["drishti", "trailer"])
def test_the_traction_check_warns_where_a_wheel_slips(name: str) -> None:
    import dataclasses

    from runtime.experiment.settings import parse_experiment
    from runtime.setting.layout import robot_layout
    from runtime.sim.slip_monitor import SlipMonitor

    target = _target(name)
    code = target.code
    fns = {f.name: f for f in gf.functions(target)}
    cm = CModel(target, False)
    header = (target.c_dir / f"{target.prefix}_types.h").read_text()
    statuses = {n: int(v) for n, v in re.findall(r"(\w+_(?:ERR|WARN)_\w+) = (-?\d+)", header)}
    prefix = target.prefix.upper()
    exp = parse_experiment("")
    exp = dataclasses.replace(exp, plant=dataclasses.replace(exp.plant, viscous=0.0,
                                                             coulomb=0.0))
    monitor = SlipMonitor(code, robot_layout(code, code.plant_defaults), exp)
    masses = np.zeros(2)
    loads = monitor.normal_loads(masses)
    shares = monitor.shares(masses)
    rng = np.random.default_rng(17)
    warned = ok = 0
    for _ in range(30):
        q = rng.uniform(-2.0, 2.0, code.nq)
        eta = rng.uniform(-8.0, 8.0, code.nu)
        tau = rng.uniform(-10.0, 10.0, code.nu)
        fx, fy = monitor.contact_forces(q, eta, tau, code.params, masses)
        needed = float(np.max(np.hypot(fx, fy) / loads))
        longitudinal, lateral = code.model.wheel_contact_forces(q, eta, tau, code.params)
        for mu in (1.05 * needed, 0.95 * needed):
            values = {"longitudinal": np.asarray(longitudinal),
                      "lateral": np.asarray(lateral), "mu": np.array([mu]), "loads": loads,
                      "shares": shares}
            expected = mu * loads - np.hypot(fx, fy)
            margins = gf._c(cm, fns["traction_margins"], values)[0]
            assert np.allclose(margins, expected, rtol=1e-9, atol=1e-9)
            assert np.allclose(gf._python(fns["traction_margins"], values)[0], expected,
                               rtol=1e-9, atol=1e-9)
            if np.all(expected > 0):
                ok += 1
                assert np.allclose(gf._c(cm, fns["traction_check"], values)[0], expected,
                                   rtol=1e-9, atol=1e-9)
                assert np.allclose(gf._python(fns["traction_check"], values)[0], expected,
                                   rtol=1e-9, atol=1e-9)
            else:
                warned += 1
                warn = statuses[f"{prefix}_WARN_TRACTION"]
                assert warn > 0
                with pytest.raises(RuntimeError, match=f"returned {warn}$"):
                    gf._c(cm, fns["traction_check"], values)
                with pytest.raises(ValueError, match=f"{prefix}_WARN_TRACTION"):
                    gf._python(fns["traction_check"], values)
    assert ok == 30 and warned == 30
    # Bad input of the check: its own status, or the contract's.
    good = {"longitudinal": np.asarray(longitudinal), "lateral": np.asarray(lateral),
            "mu": np.array([1.0]), "loads": loads, "shares": shares}
    for change, status in (({"mu": np.array([0.0])}, "ERR_BAD_TRACTION"),
                           ({"loads": -loads}, "ERR_BAD_TRACTION"),
                           ({"mu": np.array([math.nan])}, "ERR_NONFINITE_INPUT"),
                           ({"lateral": np.full(len(lateral), math.inf)},
                            "ERR_NONFINITE_INPUT")):
        for fn in ("traction_margins", "traction_check"):
            with pytest.raises(RuntimeError, match=f"returned {statuses[f'{prefix}_{status}']}$"):
                gf._c(cm, fns[fn], {**good, **change})
            with pytest.raises(ValueError, match=f"{prefix}_{status}"):
                gf._python(fns[fn], {**good, **change})
