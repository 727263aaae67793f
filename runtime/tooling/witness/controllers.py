"""TDC, TDROC, ROC and ASMC of Roy et al. (2017), typed by hand in NumPy.

Independent of ``modeling/``, ``codegen/`` and ``generated/`` (nothing imported, nothing
copied). The laws follow the specification in the module docstring of
``modeling/controllers.py`` (read, not imported); the step — history, start-up, window,
saturation — follows the behaviour documented for the generated controllers
(``generated/c/wmr_<ctrl>.h``, ``generated/python/controllers.py``), rewritten here.

Model used by a law (M̂, Ĥ at the *nominal* parameters), per formulation:

* ``paper``: the five coordinates of (14): M̂ = M14(q), Ĥ = H14(q, q̇); the law gives a
  5-vector u and only τ = Bᵀ u = (u4, u5) is applied (BᵀB = 1, so this is the least-squares
  solution of B τ = u); ‖(u1, u2, u3)‖ is reported as ``u_discarded``.
* ``minimal``: the two wheel angles: M̂ = M̄ = SᵀMS, Ĥ = H̄(η), u = τ exactly.

With e = q_d − q on the controlled coordinates:

  (18)       û_a = q̈_d + K1 e + K2 ė                     (K1, K2 diagonal)
  (24)/(25)  Δu_a = k s / max(‖s‖, ε),  s = Bᵀ P e, i.e. s_j = p12_j e_j + p22_j ė_j
             with P solving Aᵀ P + P A = −diag(q_pos, q_vel) per coordinate (A of (20)).
  TDC   (16)–(18):            u = M̂(q) û_a + Ĥ1
  TDROC (16), (17), (22), (25): u = M̂(q)(û_a + Δu_a) + Ĥ1 with
        k̂ = ‖M̂(q)⁻¹‖_F Σ_{i=1..n} w_i ‖Ω(i) − Ω(i+1)‖,  w_i = a^(i−1) / Σ_j a^(j−1),
        Ω(i) = u(t − ih) − M̂(q(t − ih)) q̈(t − ih), Ω(1) = Ĥ1.
  ROC:   u = M̂(q)(û_a + Δu_a) + Ĥ(q, q̇),  ρ = (α(‖q̈_d‖ + ‖K1 e + K2 ė‖) + φ)/(1 − α).
  ASMC:  u = M̂(q)(û_a + Δu_a) + Ĥ(q, q̇) with the current k̂; then k̂ ← k̂ + h γ ‖s‖.
  (17)  Ĥ1(t) = u(t − h) − M̂(q(t − h)) q̈(t − h), q̈(t − h) ≈ (q̇(t) − q̇(t − Δ))/Δ,
        Δ = h ("backward") or 2h ("central"); u(t − h) is the input applied, B τ.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from runtime.tooling.witness import model

Vec = NDArray[np.float64]
Kind = Literal["tdc", "tdroc", "roc", "asmc"]
Formulation = Literal["paper", "minimal"]
Accel = Literal["backward", "central", "matched"]
KINDS: tuple[Kind, ...] = ("tdc", "tdroc", "roc", "asmc")
FORMULATIONS: tuple[Formulation, ...] = ("paper", "minimal")
MAX_WINDOW = 8  # history rows kept for Ω (the generated C state has MAX_WINDOW + 1 rows)


@dataclass
class Settings:
    """Controller configuration (the fields of the generated ``Config``, own names)."""

    nominal: Mapping[str, float]
    formulation: Formulation = "paper"
    k1: ArrayLike = field(default_factory=lambda: [4.0] * 5)
    k2: ArrayLike = field(default_factory=lambda: [4.0] * 5)
    q_pos: float = 1.0
    q_vel: float = 1.0
    h: float = 0.1
    tau_max: float = 50.0
    accel: Accel = "backward"
    rate_window: float = 0.0  # s, span of the rate measurement (matched estimator)
    eps: float = 0.1
    n: int = 4
    a: float = 0.9
    alpha: float = 0.3
    phi: float = 1.0
    gamma: float = 1.0
    gain0: float = 0.0


@dataclass
class History:
    """What a controller remembers between steps (same content as the C state struct)."""

    steps: int = 0
    q_prev: Vec = field(default_factory=lambda: np.zeros(5))
    qdot_prev: Vec = field(default_factory=lambda: np.zeros(5))
    qdot_prev2: Vec = field(default_factory=lambda: np.zeros(5))
    u_prev: Vec = field(default_factory=lambda: np.zeros(5))  # B τ actually applied
    u_prev2: Vec = field(default_factory=lambda: np.zeros(5))  # the one before
    omega: NDArray[np.float64] = field(default_factory=lambda: np.zeros((MAX_WINDOW + 1, 5)))
    omega_count: int = 0
    H1hat: Vec = field(default_factory=lambda: np.zeros(5))
    gain: float = 0.0
    s_norm: float = 0.0
    u_discarded: float = 0.0
    tau: Vec = field(default_factory=lambda: np.zeros(2))


@dataclass
class StepRecord:
    """The inputs and outputs of the kernels of one step (for kernel-level comparisons)."""

    q: Vec
    qdot: Vec
    e: Vec
    edot: Vec
    qdd_des: Vec
    k1: Vec
    k2: Vec
    p12: Vec
    p22: Vec
    tde_inputs: tuple[Vec, Vec, Vec, Vec, float] | None  # q_prev, u_prev, q̇(t), q̇(t − Δ), Δ
    H1hat: Vec
    window: tuple[NDArray[np.float64], Vec, float] | None  # Ω rows, weights, ‖M̂(q)⁻¹‖_F
    gain_in: float  # gain entering the law (TDROC: k̂, ASMC: k̂ before the update)
    gain_out: float  # TDROC: k̂; ROC: ρ; ASMC: k̂ after the update; TDC: 0
    u: Vec
    s: Vec
    s_norm: float
    tau: Vec
    saturated: bool


def lyapunov_p(k1: float, k2: float, q_pos: float, q_vel: float) -> tuple[float, float, float]:
    """(p11, p12, p22) of Aᵀ P + P A = −diag(q_pos, q_vel), A = [[0, 1], [−k1, −k2]] ((20)).

    Entry by entry: (1,1) −2 k1 p12 = −q_pos; (2,2) 2(p12 − k2 p22) = −q_vel;
    (1,2) p11 − k2 p12 − k1 p22 = 0.
    """
    p12 = q_pos / (2.0 * k1)
    p22 = (p12 + q_vel / 2.0) / k2
    p11 = k2 * p12 + k1 * p22
    return p11, p12, p22


class Controller:
    """One of TDC, TDROC, ROC, ASMC; ``step`` returns τ = (τ_r, τ_l)."""

    def __init__(self, kind: Kind, settings: Settings) -> None:
        if kind not in KINDS:
            raise ValueError(f"unknown controller {kind!r}")
        if settings.formulation not in FORMULATIONS:
            raise ValueError(f"unknown formulation {settings.formulation!r}")
        self.kind: Kind = kind
        self.settings = settings
        k1 = np.asarray(settings.k1, dtype=np.float64)
        k2 = np.asarray(settings.k2, dtype=np.float64)
        pm = [lyapunov_p(k1[i], k2[i], settings.q_pos, settings.q_vel) for i in range(5)]
        self.p12 = np.array([x[1] for x in pm])
        self.p22 = np.array([x[2] for x in pm])
        self.history = History(gain=float(settings.gain0) if kind == "asmc" else 0.0)
        self.last: StepRecord | None = None
        self.saturated = False

    # -- the model a law uses -------------------------------------------------------------

    @property
    def paper(self) -> bool:
        return self.settings.formulation == "paper"

    @property
    def coords(self) -> slice:
        """Controlled coordinates: all five (paper) or the wheel angles (minimal)."""
        return slice(0, 5) if self.paper else slice(3, 5)

    def mass(self, q: Vec) -> NDArray[np.float64]:
        """M̂(q): M of (14) (paper) or M̄ = SᵀMS of (9) (minimal), nominal parameters."""
        p = self.settings.nominal
        return model.mass_matrix_14(q, p) if self.paper else model.minimal_mass_matrix(q, p)

    def bias(self, q: Vec, qdot: Vec) -> Vec:
        """Ĥ(q, q̇): H of (14) (paper) or H̄ = Sᵀ(MṠη + H) of (9) (minimal), for ROC/ASMC."""
        p = self.settings.nominal
        if self.paper:
            return model.bias_14(q, qdot, p)
        return model.minimal_bias(q, qdot[3:5], p)

    # -- one step ---------------------------------------------------------------------------

    def step(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        q_des: ArrayLike,
        qdot_des: ArrayLike,
        qddot_des: ArrayLike,
    ) -> Vec:
        """Control step at time t from measured q, q̇ and the reference (5 each): (17) Ĥ1,
        (25) k̂ (TDROC), (18) û_a, (22) with (24)/(25) Δu_a, (16) u, then τ = Bᵀu clipped to
        ±tau_max; the history keeps q, q̇ and u = Bτ (the input actually applied)."""
        cfg, hist = self.settings, self.history
        q_ = np.asarray(q, dtype=np.float64).reshape(5)
        qd_ = np.asarray(qdot, dtype=np.float64).reshape(5)
        sl = self.coords
        nc = sl.stop - sl.start
        e = np.asarray(q_des, dtype=np.float64).reshape(5)[sl] - q_[sl]
        edot = np.asarray(qdot_des, dtype=np.float64).reshape(5)[sl] - qd_[sl]
        acc_des = np.asarray(qddot_des, dtype=np.float64).reshape(5)[sl].copy()
        k1 = np.asarray(cfg.k1, dtype=np.float64)[sl]
        k2 = np.asarray(cfg.k2, dtype=np.float64)[sl]
        p12, p22 = self.p12[sl], self.p22[sl]
        tde = self.kind in ("tdc", "tdroc")

        # (17): time-delay estimate; zero until two past samples exist.
        H1 = hist.H1hat.copy()
        tde_inputs = None
        if tde:
            H1 = np.zeros(5)
            if hist.steps >= 2:
                central = cfg.accel == "central"
                span = 2.0 * cfg.h if central else cfg.h
                then = (hist.qdot_prev2 if central else hist.qdot_prev)[sl]
                qdd_est = (qd_[sl] - then) / span
                # Rates averaged over w: the quotient is (1 − c) q̈ under u(t − h) + c q̈ under
                # u(t − 2h), c = w / 2h; pair it with the same blend of inputs.
                c2 = cfg.rate_window / (2.0 * cfg.h) if cfg.accel == "matched" else 0.0
                u_paired = ((1.0 - c2) * hist.u_prev + c2 * hist.u_prev2)[sl]
                H1[:nc] = u_paired - self.mass(hist.q_prev) @ qdd_est
                tde_inputs = (
                    hist.q_prev.copy(),
                    u_paired.copy(),
                    qd_[sl].copy(),
                    then.copy(),
                    span,
                )

        # (25): window of Ω, newest first, and the discounted, normalised gain.
        omega, count = hist.omega.copy(), hist.omega_count
        window = None
        gain = hist.gain
        if self.kind == "tdroc":
            if hist.steps >= 2:
                omega = np.vstack([np.zeros((1, 5)), hist.omega[:-1]])
                omega[0, :nc] = H1[:nc]
                count = min(count + 1, MAX_WINDOW + 1)
            gain = 0.0
            if count >= 2:
                active = min(count - 1, cfg.n)
                w = np.array([cfg.a**i if i < active else 0.0 for i in range(MAX_WINDOW)])
                w = w / w.sum()
                diffs = [
                    np.linalg.norm(omega[i, :nc] - omega[i + 1, :nc]) for i in range(MAX_WINDOW)
                ]
                minv_norm = float(np.linalg.norm(np.linalg.inv(self.mass(q_)), "fro"))
                gain = minv_norm * float(np.dot(w, diffs))
                window = (omega[:, :nc].copy(), w, minv_norm)

        # The law.
        fb = k1 * e + k2 * edot
        ua = acc_des + fb  # (18)
        s = p12 * e + p22 * edot
        s_norm = float(np.linalg.norm(s))
        gain_in = gain
        if self.kind == "roc":
            alpha, phi = cfg.alpha, cfg.phi
            bound = float(np.linalg.norm(acc_des) + np.linalg.norm(fb))
            gain = (alpha * bound + phi) / (1.0 - alpha)
            gain_in = gain
        if self.kind != "tdc":
            ua = ua + gain_in * s / max(s_norm, cfg.eps)  # (22) with (24)/(25)
        else:
            s_norm, gain, gain_in = 0.0, 0.0, 0.0
        # (16) with Ĥ1 of (17) for TDC/TDROC; the nominal Ĥ(q, q̇) for ROC/ASMC.
        u = self.mass(q_) @ ua + (H1[:nc] if tde else self.bias(q_, qd_))
        if self.kind == "asmc":
            gain = hist.gain + cfg.h * cfg.gamma * s_norm  # k̂ ← k̂ + h γ ‖s‖

        # τ = Bᵀ u, saturation, and the history for (17).
        tau = u[3:5].copy() if self.paper else u.copy()
        u_discarded = float(np.linalg.norm(u[:3])) if self.paper else 0.0
        if not (np.all(np.isfinite(tau)) and math.isfinite(gain)):
            raise FloatingPointError(f"{self.kind}: non-finite output")
        saturated = bool(np.any(np.abs(tau) > cfg.tau_max))
        tau = np.clip(tau, -cfg.tau_max, cfg.tau_max)
        self.history = History(
            steps=hist.steps + 1,
            q_prev=q_.copy(),
            qdot_prev=qd_.copy(),
            qdot_prev2=hist.qdot_prev.copy(),
            u_prev=np.array([0.0, 0.0, 0.0, tau[0], tau[1]]),
            u_prev2=hist.u_prev.copy(),
            omega=omega,
            omega_count=count,
            H1hat=H1,
            gain=float(gain),
            s_norm=s_norm,
            u_discarded=u_discarded,
            tau=tau.copy(),
        )
        self.saturated = saturated
        self.last = StepRecord(
            q=q_.copy(),
            qdot=qd_.copy(),
            e=e,
            edot=edot,
            qdd_des=acc_des,
            k1=k1.copy(),
            k2=k2.copy(),
            p12=p12.copy(),
            p22=p22.copy(),
            tde_inputs=tde_inputs,
            H1hat=H1[:nc].copy(),
            window=window,
            gain_in=float(gain_in),
            gain_out=float(gain),
            u=np.asarray(u, dtype=np.float64).copy(),
            s=s.copy(),
            s_norm=s_norm,
            tau=tau.copy(),
            saturated=saturated,
        )
        return tau

    def snapshot(self) -> History:
        """A deep copy of the history (to restart a step from the same state)."""
        return copy.deepcopy(self.history)
