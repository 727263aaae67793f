"""The five-cart tugger train (``modeling/robots/train5/``) against a route that shares
nothing with the toolchain: its robot file read with ``tomllib`` and its equations of
motion written here in NumPy, particle by particle.

Each body's and wheel's mass sits at a point whose world position is a chain of rotated
offsets, p = o + Σ R(θ_k) c_k, so its velocity Jacobian J (∂p/∂θ_k = R(θ_k + π/2) c_k) and
its acceleration at q̈ = 0, J̇ q̇ = −Σ R(θ_k) c_k θ̇_k², are exact. Lagrange's equations of
a set of particles and yaw/spin inertias, with the wheel constraints of (6)–(8) (no side
slip n·v = 0, rolling r θ̇_w − e·v = 0, e and n the wheel's body axes) as multipliers, are
the saddle-point (KKT) system of (9):

    [[M, Aᵀ], [A, 0]] [q̈; λ] = [B τ − Σ m Jᵀ J̇ q̇; −(Ȧ q̇)],

solved at random consistent states and compared with the generated forward dynamics
(base parameters, the staged minimal form, ``modeling.staged``) to 1e-12 relative. Two
redundant no-side-slip rows (two wheels on one axle) are left in: ``lstsq`` of the
saddle point gives the unique q̈ all the same.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from description_numeric import rel

from runtime.bindings.generated import RobotCode, load_robot_code

ROOT = Path(__file__).resolve().parents[2]
FILE = ROOT / "modeling" / "robots" / "train5" / "train5.toml"
RTOL = 1e-12
N_STATES = 40


def _rot(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Chain:
    """A point of a body: (angle index, local offset) terms from the root's origin."""

    terms: tuple[tuple[int, np.ndarray], ...]
    yaw: int  # the index of its body's yaw in q

    def position(self, q: np.ndarray) -> np.ndarray:
        return q[:2] + sum((_rot(q[k]) @ c for k, c in self.terms), np.zeros(2))

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        j = np.zeros((2, len(q)))
        j[:, :2] = np.eye(2)
        for k, c in self.terms:
            j[:, k] += _rot(q[k] + np.pi / 2) @ c
        return j

    def drift(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """J̇ q̇ (the acceleration at q̈ = 0)."""
        return -sum((_rot(q[k]) @ c * qdot[k] ** 2 for k, c in self.terms), np.zeros(2))


class Train:
    """The robot file's bodies, joints and wheels as NumPy equations of motion."""

    def __init__(self, path: Path) -> None:
        with path.open("rb") as f:
            data: dict[str, Any] = tomllib.load(f)
        bodies = data["body"]
        wheels = data["wheel"]
        self.n = 2 + len(bodies) + len(wheels)
        yaw = {b["name"]: 2 + i for i, b in enumerate(bodies)}
        order = [w for w in wheels if w["driven"]] + [w for w in wheels if not w["driven"]]
        spin = {w["name"]: 2 + len(bodies) + i for i, w in enumerate(order)}
        self.driven = [spin[w["name"]] for w in wheels if w["driven"]]
        # origin of each body: the parent's hitch point minus the child's, rotated
        origin: dict[str, tuple[tuple[int, np.ndarray], ...]] = {bodies[0]["name"]: ()}
        for j in data.get("joint", []):
            origin[j["child"]] = (*origin[j["parent"]],
                                  (yaw[j["parent"]], np.array(j["parent_point"], float)),
                                  (yaw[j["child"]], -np.array(j["child_point"], float)))

        def point(body: str, local: list[float]) -> Chain:
            return Chain((*origin[body], (yaw[body], np.array(local, float))), yaw[body])

        # (mass, point), (inertia, coordinate) of every body and wheel
        self.masses = [(b["mass"], point(b["name"], b["com"])) for b in bodies]
        self.masses += [(w["mass"], point(w["body"], w["position"])) for w in wheels]
        self.inertias = [(b["yaw_inertia"], yaw[b["name"]]) for b in bodies]
        self.inertias += [(w["diameter_inertia"], yaw[w["body"]]) for w in wheels]
        self.inertias += [(w["spin_inertia"], spin[w["name"]]) for w in wheels]
        self.wheels = [(point(w["body"], w["position"]), w["radius"], spin[w["name"]])
                       for w in wheels]

    def constraints(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A(q) and Ȧ q̇: per wheel its no-side-slip and its rolling row."""
        rows, rates = [], []
        for p, radius, k in self.wheels:
            a = q[p.yaw]
            e, n = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
            j, drift = p.jacobian(q), p.drift(q, qdot)
            v, w = j @ qdot, qdot[p.yaw]
            rows.append(n @ j)
            rates.append(n @ drift - w * (e @ v))  # d/dt n = −θ̇ e
            roll = -(e @ j)
            roll[k] += radius
            rows.append(roll)
            rates.append(-(e @ drift) - w * (n @ v))  # d/dt e = θ̇ n
        return np.array(rows), np.array(rates)

    def accelerations(self, q: np.ndarray, qdot: np.ndarray, tau: np.ndarray) -> np.ndarray:
        m = np.zeros((self.n, self.n))
        rhs = np.zeros(self.n)
        for mass, p in self.masses:
            j = p.jacobian(q)
            m += mass * j.T @ j
            rhs -= mass * j.T @ p.drift(q, qdot)
        for inertia, k in self.inertias:
            m[k, k] += inertia
        rhs[self.driven] += tau
        a, rate = self.constraints(q, qdot)
        kkt = np.block([[m, a.T], [a, np.zeros((len(a), len(a)))]])
        sol = np.linalg.lstsq(kkt, np.r_[rhs, -rate], rcond=None)[0]
        return sol[: self.n]

    def states(self, seed: int, count: int) -> list[tuple[np.ndarray, ...]]:
        """(q, q̇, τ): driven rates random, the rest the least-squares solution of
        A q̇ = 0 (exact: A's null space is two-dimensional, spanned by the driven rates)."""
        rng = np.random.default_rng(seed)
        out = []
        for _ in range(count):
            q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, self.n - 2)]
            a, _ = self.constraints(q, np.zeros(self.n))
            rest = [i for i in range(self.n) if i not in self.driven]
            eta = rng.uniform(-15, 15, len(self.driven))
            qdot = np.zeros(self.n)
            qdot[self.driven] = eta
            qdot[rest] = np.linalg.lstsq(a[:, rest], -a[:, self.driven] @ eta, rcond=None)[0]
            assert np.max(np.abs(a @ qdot)) < 1e-12 * np.max(np.abs(eta))
            out.append((q, qdot, rng.uniform(-10, 10, len(self.driven))))
        return out


@pytest.fixture(scope="module")
def train() -> Train:
    return Train(FILE)


@pytest.fixture(scope="module")
def code() -> RobotCode:
    return load_robot_code("train5")


def test_train5_is_a_tractor_with_five_carts(train: Train, code: RobotCode) -> None:
    assert train.n == code.nq == 20 and code.nu == 2 and train.driven == [8, 9]


def test_forward_dynamics_equals_the_numpy_kkt_of_the_robot_file(
        train: Train, code: RobotCode) -> None:
    worst = 0.0
    for q, qdot, tau in train.states(seed=51, count=N_STATES):
        qdd = code.model.forward_dynamics(q, qdot, tau, code.params)
        worst = max(worst, rel(qdd, train.accelerations(q, qdot, tau)))
    assert worst < RTOL, worst


def test_the_kkt_comparison_sees_a_heavier_last_cart(train: Train, code: RobotCode) -> None:
    """A 1 % heavier fifth cart in the generated model's parameters (the base parameters
    that name it) moves the accelerations far beyond the tolerance: it is not vacuous."""
    heavier = {k: v * 1.01 if k.endswith("cart5") or "cart5_x" in k else v
               for k, v in code.params.items()}
    assert heavier != code.params
    worst = max(rel(code.model.forward_dynamics(q, qdot, tau, heavier),
                    train.accelerations(q, qdot, tau))
                for q, qdot, tau in train.states(seed=52, count=5))
    assert worst > 1e3 * RTOL, worst


def kane_accelerations(train: Train, q: np.ndarray, qdot: np.ndarray, tau: np.ndarray,
                       heavier: float = 1.0) -> np.ndarray:
    """q̈ by Kane's method, from the robot file's bodies and wheels (``Train``), with no
    mass matrix of the whole robot and no multipliers: the generalised speeds are the
    driven wheel rates η; every rate follows from the wheel constraints, q̇ = S(q) η (A S =
    0, S's driven rows the identity), and at η̇ = 0 the constrained acceleration is
    q̈₀ = w (A w = −Ȧ q̇, w's driven rows 0). Each mass point's partial velocities are
    v_r = J S e_r and each inertia's partial angular velocities ω_r = S[k, r]; Kane's
    equations F_r + F*_r = 0, with F_r = τ_r (the motor torque on its wheel's relative
    spin) and the generalised inertia forces F*_r = −Σ m v_r · a − Σ I ω_r α, a = J q̈ + J̇
    q̇, are linear in η̇: solved, then q̈ = S η̇ + w. ``heavier`` scales the last body's
    mass (a wrong model, for the check's teeth)."""
    a_mat, rate = train.constraints(q, qdot)
    rest = [i for i in range(train.n) if i not in train.driven]
    s = np.zeros((train.n, len(train.driven)))
    s[train.driven] = np.eye(len(train.driven))
    s[rest] = np.linalg.lstsq(a_mat[:, rest], -a_mat[:, train.driven], rcond=None)[0]
    w = np.zeros(train.n)
    w[rest] = np.linalg.lstsq(a_mat[:, rest], -rate, rcond=None)[0]
    k = len(train.driven)
    inertia = np.zeros((k, k))  # coefficient of η̇ in −F*
    free = np.zeros(k)  # −F* at η̇ = 0
    last = len(train.masses) - len(train.wheels) - 1  # the last body (not a wheel)
    for i, (mass, p) in enumerate(train.masses):
        mass = mass * heavier if i == last else mass
        j = p.jacobian(q)
        partial = j @ s  # 2 × k: v_r of this point
        inertia += mass * partial.T @ partial
        free += mass * partial.T @ (j @ w + p.drift(q, qdot))
    for rot, col in train.inertias:
        omega = s[col]  # ω_r of this yaw or spin
        inertia += rot * np.outer(omega, omega)
        free += rot * omega * w[col]
    eta_dot = np.linalg.solve(inertia, tau - free)  # F_r = τ_r: the torques' speeds
    return s @ eta_dot + w


def test_forward_dynamics_equals_kanes_method(train: Train, code: RobotCode) -> None:
    """Item 4 of issue 51: the generated forward dynamics against Kane's method written
    from the robot file (``kane_accelerations``) at random consistent states, 1e-12."""
    worst = 0.0
    for q, qdot, tau in train.states(seed=53, count=N_STATES):
        qdd = code.model.forward_dynamics(q, qdot, tau, code.params)
        worst = max(worst, rel(qdd, kane_accelerations(train, q, qdot, tau)))
    assert worst < RTOL, worst


def test_the_kane_comparison_sees_a_heavier_last_cart(train: Train, code: RobotCode) -> None:
    worst = max(rel(code.model.forward_dynamics(q, qdot, tau, code.params),
                    kane_accelerations(train, q, qdot, tau, heavier=1.01))
                for q, qdot, tau in train.states(seed=54, count=5))
    assert worst > 1e3 * RTOL, worst
