"""The derived forms (14), the minimal form and the multipliers against the KKT system.

The reference is the saddle-point system of (9) together with the second derivative of the
constraints, [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − H; −Ȧ q̇], solved numerically with
np.linalg.solve. It uses only M, H, A and B of (9); everything else (S, Ṡη, M̃, H̃, the
minimal form, λ(q, q̇, η̇)) is compared with it at N_STATES random constraint-consistent
states (random q, random wheel rates η, q̇ = S(q) η) and random torques, for Drishti and
for randomly perturbed parameter sets (±30 %, I > (K² + K_lat²)/m kept).

All comparisons are norm-wise relative: ‖x − x_ref‖ ≤ RTOL ‖x_ref‖ with RTOL = 1e-12
(measured: below 2e-15 for every quantity).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import sympy as sp

from modeling.robot_file import load_robot
from modeling.robots.drishti import model as wmr

NumericWMR = Any  # tests/conftest.py: NumericWMR (lambdified model), via fixtures

RTOL = 1e-12
N_STATES = 100
N_PERTURBED = 3
SEED = 20170343


def drishti_params() -> np.ndarray:
    """(m, I, K, K_lat, I_w, r, b, d) of Drishti, from the packaged robot file."""
    p = load_robot().lumped
    return np.array([p["m"], p["I"], p["K"], 0.0, p["Iw"], p["r"], p["b"], p["d"]])


def perturbed_params(rng: np.random.Generator, lateral: bool) -> np.ndarray:
    """Drishti's parameters, each scaled by a factor in [0.7, 1.3]; with ``lateral`` a
    K_lat of up to ±0.05 m · m is added. Redrawn until the kinetic energy is positive
    definite (I > (K² + K_lat²)/m)."""
    base = drishti_params()
    while True:
        p = base * rng.uniform(0.7, 1.3, base.size)
        p[3] = rng.uniform(-0.05, 0.05) * p[0] if lateral else 0.0
        if p[1] > (p[2] ** 2 + p[3] ** 2) / p[0]:
            return p


def strong_coupling_params(lateral: bool) -> np.ndarray:
    """Drishti with K (and K_lat) so large that (K² + K_lat²)/m = I/2: the coupling terms
    of M, which Drishti's small K = 0.34 hardly exercises, are then of the order of I."""
    p = drishti_params()
    k2 = 0.5 * p[1] * p[0]
    p[2] = np.sqrt(k2 / 2) if lateral else np.sqrt(k2)
    p[3] = -np.sqrt(k2 / 2) if lateral else 0.0
    return p


def parameter_sets(lateral: bool) -> list[tuple[str, np.ndarray]]:
    rng = np.random.default_rng(SEED + int(lateral))
    sets = [("drishti", drishti_params())] if not lateral else []
    sets += [(f"perturbed{i}", perturbed_params(rng, lateral)) for i in range(N_PERTURBED)]
    sets.append(("strong-coupling", strong_coupling_params(lateral)))
    return sets


PAPER_SETS = parameter_sets(False)
LATERAL_SETS = parameter_sets(True)


def states(
    model: NumericWMR, p: np.ndarray, seed: int
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """(q, η, q̇ = S η, τ): positions in ±5 m, angles anywhere, wheel rates ±15 rad/s,
    torques ±10 N m."""
    rng = np.random.default_rng(seed)
    for _ in range(N_STATES):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi), rng.uniform(-50, 50, 2)]
        eta = rng.uniform(-15, 15, 2)
        qd = model.qdot_on_manifold(q, eta, p)
        tau = rng.uniform(-10, 10, 2)
        yield q, eta, qd, tau


def rel(x: np.ndarray, ref: np.ndarray) -> float:
    x, ref = np.ravel(x), np.ravel(ref)
    scale = np.linalg.norm(ref)
    assert scale > 0, "reference is exactly zero: the comparison would be vacuous"
    return float(np.linalg.norm(x - ref) / scale)


def ids(sets: list[tuple[str, np.ndarray]]) -> list[str]:
    return [name for name, _ in sets]


# ---------------------------------------------------------------------------------------
# (a)–(f) for the paper's model
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("p", [p for _, p in PAPER_SETS], ids=ids(PAPER_SETS))
def test_reduced_minimal_and_multipliers_match_kkt(paper_model: NumericWMR, p: np.ndarray) -> None:
    model = paper_model
    worst: dict[str, float] = dict.fromkeys(
        ("constraint", "a", "b", "c_eta", "c_full", "d", "e", "f"), 0.0
    )
    for q, _, qd, tau in states(model, p, seed=int(p[0] * 1e6)):
        a = model.A(q, p=p)
        # The state is on the constraint manifold (6)–(8).
        worst["constraint"] = max(
            worst["constraint"], float(np.linalg.norm(a @ qd) / np.linalg.norm(qd))
        )
        qdd_kkt, lam_kkt = model.kkt_solve(q, qd, tau, p)
        bt = (model.B(q, p=p) @ tau).ravel()

        # (a) (14) solved numerically.
        m_red = model.M_red(q, qd, p=p)
        qdd_14 = np.linalg.solve(m_red, bt - model.H_red(q, qd, p=p).ravel())
        worst["a"] = max(worst["a"], rel(qdd_14, qdd_kkt))

        # (b) the symbolic forward dynamics of (14).
        worst["b"] = max(worst["b"], rel(model.qdd_red(q, qd, tau=tau, p=p), qdd_kkt))

        # (c) the minimal form, and q̈ = S η̇ + Ṡ η.
        eta_dot = model.eta_dot(q, qd, tau=tau, p=p).ravel()
        worst["c_eta"] = max(worst["c_eta"], rel(eta_dot, qdd_kkt[3:]))
        qdd_min = model.S(q, p=p) @ eta_dot + model.Sdot_eta(q, qd, p=p).ravel()
        worst["c_full"] = max(worst["c_full"], rel(qdd_min, qdd_kkt))

        # (d) A S = 0, relative to |A| |S|.
        s = model.S(q, p=p)
        worst["d"] = max(
            worst["d"], float(np.linalg.norm(a @ s) / (np.linalg.norm(a) * np.linalg.norm(s)))
        )

        # (e) M̃⁻¹ M̃ = I.
        worst["e"] = max(
            worst["e"], float(np.linalg.norm(model.M_red_inv(q, qd, p=p) @ m_red - np.eye(5)))
        )

        # (f) λ(q, q̇, η̇, τ) with the KKT's η̇.
        qdd_arg = np.r_[0.0, 0.0, 0.0, qdd_kkt[3:]]
        lam = model.multipliers(q, qd, qdd_arg, tau, p)
        worst["f"] = max(worst["f"], rel(lam, lam_kkt))

    assert max(worst.values()) < RTOL, worst


def test_multipliers_read_only_wheel_accelerations(paper_model: NumericWMR) -> None:
    """λ(q, q̇, η̇) must read only η̇ = (θ̈_r, θ̈_l) of its qddot argument (the route of
    (10)–(12) takes q̈ = S η̇ + Ṡ η); garbage in the dependent slots changes nothing."""
    p = drishti_params()
    q, _, qd, tau = next(states(paper_model, p, seed=1))
    qdd_kkt, lam_kkt = paper_model.kkt_solve(q, qd, tau, p)
    junk = np.r_[1e3, -2e3, 5e2, qdd_kkt[3:]]
    assert rel(paper_model.multipliers(q, qd, junk, tau, p), lam_kkt) < RTOL


def test_kkt_reference_is_not_degenerate(paper_model: NumericWMR) -> None:
    """The KKT matrix is well conditioned at Drishti's parameters, so the 1e-12 agreement
    is meaningful, and the forces do something: λ ≠ 0, and τ changes q̈."""
    p = drishti_params()
    q, _, qd, tau = next(states(paper_model, p, seed=2))
    assert np.linalg.cond(paper_model.kkt_lhs(q, qd, p=p)) < 1e6
    qdd0, _ = paper_model.kkt_solve(q, qd, np.zeros(2), p)
    qdd1, lam1 = paper_model.kkt_solve(q, qd, tau, p)
    assert np.linalg.norm(lam1) > 1e-3
    assert np.linalg.norm(qdd1 - qdd0) > 1e-3 * np.linalg.norm(tau)


# ---------------------------------------------------------------------------------------
# (d) symbolically, and the (non-)symmetry of M̃
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("lateral", [False, True])
def test_null_space_annihilates_constraints_symbolically(lateral: bool) -> None:
    s = wmr.wmr_system(lateral)
    product = (s.constraint_matrix * s.null_space).applyfunc(sp.simplify)
    assert product == sp.zeros(3, 2)
    # and S has full column rank: its wheel-angle rows are the identity
    assert s.null_space[3:, :] == sp.eye(2)


def test_reduced_mass_matrix_is_not_symmetric(paper_model: NumericWMR) -> None:
    """The paper calls M̃ of (14) a mass matrix but never claims symmetry; the derivation
    shows it is not (its dependent rows are M_dd-weighted constraint rows)."""
    s = wmr.wmr_system()
    m_red = s.reduced_mass_matrix
    asym = (m_red - m_red.T).applyfunc(sp.simplify)
    assert asym != sp.zeros(5, 5)
    # The asymmetry survives at Drishti's numbers (not a symbolic artefact).
    p = drishti_params()
    q = np.array([0.3, -0.2, 0.7, 1.0, -1.0])
    mn = paper_model.M_red(q, p=p)
    assert np.linalg.norm(mn - mn.T) > 1e-2 * np.linalg.norm(mn)
    # ... whereas M of (9) and the minimal Sᵀ M S are symmetric.
    assert (s.mass_matrix - s.mass_matrix.T) == sp.zeros(5, 5)
    mm = s.minimal_mass_matrix
    assert (mm - mm.T).applyfunc(sp.simplify) == sp.zeros(2, 2)


# ---------------------------------------------------------------------------------------
# (g) the model with a lateral first moment K_lat
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("p", [p for _, p in LATERAL_SETS], ids=ids(LATERAL_SETS))
def test_lateral_moment_model_matches_kkt(lateral_model: NumericWMR, p: np.ndarray) -> None:
    model = lateral_model
    assert p[3] != 0.0
    worst: dict[str, float] = dict.fromkeys(("a", "b", "c_eta", "c_full", "f"), 0.0)
    for q, _, qd, tau in states(model, p, seed=int(p[0] * 1e6) + 7):
        qdd_kkt, lam_kkt = model.kkt_solve(q, qd, tau, p)
        bt = (model.B(q, p=p) @ tau).ravel()
        qdd_14 = np.linalg.solve(model.M_red(q, qd, p=p), bt - model.H_red(q, qd, p=p).ravel())
        worst["a"] = max(worst["a"], rel(qdd_14, qdd_kkt))
        worst["b"] = max(worst["b"], rel(model.qdd_red(q, qd, tau=tau, p=p), qdd_kkt))
        eta_dot = model.eta_dot(q, qd, tau=tau, p=p).ravel()
        worst["c_eta"] = max(worst["c_eta"], rel(eta_dot, qdd_kkt[3:]))
        qdd_min = model.S(q, p=p) @ eta_dot + model.Sdot_eta(q, qd, p=p).ravel()
        worst["c_full"] = max(worst["c_full"], rel(qdd_min, qdd_kkt))
        lam = model.multipliers(q, qd, np.r_[0.0, 0.0, 0.0, qdd_kkt[3:]], tau, p)
        worst["f"] = max(worst["f"], rel(lam, lam_kkt))
    assert max(worst.values()) < RTOL, worst


def test_lateral_moment_changes_the_dynamics(
    paper_model: NumericWMR, lateral_model: NumericWMR
) -> None:
    """K_lat is not silently dropped: with K_lat ≠ 0 the accelerations differ from the
    paper's model, and with K_lat = 0 the two models coincide."""
    p = LATERAL_SETS[0][1]
    q, _, qd, tau = next(states(lateral_model, p, seed=3))
    p0 = p.copy()
    p0[3] = 0.0
    qdd_lat, _ = lateral_model.kkt_solve(q, qd, tau, p)
    qdd_lat0, _ = lateral_model.kkt_solve(q, qd, tau, p0)
    qdd_paper, _ = paper_model.kkt_solve(q, qd, tau, p0)
    assert rel(qdd_lat0, qdd_paper) < RTOL
    assert rel(qdd_lat, qdd_paper) > 1e-6
