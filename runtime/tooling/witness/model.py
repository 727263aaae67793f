"""The WMR model of Roy et al. (2017), typed by hand from the paper in NumPy.

Independent of ``modeling/``, ``codegen/`` and ``generated/`` on purpose: nothing is
imported from them and no expression is copied from them. Every function is typed from
the paper's printed equations, with the minus signs that the text extraction lost put
back (docs/PAPER.md item 1) and with the corrections listed below, each of which I
re-derived by hand before typing it (the derivation is in the docstrings;
``runtime.tooling.crosscheck`` also checks it numerically, e.g. that A(q) S(q) = 0 and that
(14) is (9) on the manifold).

Coordinates q = (x_c, y_c, θ, θ_r, θ_l), wheel rates η = (θ̇_r, θ̇_l), parameters a dict
with keys m, I, K, Iw, r, b, d (the paper's lumped parameters; K is the first moment of
mass behind C, as the sign of K in (1)–(3) implies).

Deviations from the printed text (beyond restoring lost minus signs):

* (31): the printed kinematic matrix has r/b·(b cos θ ∓ d sin θ) in row 1 and
  r/b·(b sin θ ± d cos θ) in row 2. From (7) + (8), ẋ cos θ + ẏ sin θ = r(θ̇_r + θ̇_l)/2:
  each wheel contributes r/2 (not r) to the forward speed, so b must read b/2 there.
  ``kinematics_31`` uses b/2; ``kinematics_31_as_printed`` keeps the printed b, for
  comparison only.
* (14): the printed M is not symmetric, and it must not be: with the signs restored by
  the derivation (see ``mass_matrix_14``) M14(4,1) = −k1, M14(4,2) = −k3, M14(5,1) = −k2,
  M14(5,2) = −k4, M14(3,4) = −k5, M14(4,3) = +k5, M14(5,3) = −k5, while the upper-right
  block holds +k1..+k4.
* (4) prints λ3 where λ2 belongs (the right wheel rolls by (7), whose multiplier is λ2).
  It enters here only through the derivation of (14), which uses the corrected (4).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

Params = Mapping[str, float]
Vec = NDArray[np.float64]
Mat = NDArray[np.float64]

#: Drishti, as printed in the paper ("Experimental results and comparison").
DRISHTI: dict[str, float] = {
    "m": 36.0,
    "I": 5.72,
    "K": 0.34,
    "Iw": 0.07,
    "r": 0.096,
    "b": 0.414,
    "d": 0.12,
}
PARAM_KEYS = ("m", "I", "K", "Iw", "r", "b", "d")


def _params(p: Params) -> tuple[float, float, float, float, float, float, float]:
    return (
        float(p["m"]),
        float(p["I"]),
        float(p["K"]),
        float(p["Iw"]),
        float(p["r"]),
        float(p["b"]),
        float(p["d"]),
    )


def _vec(x: ArrayLike, n: int) -> Vec:
    v = np.asarray(x, dtype=np.float64).reshape(-1)
    if v.size != n:
        raise ValueError(f"expected {n} values, got {v.size}")
    return v


# --------------------------------------------------------------------------- (9), (6)–(8)


def mass_matrix_9(q: ArrayLike, p: Params) -> Mat:
    """M(q) of (9): the kinetic-energy matrix of (1)–(5), symmetric.

    Row 2, column 3 is −K cos θ (the extraction lost the minus; (2) has −K θ̈ cos θ).
    """
    m, I, K, Iw, _, _, _ = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    return np.array(
        [
            [m, 0.0, K * s, 0.0, 0.0],
            [0.0, m, -K * c, 0.0, 0.0],
            [K * s, -K * c, I, 0.0, 0.0],
            [0.0, 0.0, 0.0, Iw, 0.0],
            [0.0, 0.0, 0.0, 0.0, Iw],
        ]
    )


def bias_9(q: ArrayLike, qdot: ArrayLike, p: Params) -> Vec:
    """H(q, q̇) of (9): (K θ̇² cos θ, K θ̇² sin θ, 0, 0, 0), the θ̇² terms of (1)–(2)."""
    K = float(p["K"])
    th = _vec(q, 5)[2]
    thd = _vec(qdot, 5)[2]
    return np.array([K * thd**2 * math.cos(th), K * thd**2 * math.sin(th), 0.0, 0.0, 0.0])


def input_matrix_9() -> Mat:
    """B of (9): the torques act on the wheel coordinates only."""
    return np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


def constraint_matrix(q: ArrayLike, p: Params) -> Mat:
    """A(q) of (9), A(q) q̇ = 0 being (6)–(8) with their minus signs restored:

    (6) ẏ cos θ − ẋ sin θ − d θ̇ = 0                 (no side slip of the axle)
    (7) −(ẋ cos θ + ẏ sin θ + (b/2) θ̇ − r θ̇_r) = 0  (right wheel rolls)
    (8) −(ẋ cos θ + ẏ sin θ − (b/2) θ̇ − r θ̇_l) = 0  (left wheel rolls)
    Rows 2 and 3 carry the overall sign of the printed A of (9).
    """
    _, _, _, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    return np.array(
        [
            [-s, c, -d, 0.0, 0.0],
            [-c, -s, -b / 2.0, r, 0.0],
            [-c, -s, b / 2.0, 0.0, r],
        ]
    )


# --------------------------------------------------------------------------- (13), (31)


def null_space(q: ArrayLike, p: Params) -> Mat:
    """S(q) (5×2), q̇ = S(q) η: rows 1–3 are (31) (corrected, b/2), rows 4–5 identity.

    From (7) − (8): θ̇ = r(θ̇_r − θ̇_l)/b, which is (13); from (7) + (8): the forward speed
    v = ẋ cos θ + ẏ sin θ = r(θ̇_r + θ̇_l)/2; (6): the lateral speed of C is d θ̇. Hence
    ẋ = v cos θ − d θ̇ sin θ, ẏ = v sin θ + d θ̇ cos θ.
    """
    _, _, _, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    # (31) with b/2 in place of the printed b in the cos θ (row 1) and sin θ (row 2) terms.
    return np.array(
        [
            [r / b * (b / 2.0 * c - d * s), r / b * (b / 2.0 * c + d * s)],
            [r / b * (b / 2.0 * s + d * c), r / b * (b / 2.0 * s - d * c)],
            [r / b, -r / b],
            [1.0, 0.0],
            [0.0, 1.0],
        ]
    )


def kinematics_31(q: ArrayLike, wheel_rates: ArrayLike, p: Params) -> Vec:
    """(31): (ẋ_c, ẏ_c, θ̇) from (θ̇_r, θ̇_l), with b/2 where the paper prints b (erratum;
    see ``null_space`` for the derivation from (6)–(8) and (13))."""
    return null_space(q, p)[:3] @ _vec(wheel_rates, 2)


def kinematics_31_as_printed(q: ArrayLike, wheel_rates: ArrayLike, p: Params) -> Vec:
    """(31) exactly as printed (signs restored, b kept): violates (7)–(8); reference only."""
    _, _, _, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    sd = np.array(
        [
            [r / b * (b * c - d * s), r / b * (b * c + d * s)],
            [r / b * (b * s + d * c), r / b * (b * s - d * c)],
            [r / b, -r / b],
        ]
    )
    return sd @ _vec(wheel_rates, 2)


def null_space_rate_times_eta(q: ArrayLike, wheel_rates: ArrayLike, p: Params) -> Vec:
    """Ṡ(q, q̇) η: the velocity part of q̈ = S η̇ + Ṡ η (differentiate ``null_space`` at
    fixed η): ẍ ∋ −v θ̇ sin θ − d θ̇² cos θ, ÿ ∋ v θ̇ cos θ − d θ̇² sin θ, zero for θ, θ_r, θ_l.
    """
    _, _, _, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    wr, wl = _vec(wheel_rates, 2)
    v = r * (wr + wl) / 2.0
    thd = r * (wr - wl) / b  # (13)
    s, c = math.sin(th), math.cos(th)
    return np.array([-v * thd * s - d * thd**2 * c, v * thd * c - d * thd**2 * s, 0.0, 0.0, 0.0])


def qdot_on_manifold(q: ArrayLike, wheel_rates: ArrayLike, p: Params) -> Vec:
    """q̇ = S(q) η: the full velocity consistent with (6)–(8)."""
    return null_space(q, p) @ _vec(wheel_rates, 2)


# --------------------------------------------------------------------------- (14)


def coupling_k(q: ArrayLike, p: Params) -> tuple[float, float, float, float, float]:
    """k1..k5 printed under (14), minus signs restored:

    k1 = (m d r − K r)/b sin θ − m r/2 cos θ,   k2 = (K r − m d r)/b sin θ − m r/2 cos θ,
    k3 = (K r − m d r)/b cos θ − m r/2 sin θ,   k4 = (m d r − K r)/b cos θ − m r/2 sin θ,
    k5 = r (I − K d)/b.
    """
    m, I, K, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    k1 = (m * d * r - K * r) / b * s - m * r / 2.0 * c
    k2 = (K * r - m * d * r) / b * s - m * r / 2.0 * c
    k3 = (K * r - m * d * r) / b * c - m * r / 2.0 * s
    k4 = (m * d * r - K * r) / b * c - m * r / 2.0 * s
    k5 = r * (I - K * d) / b
    return k1, k2, k3, k4, k5


def mass_matrix_14(q: ArrayLike, p: Params) -> Mat:
    """M(q) of (14), typed from the printed matrix with the signs the derivation gives.

    Derivation (mine, from (1)–(9)): rows 1–3 of (9) are M_a q̈_a + H_a = −A_aᵀ λ
    (a = the pose block, A_a = first three columns of A). Solving them for λ on the
    manifold (q̈_a = S_a η̇ + Ṡ_a η) gives (10)–(12), and substituting back yields
    M_a q̈_a − M_a S_a η̇ − M_a Ṡ_a η = 0: the upper-right block is −M_a S_a. Rows 4–5
    (with (4) corrected to carry λ2) are I_w η̇ + r (λ2, λ3) = τ with λ = −A_a⁻ᵀ(M_a q̈_a + H_a);
    since A S = 0 gives S_a = −A_a⁻¹ A_w, r (rows 2–3 of A_a⁻ᵀ) = −S_aᵀ, so the lower-left
    block is +S_aᵀ M_a. Hence M14 = [[M_a, −M_a S_a], [S_aᵀ M_a, I_w 1]], and because M_a is
    symmetric the lower-left block is MINUS the transpose of the upper-right one:

        M14(4,1) = −k1, M14(4,2) = −k3, M14(4,3) = +k5,
        M14(5,1) = −k2, M14(5,2) = −k4, M14(5,3) = −k5,  while M14(3,4) = −k5, M14(3,5) = +k5.

    The printed row 3 "K sin θ  K cos θ  I  k5  k5" and rows 4–5 "k1 k3 k5 Iw 0",
    "k2 k4 k5 0 Iw" are this matrix with the minus signs lost (checked numerically
    against the block formula in ``runtime.tooling.crosscheck``).
    """
    m, I, K, Iw, _, _, _ = _params(p)
    th = _vec(q, 5)[2]
    s, c = math.sin(th), math.cos(th)
    k1, k2, k3, k4, k5 = coupling_k(q, p)
    return np.array(
        [
            [m, 0.0, K * s, k1, k2],
            [0.0, m, -K * c, k3, k4],
            [K * s, -K * c, I, -k5, k5],  # printed: "k5 k5"; M14(3,4) = −k5
            [-k1, -k3, k5, Iw, 0.0],  # printed: "k1 k3 k5"; NOT the transpose of column 4
            [-k2, -k4, -k5, 0.0, Iw],  # printed: "k2 k4 k5"
        ]
    )


def bias_14(q: ArrayLike, qdot: ArrayLike, p: Params) -> Vec:
    """H(q, q̇) of (14), as printed with the minus signs restored:

        ( m d θ̇² cos θ + m r² sin θ (θ̇_r² − θ̇_l²)/(2b),
          m d θ̇² sin θ − m r² cos θ (θ̇_r² − θ̇_l²)/(2b),
          K r² (θ̇_r² − θ̇_l²)/(2b),
          K r θ̇²/2,
          K r θ̇²/2 ).

    Valid on the constraint manifold only (q̇ = S(q) η), where θ̇ = r(θ̇_r − θ̇_l)/b (13):
    rows 1–3 are −M_a Ṡ_a η and rows 4–5 are S_aᵀ H_a (see ``mass_matrix_14``).
    θ̇ is read from q̇[2].
    """
    m, _, K, _, r, b, d = _params(p)
    th = _vec(q, 5)[2]
    qd = _vec(qdot, 5)
    thd, wr, wl = qd[2], qd[3], qd[4]
    s, c = math.sin(th), math.cos(th)
    dw2 = wr**2 - wl**2
    return np.array(
        [
            m * d * thd**2 * c + m * r**2 * s * dw2 / (2.0 * b),
            m * d * thd**2 * s - m * r**2 * c * dw2 / (2.0 * b),
            K * r**2 * dw2 / (2.0 * b),
            K * r * thd**2 / 2.0,
            K * r * thd**2 / 2.0,
        ]
    )


def forward_dynamics_14(q: ArrayLike, qdot: ArrayLike, tau: ArrayLike, p: Params) -> Vec:
    """q̈ from (14), M(q) q̈ + H(q, q̇) = u = B τ, by ``numpy.linalg.solve``.

    (14) is nonsingular: its Schur complement is I_w 1 + S_aᵀ M_a S_a = S ᵀ M S > 0.
    q̇ must lie on the constraint manifold (``bias_14``).
    """
    u = input_matrix_9() @ _vec(tau, 2)
    qddot = np.linalg.solve(mass_matrix_14(q, p), u - bias_14(q, qdot, p))
    return np.asarray(qddot, dtype=np.float64)


# --------------------------------------------------------------------------- minimal form


def minimal_mass_matrix(q: ArrayLike, p: Params) -> Mat:
    """M̄ = Sᵀ M S with M of (9) and S of (31)/(13) (constant: θ drops out)."""
    S = null_space(q, p)
    return S.T @ mass_matrix_9(q, p) @ S


def minimal_bias(q: ArrayLike, wheel_rates: ArrayLike, p: Params) -> Vec:
    """H̄ = Sᵀ (M Ṡ η + H) with M, H of (9) on q̇ = S η."""
    eta = _vec(wheel_rates, 2)
    S = null_space(q, p)
    qd = S @ eta
    return S.T @ (mass_matrix_9(q, p) @ null_space_rate_times_eta(q, eta, p) + bias_9(q, qd, p))


def minimal_forward_dynamics(
    q: ArrayLike, wheel_rates: ArrayLike, tau: ArrayLike, p: Params
) -> Vec:
    """η̇ from M̄ η̇ + H̄ = Sᵀ B τ = τ (projecting (9) on S removes λ)."""
    rhs = _vec(tau, 2) - minimal_bias(q, wheel_rates, p)
    eta_dot = np.linalg.solve(minimal_mass_matrix(q, p), rhs)
    return np.asarray(eta_dot, dtype=np.float64)


def pose_acceleration(
    q: ArrayLike, wheel_rates: ArrayLike, wheel_accels: ArrayLike, p: Params
) -> Vec:
    """q̈ = S η̇ + Ṡ η (all five coordinates) for given wheel rates and accelerations."""
    return null_space(q, p) @ _vec(wheel_accels, 2) + null_space_rate_times_eta(q, wheel_rates, p)


# Names of the generated functions, for callers that compare like with like (runtime.tooling.bench).
mass_matrix = mass_matrix_14
bias_forces = bias_14
forward_dynamics = forward_dynamics_14
kinematics = kinematics_31
