"""The four controllers of Roy et al. (2017) as symbolic laws: TDC, TDROC, ROC and ASMC.

Every law acts on a model  M(q) q̈ + H(q, q̇) = u  in one of two formulations:

* ``paper``: the five coordinates of (14), M = M̃(q) (not symmetric), u = B τ. The law
  computes a 5-vector u, but only τ = (τ_r, τ_l) can be applied: we take τ = Bᵀ u (rows
  4–5 of u, the least-squares solution of B τ = u since BᵀB = I). Rows 1–3 of u are
  discarded; the controllers report their norm (the cost of this choice; docs/PAPER.md
  item 7).
* ``minimal``: the two wheel angles, M = M̄ = Sᵀ M S (constant), H = H̄, u = τ exactly.
  The law then tracks the wheel angles of a kinematically consistent reference; the pose
  is not fed back (drift of the pose is not corrected).

Common to all (e = q_d − q):
  (18)  û_a = q̈_d + K1 e + K2 ė,  K1 = diag(k1), K2 = diag(k2) > 0
  (22)  u_a = û_a + Δu_a
  (24)/(25)  Δu_a = k s / max(‖s‖, ε)   — k s/‖s‖ outside the boundary layer, k s/ε inside
        s = Bᵀ P e, P from Aᵀ P + P A = −Q (per coordinate, see ``lyapunov_p``):
        s_j = p12_j e_j + p22_j ė_j.

TDC   (16)–(18): u = M̂(q) û_a + Ĥ1, no switching term.
TDROC (16), (17), (22), (25): u = M̂(q) u_a + Ĥ1 with the gain
        k̂ = ‖M̂(q)⁻¹‖_F · Σ_{i=1..n} w_i ‖Ω(i) − Ω(i+1)‖ / Σ w_i,
        Ω(i) = u(t − ih) − M̂(q(t − ih)) q̈(t − ih)   (Ω(1) is Ĥ1 of (17)).
        Weights w_i = a^(i−1) (i = 1 is the most recent difference), normalised: the
        printed (25) is unreadable here; Remark 3 asks that recent data weigh most, which
        a^(i−1) does for 0 < a < 1 (a = 1: equal weights). ‖·‖_F bounds the spectral
        norm from above, so the robustness argument of (23) still holds (docs/PAPER.md
        item 10).
ROC   (Ryu & Agarwal's robust control in its standard Lyapunov-redesign form; ROC and
      ASMC are only cited by the paper, docs/PAPER.md item 11):
        u = M̂(q) u_a + Ĥ(q, q̇) (full nominal model), gain
        ρ = (α (‖q̈_d‖ + ‖K1 e + K2 ė‖) + φ) / (1 − α),
        α ≥ ‖M⁻¹ M̂ − I‖ and φ ≥ ‖M⁻¹ (H − Ĥ)‖ over the predefined uncertainty box
        (30 % above nominal), computed when the configuration is built.
ASMC  (Chen et al.'s adaptive sliding mode): u = M̂(q) u_a + Ĥ(q, q̇), gain adapted by
        dk̂/dt = γ ‖s‖ (explicit Euler over one sample h): k̂ never decreases.

q̈(t − h) in (17) is estimated from the measured rates by a difference quotient
        q̈(t − h) ≈ (q̇(t) − q̇(t − Δ)) / Δ,
a configuration choice (docs/PAPER.md item 9):
  * backward (default), Δ = h: the mean acceleration over [t − h, t], exactly the period
    during which u(t − h) was held (zero-order hold), so Ĥ1 pairs each input with the
    acceleration it produced; exact for a constant H1.
  * central, Δ = 2h: second-order accurate at the instant t − h for a smooth motion, but
    it mixes the responses to u(t − h) and u(t − 2h); measured in the reproduction.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from typing import Literal

import sympy as sp

from modeling.lagrange import ConstrainedSystem
from modeling.robot_model import RobotModel
from modeling.staged import Stage

Formulation = Literal["paper", "minimal"]
FORMULATIONS: tuple[Formulation, ...] = ("paper", "minimal")


def _vec(name: str, n: int) -> sp.Matrix:
    return sp.Matrix(sp.symbols(f"{name}0:{n}", real=True))


@dataclass(frozen=True)
class ControlModel:
    """M̂(q), Ĥ(q, q̇) and Bᵀ-selection of one formulation at the nominal parameters.

    ``size`` is the number of controlled coordinates and ``rows`` their indices in q
    (all of q for the paper form; the actuated wheel angles for the minimal form).
    ``stage``: for a staged robot (``RobotModel.staged``), the quantities M̂ and Ĥ are
    written in (``modeling.staged``); a law's kernel evaluates the ones it reads.
    """

    formulation: Formulation
    size: int
    rows: tuple[int, ...]
    mass: sp.Matrix
    bias: sp.Matrix
    velocities: tuple[sp.Symbol, ...]
    system: ConstrainedSystem
    stage: Stage | None = None

    @property
    def mass_inverse(self) -> sp.Matrix:
        """M̂⁻¹ in closed form (by cofactors; derived on first use: only the paper
        formulation's ‖M̂⁻¹‖ reads it)."""
        if self.stage is not None:
            raise ValueError("a staged model has no closed-form M-hat inverse")
        if self.formulation == "paper":
            return self.system.reduced_mass_matrix_inverse
        return self.system.minimal_mass_matrix_inverse

    def definitions(self, exprs: list[sp.Expr]) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
        """The staged quantities ``exprs`` read (none for a closed-form model)."""
        return () if self.stage is None else self.stage.definitions_for(exprs)

    def depends_on(self, exprs: list[sp.Expr], symbols: tuple[sp.Symbol, ...]) -> bool:
        """Whether ``exprs`` depend on ``symbols``, through the staged quantities too."""
        wanted = set(symbols)
        return any(e.free_symbols & wanted
                   for e in [*exprs, *(d for _, d in self.definitions(exprs))])


def control_model(formulation: Formulation, model: RobotModel) -> ControlModel:
    """The model a controller uses. Paper: M̃, H̃ of (14); minimal: M̄, H̄ (Sᵀ M S form)."""
    return _control_model(formulation, model)


@cache
def _control_model(formulation: Formulation, model: RobotModel) -> ControlModel:
    s = model.system
    rates = tuple(model.qdot[i] for i in model.actuated)
    if formulation == "paper" and model.paper:
        return ControlModel(
            formulation,
            model.nq,
            tuple(range(model.nq)),
            s.reduced_mass_matrix,
            s.reduced_bias,
            rates,
            s,
        )
    if formulation == "minimal" and model.staged:
        stage = Stage("_c")
        staged = s.staged_minimal(stage, root_frame=True, positive=model.positive_symbols)
        return ControlModel(formulation, model.nu, model.actuated, staged.mass_matrix,
                            staged.bias, rates, s, stage)
    if formulation == "minimal":
        return ControlModel(
            formulation,
            model.nu,
            model.actuated,
            s.minimal_mass_matrix,
            s.minimal_bias,
            rates,
            s,
        )
    raise ValueError(
        f"formulation {formulation!r} is not available for robot '{model.name}' "
        f"(available: {', '.join(model.formulations)})"
    )


def lyapunov_p(k1: sp.Expr, k2: sp.Expr, q1: sp.Expr, q2: sp.Expr) -> tuple[sp.Expr, ...]:
    """(p11, p12, p22) solving Aᵀ P + P A = −diag(q1, q2) for A = [[0, 1], [−k1, −k2]].

    With K1, K2 and Q diagonal, the 2n×2n Lyapunov equation of (20) splits into one 2×2
    equation per coordinate; it is solved here symbolically, not typed.
    """
    p11, p12, p22 = sp.symbols("p11 p12 p22")
    a = sp.Matrix([[0, 1], [-k1, -k2]])
    p = sp.Matrix([[p11, p12], [p12, p22]])
    eqs = a.T * p + p * a + sp.diag(q1, q2)
    sol = sp.solve([eqs[0, 0], eqs[0, 1], eqs[1, 1]], [p11, p12, p22], dict=True)[0]
    return tuple(sp.factor(sol[v]) for v in (p11, p12, p22))


@dataclass(frozen=True)
class LawSymbols:
    """Input symbols shared by the laws of one formulation (size n)."""

    e: sp.Matrix
    edot: sp.Matrix
    qddot_des: sp.Matrix
    h1: sp.Matrix
    k1: sp.Matrix
    k2: sp.Matrix
    p12: sp.Matrix
    p22: sp.Matrix
    gain: sp.Symbol
    eps: sp.Symbol
    alpha: sp.Symbol
    phi: sp.Symbol


def law_symbols(n: int) -> LawSymbols:
    return LawSymbols(
        e=_vec("e", n),
        edot=_vec("edot", n),
        qddot_des=_vec("qdd_des", n),
        h1=_vec("H1hat", n),
        k1=_vec("k1_", n),
        k2=_vec("k2_", n),
        p12=_vec("p12_", n),
        p22=_vec("p22_", n),
        gain=sp.Symbol("gain", real=True),
        eps=sp.Symbol("eps", positive=True),
        alpha=sp.Symbol("alpha", real=True),
        phi=sp.Symbol("phi", real=True),
    )


def _norm(v: sp.Matrix) -> sp.Expr:
    return sp.sqrt(sum((x**2 for x in v), sp.S.Zero))


def nominal_acceleration(ls: LawSymbols) -> sp.Matrix:
    """(18): û_a = q̈_d + K1 e + K2 ė with diagonal gains."""
    n = ls.e.rows
    return sp.Matrix(
        [ls.qddot_des[j] + ls.k1[j] * ls.e[j] + ls.k2[j] * ls.edot[j] for j in range(n)]
    )


def sliding_variable(ls: LawSymbols) -> sp.Matrix:
    """s = Bᵀ P e (below (24)): s_j = p12_j e_j + p22_j ė_j."""
    return sp.Matrix([ls.p12[j] * ls.e[j] + ls.p22[j] * ls.edot[j] for j in range(ls.e.rows)])


def switching_direction(ls: LawSymbols) -> tuple[sp.Matrix, sp.Expr]:
    """(24)/(25) without the gain: s / max(‖s‖, ε), at most 1 in norm; returns it and ‖s‖.
    The switching term is Δu_a = k s / max(‖s‖, ε) = k times this."""
    s = sliding_variable(ls)
    s_norm = _norm(s)
    return s * (1 / sp.Max(s_norm, ls.eps)), s_norm


# Up to this many controlled coordinates k the gain is distributed through M-hat (below):
# k^2 more multiply-adds for a shorter chain after the gain. Measured on the step benchmark:
# the trailer's minimal form (k = 2) 67 -> 61 ns; Drishti's paper form (k = 5) 0.95 -> 1.05x
# the hand-written step with it, so not there.
DISTRIBUTED_SWITCHING_MAX_SIZE = 2


def _with_switching(mass: sp.Matrix, ua: sp.Matrix, bias: sp.Matrix, gain: sp.Expr,
                    direction: sp.Matrix) -> sp.Matrix:
    """u = M̂ (u_a + k s / max(‖s‖, ε)) + Ĥ (22), (24), with s / max(‖s‖, ε) a product by
    one reciprocal (``direction``): the division runs beside the gain k — the last input
    ready in a step (it waits for ‖M̂⁻¹‖ of (25), or ρ of ROC) — not after it. For a small
    M̂ (``DISTRIBUTED_SWITCHING_MAX_SIZE``) written (M̂ u_a + Ĥ) + k (M̂ s / max(‖s‖, ε)):
    the same value, k one product and one sum before u. M̂ s / max(‖s‖, ε) is at most
    ‖M̂‖ in size: it overflows only where the law as written does."""
    if mass.rows > DISTRIBUTED_SWITCHING_MAX_SIZE:
        return mass * (ua + gain * direction) + bias
    rest = mass * ua + bias
    toward = mass * direction
    return sp.Matrix([rest[j] + gain * toward[j] for j in range(rest.rows)])


@dataclass(frozen=True)
class Law:
    """Outputs of one control law: u (n), s (n), ‖s‖, and the gain actually used."""

    u: sp.Matrix
    s: sp.Matrix
    s_norm: sp.Expr
    gain: sp.Expr


def tde_law(
    formulation: Formulation, switching: bool, model: RobotModel
) -> tuple[Law, LawSymbols]:
    """TDC (16)–(18) when ``switching`` is False; TDROC (16), (22), (25) with the gain
    symbol ``ls.gain`` (k̂, computed by ``tdroc_gain``) when True. Ĥ1 is an input (17)."""
    cm = control_model(formulation, model)
    ls = law_symbols(cm.size)
    ua = nominal_acceleration(ls)
    if switching:
        direction, s_norm = switching_direction(ls)
        gain: sp.Expr = ls.gain
        u = _with_switching(cm.mass, ua, ls.h1, gain, direction)
    else:
        s_norm, gain = sp.S.Zero, sp.S.Zero
        u = cm.mass * ua + ls.h1
    return Law(u, sliding_variable(ls), s_norm, gain), ls


def model_law(
    formulation: Formulation,
    controller: Literal["roc", "asmc"],
    model: RobotModel,
) -> tuple[Law, LawSymbols]:
    """ROC and ASMC: u = M̂ u_a + Ĥ(q, q̇) with the nominal model's Ĥ.

    ROC's gain is ρ = (α(‖q̈_d‖ + ‖K1 e + K2 ė‖) + φ)/(1 − α); ASMC's is the input k̂.
    """
    cm = control_model(formulation, model)
    ls = law_symbols(cm.size)
    ua_hat = nominal_acceleration(ls)
    if controller == "roc":
        feedback = ua_hat - ls.qddot_des
        gain = (ls.alpha * (_norm(ls.qddot_des) + _norm(feedback)) + ls.phi) / (1 - ls.alpha)
    else:
        gain = ls.gain
    direction, s_norm = switching_direction(ls)
    u = _with_switching(cm.mass, ua_hat, cm.bias, gain, direction)
    return Law(u, sliding_variable(ls), s_norm, gain), ls


@dataclass(frozen=True)
class TdeSymbols:
    q_prev: sp.Matrix  # q(t − h), all n coordinates
    u_prev: sp.Matrix  # u(t − h) actually applied (B τ for the paper form)
    qdot_now: sp.Matrix  # q̇(t), size n
    qdot_then: sp.Matrix  # q̇(t − Δ), size n
    span: sp.Symbol  # Δ


def tde_estimate(
    formulation: Formulation, model: RobotModel
) -> tuple[sp.Matrix, TdeSymbols]:
    """(17): Ĥ1(t) = Ω(1) = u(t − h) − M̂(q(t − h)) q̈(t − h), with the difference quotient
    q̈(t − h) ≈ (q̇(t) − q̇(t − Δ)) / Δ (Δ = h backward, 2h central)."""
    rm = model
    cm = control_model(formulation, rm)
    n = cm.size
    ts = TdeSymbols(
        q_prev=_vec("qp", rm.nq),
        u_prev=_vec("up", n),
        qdot_now=_vec("qd_now", n),
        qdot_then=_vec("qd_then", n),
        span=sp.Symbol("span", positive=True),
    )
    qdd = (ts.qdot_now - ts.qdot_then) / ts.span
    at_prev = dict(zip(rm.q, ts.q_prev, strict=True))
    mass = (cm.mass.subs(at_prev) if cm.stage is None
            else sp.Matrix(n, n, cm.stage.substituted(list(cm.mass), at_prev)))
    return ts.u_prev - mass * qdd, ts


def mass_angles(formulation: Formulation, model: RobotModel) -> tuple[int, ...]:
    """Indices in q of the coordinates M̂ depends on (the heading, hitch angles): the only
    way the laws with Ĥ1 of (17) (TDC, TDROC) and (17) itself depend on q."""
    cm = control_model(formulation, model)
    if cm.stage is not None:  # its M-hat is evaluated in the kernel: no _trig variants
        return ()
    free = cm.mass.free_symbols
    return tuple(i for i, x in enumerate(model.q) if x in free)


def trig_symbols(name: str, count: int) -> tuple[sp.Symbol, ...]:
    """(sin a0, cos a0, sin a1, cos a1, ...) as symbols ``<name>_s<k>``, ``<name>_c<k>``."""
    return tuple(sp.Symbol(f"{name}_{sc}{k}", real=True) for k in range(count) for sc in "sc")


def in_trig(
    exprs: sp.Matrix, angles: tuple[sp.Symbol, ...], trig: tuple[sp.Symbol, ...]
) -> sp.Matrix | None:
    """``exprs`` with sin/cos of each angle replaced by ``trig`` (sin, cos interleaved), so a
    caller that already has them (the previous step's law had sin/cos of what is now
    q(t − h)) computes none; None when an angle also appears otherwise (bare, or inside a
    sum that expand_trig does not split)."""
    mapping: dict[sp.Expr, sp.Expr] = {}
    for k, a in enumerate(angles):
        mapping[sp.sin(a)] = trig[2 * k]
        mapping[sp.cos(a)] = trig[2 * k + 1]
    out = exprs.xreplace(mapping)
    if out.free_symbols & set(angles):
        out = exprs.applyfunc(sp.expand_trig).xreplace(mapping)
    return None if out.free_symbols & set(angles) else out


def heading_rotation(formulation: Formulation, model: RobotModel) -> sp.Matrix:
    """T(θ): rotates the root's (x, y) rows by its yaw θ in the paper form (q starts with
    them); the identity for the minimal form's wheel angles."""
    rm = model
    size = control_model(formulation, rm).size
    t = sp.eye(size)
    if formulation == "paper":
        c, s = sp.cos(rm.heading), sp.sin(rm.heading)
        t[0, 0], t[0, 1], t[1, 0], t[1, 1] = c, -s, s, c
    return t


def rotation_residual(formulation: Formulation, model: RobotModel) -> sp.Matrix:
    """M̂(θ) − T(θ) M̂(0) T(θ)ᵀ, which is zero: the model is invariant under heading.

    So M̂(θ)⁻¹ = T M̂(0)⁻¹ Tᵀ with T orthogonal, and every unitarily invariant norm of
    M̂⁻¹ (Frobenius, spectral) is independent of θ — (25) needs it for the parameters
    only. Tests assert the residual simplifies to zero.
    """
    rm = model
    cm = control_model(formulation, rm)
    t = heading_rotation(formulation, rm)
    at_zero = cm.mass.subs(rm.heading, 0)
    return (cm.mass - t * at_zero * t.T).applyfunc(rm.system.simplify)


# Up to this size ‖M̂⁻¹‖_F is built from M̂'s entries as ‖adj M̂‖_F / |det M̂|: the expanded
# inverse costs ~2.4x the operations (Drishti's minimal form 75 -> 31, the trailer's 994 -> 425).
ADJUGATE_NORM_MAX_SIZE = 3


def mass_inverse_norm(formulation: Formulation, model: RobotModel) -> sp.Expr:
    """‖M̂⁻¹‖_F of (25). The paper form is evaluated at θ = 0 (exact for every θ, see
    rotation_residual); the minimal form as it is — a constant for a single body, a
    function of the hitch angles for a robot with trailers (then an input of the kernel).
    A small M̂ (``ADJUGATE_NORM_MAX_SIZE``) goes through its entries: M̂⁻¹ = adj M̂ / det M̂
    over entry symbols, the entries substituted after (the same value, fewer operations)."""
    rm = model
    cm = control_model(formulation, rm)
    if cm.stage is not None:  # M-hat's entries are quantities of the stage
        n = cm.mass.rows
        if n > ADJUGATE_NORM_MAX_SIZE:
            return _norm(sp.Matrix(list(cm.stage.solve(cm.mass, sp.eye(n)))))
        return _norm(sp.Matrix(list(cm.mass.adjugate()))) / sp.Abs(cm.mass.det())
    if formulation == "paper":
        mass, inverse = cm.mass.subs(rm.heading, 0), cm.mass_inverse.subs(rm.heading, 0)
    else:
        mass, inverse = cm.mass, cm.mass_inverse
    n = mass.rows
    if n > ADJUGATE_NORM_MAX_SIZE:
        return _norm(sp.Matrix(list(inverse)))
    entries = sp.Matrix(n, n, lambda i, j: sp.Symbol(f"_mhat_{i}_{j}", real=True))
    by_entries = _norm(sp.Matrix(list(entries.adjugate()))) / sp.Abs(entries.det())
    return by_entries.subs(dict(zip(list(entries), list(mass), strict=True)), simultaneous=True)


def tdroc_gain(
    formulation: Formulation, window: int, model: RobotModel
) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """(25): k̂ = ‖M̂⁻¹‖_F Σ_{i=1..window} w_i ‖Ω(i) − Ω(i+1)‖ with the weights w_i
    given normalised (Σ w_i = 1 over the active window, 0 beyond it) by the caller.
    ‖M̂⁻¹‖_F depends on the nominal parameters only (``mass_inverse_norm``): it is an
    input here (symbol ``minv_norm``), computed when the nominal parameters change.

    Returns (k̂, Ω window symbols ((window + 1) × n, row i = Ω(i + 1)), weight symbols).
    """
    cm = control_model(formulation, model)
    n = cm.size
    omega = sp.Matrix(window + 1, n, lambda i, j: sp.Symbol(f"Om{i}_{j}", real=True))
    w = _vec("w", window)
    total = sp.S.Zero
    for i in range(window):
        total += w[i] * _norm((omega[i, :] - omega[i + 1, :]).T)
    return sp.Symbol("minv_norm", positive=True) * total, omega, w


def asmc_adaptation(gain: sp.Symbol, gamma: sp.Symbol, s_norm: sp.Symbol, h: sp.Symbol) -> sp.Expr:
    """ASMC: k̂(t + h) = k̂(t) + h γ ‖s(t)‖ (explicit Euler of dk̂/dt = γ‖s‖)."""
    return gain + h * gamma * s_norm


def omega_difference_norm(
    formulation: Formulation, model: RobotModel
) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """One term of (25): ‖Ω(i) − Ω(i+1)‖ for two consecutive rows of the window.

    Each difference is computed once, when its newer row joins the window, and then only
    moves down the window: a step evaluates one norm instead of ``window``. Returns (norm,
    newer row symbols, older row symbols).
    """
    n = control_model(formulation, model).size
    newer, older = _vec("Om_new", n), _vec("Om_old", n)
    return _norm(newer - older), newer, older


def tdroc_weighted_gain(window: int) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
    """(25) from the window's difference norms d_i = ‖Ω(i) − Ω(i+1)‖ (``omega_difference_norm``):
    k̂ = ‖M̂⁻¹‖_F Σ_{i=1..window} w_i d_i — ``tdroc_gain`` with its norms given.

    Returns (k̂, difference-norm symbols, weight symbols); ``minv_norm`` as in ``tdroc_gain``.
    """
    d = _vec("dn", window)
    w = _vec("w", window)
    total = sum((w[i] * d[i] for i in range(window)), sp.S.Zero)
    return sp.Symbol("minv_norm", positive=True) * total, d, w


def wheel_pi_law(
    model: RobotModel,
) -> tuple[sp.Matrix, sp.Matrix, dict[str, tuple[sp.Symbol, ...]]]:
    """The baseline a mobile-robot user deploys: ros2_control's ``diff_drive_controller``
    structure (a wheel-velocity PI loop per driven wheel) under a pose-correcting path
    tracker (Kanayama et al. 1990), generic over robots whose root body carries two driven
    wheels. With the root's pose (x, y, θ) = q[0], q[1], q[heading] and its reference:

      e_x = cos θ Δx + sin θ Δy,  e_y = −sin θ Δx + cos θ Δy,  e_θ = θ_d − θ
      v_d = cos θ_d ẋ_d + sin θ_d ẏ_d,  ω_d = θ̇_d                (the reference's feed-forward)
      v_c = v_d cos e_θ + k_x e_x,  ω_c = ω_d + v_d (k_y e_y + k_θ sin e_θ)
      η_c = A(q)⁻¹ (v_c, ω_c),  A = [[cos θ, sin θ, 0], [0, 0, 1]] S_root(q)

    (A maps the driven-wheel rates η to the root's forward speed and yaw rate, from the
    derived kinematics q̇ = S(q) η; for a differential drive [[r/2, r/2], [r/b, −r/b]]), and
    the wheel-velocity PI with the integral kept in torque units and clamped to ±τ_max (anti
    wind-up):  I⁺ = clamp(I + k_i h (η_c − η), ±τ_max),  τ = k_p (η_c − η) + I⁺.

    Returns (τ, I⁺, input symbols). No model of the dynamics is used: only the kinematics
    (wheel radius and track through the nominal parameters)."""
    if model.nu != 2:
        raise ValueError(f"robot '{model.name}': the wheel-velocity PI controller needs two "
                         f"driven wheels on the root body; it has {model.nu}")
    n = model.nq
    q, qdot = sp.Matrix(model.q), sp.Matrix(model.qdot)
    q_des, qdot_des = _vec("qd_", n), _vec("qdd_", n)
    integral = _vec("I_", model.nu)
    kx, ky, kth, kp, ki = sp.symbols("kx ky ktheta kp ki", real=True)
    h, tau_max = sp.symbols("h tau_max", positive=True)
    th_i = list(model.q).index(model.heading)
    th, thd = q[th_i], q_des[th_i]
    dx, dy = q_des[0] - q[0], q_des[1] - q[1]
    ex = sp.cos(th) * dx + sp.sin(th) * dy
    ey = -sp.sin(th) * dx + sp.cos(th) * dy
    eth = thd - th
    vd = sp.cos(thd) * qdot_des[0] + sp.sin(thd) * qdot_des[1]
    wd = qdot_des[th_i]
    vc = vd * sp.cos(eth) + kx * ex
    wc = wd + vd * (ky * ey + kth * sp.sin(eth))
    s_root = model.system.null_space.extract([0, 1, th_i], list(range(model.nu)))
    rows = sp.Matrix([[sp.cos(th), sp.sin(th), 0], [0, 0, 1]])
    a = (rows * s_root).applyfunc(model.system.simplify)
    eta_c = (a.adjugate() / a.det()).applyfunc(model.system.simplify) * sp.Matrix([vc, wc])
    eta = sp.Matrix([qdot[i] for i in model.actuated])
    err = eta_c - eta
    i_next = sp.Matrix([sp.Min(sp.Max(integral[j] + ki * h * err[j], -tau_max), tau_max)
                        for j in range(model.nu)])
    tau = sp.Matrix([kp * err[j] + i_next[j] for j in range(model.nu)])
    symbols = {"q_des": tuple(q_des), "qdot_des": tuple(qdot_des), "integral": tuple(integral),
               "gains": (kx, ky, kth, kp, ki), "limits": (h, tau_max)}
    return tau, i_next, symbols


# --------------------------------------------------------------------------- the registry
#
# Every controller is declared once, below: its law (the kernel a step calls, with the
# argument list the step fills), its configuration fields (with the check, the status a bad
# value gets, the unit and where the runtime takes the value), the features its step needs
# and its labels. codegen builds the kernels and the C and Python step functions from these
# entries, the generated robot.py exports them, and the runtime and the reports iterate them.


@dataclass(frozen=True)
class ConfigField:
    """One field of ``<prefix>_<ctrl>_config_t`` (after ``nominal``).

    ``kind``: ``real``, ``int``, or ``vector`` (one real per coordinate of q). ``check``: how
    the C and the Python mirror validate it (``codegen.controller_api.FIELD_CHECKS``),
    failing with status ``ERR_<status>``. ``doc``: the struct comment, a format string over
    ``PRE`` (the C prefix in capitals), ``actuated_k1`` and ``formulations`` (the robot's).
    ``source``: where the runtime's configuration builder takes the value
    (``runtime`` knows each source; ``experiment.<section>.<field>`` reads an experiment
    field)."""

    name: str
    kind: Literal["real", "int", "vector"]
    check: str
    status: str
    unit: str
    doc: str
    source: str


@dataclass(frozen=True)
class KernelArg:
    """One argument of a law kernel: its name (the kernel's parameter), what the step passes
    (``source``: ``codegen.controller_api.STEP_SOURCES``) and the symbols or expressions."""

    name: str
    source: str
    values: tuple[sp.Expr, ...]
    doc: str = ""


@dataclass(frozen=True)
class Kernel:
    """A controller's law as one generated function of ``<prefix>_laws``: ``doc`` (after
    "(<formulation> formulation) "), the paper's equations, inputs after the nominal
    parameters, outputs."""

    doc: str
    equations: tuple[str, ...]
    inputs: tuple[KernelArg, ...]
    outputs: tuple[KernelArg, ...]
    definitions: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()  # staged quantities it reads


@dataclass(frozen=True)
class ControllerSpec:
    """A controller: identity, labels, step features, configuration and law.

    Features the step functions are built from (none names a controller):
    ``tde``: Ĥ1 from the time-delay estimate (17), with its history and estimator fields;
    ``window``: TDROC's k̂ of (25) over a window of past Ω's (history in the state);
    ``switching``: a switching term with a boundary layer ε (the law returns s and ‖s‖);
    ``adaptive``: a gain the law adapts, kept in the state and capped;
    ``bounds``: uncertainty bounds α, φ in the configuration;
    ``trig``: the law has a ``_trig`` variant taking sin/cos of q's angles (the TDE laws);
    ``error_dynamics``: K1, K2, Q and P of (18)-(20) (the four of the paper);
    ``integrator``: an integral per driven wheel the law updates (the wheel PI).
    ``checks``: the fields in the order a configuration is validated (the order of the
    statuses when several fields are bad), ``fields`` in struct order.
    """

    name: str
    label: str
    title: str
    equations: str
    tde: bool
    switching: bool
    window: bool
    bounds: bool
    adaptive: bool
    trig: bool
    fields: tuple[ConfigField, ...]
    checks: tuple[str, ...]
    kernel: Callable[[Formulation, RobotModel], Kernel]
    error_dynamics: bool = True  # K1, K2, Q, P of (18)-(20): the error e, ė of a formulation
    integrator: bool = False  # an integral per driven wheel in the state, from the law
    formulations: tuple[Formulation, ...] = FORMULATIONS  # those it has where the robot does

    def formulations_of(self, model: RobotModel) -> tuple[Formulation, ...]:
        """The formulations generated for ``model``."""
        return tuple(f for f in model.formulations if f in self.formulations)

    def field(self, name: str) -> ConfigField:
        return next(f for f in self.fields if f.name == name)


# The fields, each declared once; a controller lists the ones it has.
FORMULATION_FIELD = ConfigField(
    "formulation", "int", "formulation", "BAD_FORMULATION", "",
    "{formulations}", "formulation")
K1_FIELD = ConfigField(
    "k1", "vector", "gain", "BAD_GAINS", "1/s^2",
    "diagonal of K1 (18), [GAIN_MIN, GAIN_MAX]; the minimal form uses {actuated_k1}",
    "experiment.controller.k1")
K2_FIELD = ConfigField(
    "k2", "vector", "gain", "BAD_GAINS", "1/s",
    "diagonal of K2 (18), [GAIN_MIN, GAIN_MAX]", "experiment.controller.k2")
Q_POS_FIELD = ConfigField(
    "q_pos", "real", "gain", "BAD_GAINS", "",
    "Q = diag(q_pos I, q_vel I) of the Lyapunov equation, [GAIN_MIN, GAIN_MAX]",
    "experiment.controller.q_pos")
Q_VEL_FIELD = ConfigField("q_vel", "real", "gain", "BAD_GAINS", "", "",
                          "experiment.controller.q_vel")
H_FIELD = ConfigField("h", "real", "sample_time", "BAD_SAMPLE_TIME", "s",
                      "sample time [s], [H_MIN, H_MAX]", "experiment.controller.h")
TAU_MAX_FIELD = ConfigField(
    "tau_max", "real", "torque_limit", "BAD_TORQUE_LIMIT", "N m",
    "torque limit [N m], (0, TORQUE_LIMIT_MAX]; larger torques are clipped",
    "experiment.controller.tau_max")
ESTIMATOR_FIELD = ConfigField(
    "accel_estimator", "int", "estimator", "BAD_ESTIMATOR", "",
    "qddot(t-h) for (17): {PRE}_ACCEL_BACKWARD, _CENTRAL or _MATCHED", "accel_estimator")
RATE_WINDOW_FIELD = ConfigField(
    "rate_window", "real", "rate_window", "BAD_ESTIMATOR", "s",
    "span [s] over which qdot is measured, 0..h (MATCHED): 0 for a\n"
    "rate at the sample instant, h for encoder counts over h", "rate_window")
EPS_FIELD = ConfigField("eps", "real", "gain", "BAD_EPS", "",
                        "boundary layer of (24)/(25), [GAIN_MIN, GAIN_MAX]",
                        "experiment.controller.eps")
N_FIELD = ConfigField("n", "int", "window", "BAD_WINDOW", "",
                      "window of past instants, 2..{PRE}_MAX_WINDOW", "experiment.controller.n")
A_FIELD = ConfigField("a", "real", "discount", "BAD_DISCOUNT", "",
                      "discount, 0 < a <= 1; weights a^(i-1), normalised",
                      "experiment.controller.a")
HOLD_GAIN_FIELD = ConfigField("hold_gain", "int", "flag", "BAD_HELD_GAIN", "",
                              "0: k-hat from (25); 1: k-hat held at held_gain", "hold_gain")
HELD_GAIN_FIELD = ConfigField("held_gain", "real", "nonnegative_gain", "BAD_HELD_GAIN", "",
                              "[0, GAIN_MAX], used when hold_gain = 1", "held_gain")
ALPHA_FIELD = ConfigField("alpha", "real", "alpha", "BAD_BOUNDS", "",
                          "bound on ||M^-1 Mhat - I|| over the uncertainty box, [0, 1)",
                          "roc_bounds.alpha")
PHI_FIELD = ConfigField("phi", "real", "nonnegative_gain", "BAD_BOUNDS", "",
                        "bound on ||M^-1 (H - Hhat)||, [0, GAIN_MAX]", "roc_bounds.phi")
GAMMA_FIELD = ConfigField("gamma", "real", "nonnegative_gain", "BAD_BOUNDS", "",
                          "adaptation rate of the switching gain, [0, GAIN_MAX]",
                          "experiment.controller.gamma")
GAIN0_FIELD = ConfigField(
    "gain0", "real", "nonnegative_gain", "BAD_BOUNDS", "",
    "initial switching gain, [0, GAIN_MAX]; the gain is capped at GAIN_MAX", "zero")

KX_FIELD = ConfigField("kx", "real", "nonnegative_gain", "BAD_GAINS", "1/s",
                       "path tracker: along-track gain k_x [1/s], [0, GAIN_MAX]",
                       "experiment.controller.pi_kx")
KY_FIELD = ConfigField("ky", "real", "nonnegative_gain", "BAD_GAINS", "1/m^2",
                       "path tracker: cross-track gain k_y [1/m^2], [0, GAIN_MAX]",
                       "experiment.controller.pi_ky")
KTHETA_FIELD = ConfigField("ktheta", "real", "nonnegative_gain", "BAD_GAINS", "1/m",
                           "path tracker: heading gain k_theta [1/m], [0, GAIN_MAX]",
                           "experiment.controller.pi_ktheta")
KP_FIELD = ConfigField("kp", "real", "gain", "BAD_GAINS", "N m s/rad",
                       "wheel-velocity PI: proportional gain [N m s/rad], [GAIN_MIN, GAIN_MAX]",
                       "pi_kp")
KI_FIELD = ConfigField("ki", "real", "nonnegative_gain", "BAD_GAINS", "N m/rad",
                       "wheel-velocity PI: integral gain [N m/rad], [0, GAIN_MAX]", "pi_ki")

# The fields every controller of the paper has, in struct and check order.
_LYAPUNOV_BASE = (FORMULATION_FIELD, K1_FIELD, K2_FIELD, Q_POS_FIELD, Q_VEL_FIELD, H_FIELD,
                  TAU_MAX_FIELD)
# What <prefix>_check_base_config checks (shared by every controller that has these fields).
BASE_CHECKS = ("formulation", "h", "k1", "k2", "q_pos", "q_vel", "tau_max")


def _args(ls: LawSymbols, *names: str) -> tuple[KernelArg, ...]:
    """Kernel inputs that are law symbols, by name (the step's source has the same name)."""
    return tuple(KernelArg(n, n, tuple(getattr(ls, {"qddot_des": "qddot_des",
                                                    "H1hat": "h1"}.get(n, n))))
                 for n in names)


_COMMON = ("e", "edot", "qddot_des", "k1", "k2", "p12", "p22")


def _tdc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = tde_law(formulation, switching=False, model=model)
    return Kernel(
        "TDC (16), (18): u = Mhat(q) ua_hat + H1hat.", ("(16)", "(18)"),
        (KernelArg("q", "q", tuple(model.q)), *_args(ls, *_COMMON, "H1hat")),
        (KernelArg("u", "u", tuple(law.u)),),
    )


def _tdroc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = tde_law(formulation, switching=True, model=model)
    return Kernel(
        "TDROC (16), (22), (25):\nu = Mhat(q)(ua_hat + gain s/max(|s|, eps))\n"
        "+ H1hat, s = B^T P e.", ("(16)", "(22)", "(24)", "(25)"),
        (KernelArg("q", "q", tuple(model.q)), *_args(ls, *_COMMON, "H1hat"),
         KernelArg("gain", "khat", (ls.gain,), "khat of (25)"),
         KernelArg("eps", "config", (ls.eps,), "boundary layer")),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,))),
    )


def _roc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = model_law(formulation, "roc", model)
    return Kernel(
        "ROC:\nu = Mhat(q)(ua_hat + rho s/max(|s|, eps)) + Hhat(q, qdot),\n"
        "rho = (alpha(|qddot_des| + |K1 e + K2 edot|) + phi)/(1 - alpha).", ("(22)", "(24)"),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         *_args(ls, *_COMMON),
         KernelArg("bounds", "config", (ls.alpha, ls.phi), "alpha, phi"),
         KernelArg("eps", "config", (ls.eps,))),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,)),
         KernelArg("gain", "gain", (law.gain,))),
    )


def _asmc_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    law, ls = model_law(formulation, "asmc", model)
    gamma, h = sp.symbols("gamma h", positive=True)
    return Kernel(
        "ASMC:\nu = Mhat(q)(ua_hat + khat s/max(|s|, eps)) + Hhat(q, qdot);\n"
        "gain_next = khat + h gamma |s|.", ("(22)", "(24)"),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         *_args(ls, *_COMMON),
         KernelArg("gain", "adapted_gain", (ls.gain,), "khat"),
         KernelArg("eps", "config", (ls.eps,)),
         KernelArg("adapt", "config", (gamma, h), "gamma, h")),
        (KernelArg("u", "u", tuple(law.u)), KernelArg("s", "s", tuple(law.s)),
         KernelArg("s_norm", "s_norm", (law.s_norm,)),
         KernelArg("gain_next", "gain",
                   (asmc_adaptation(ls.gain, gamma, law.s_norm, h),))),
    )


def _pi_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    tau, i_next, sym = wheel_pi_law(model)
    return Kernel(
        "wheel-velocity PI under a pose-correcting path tracker (the ros2_control\n"
        "diff_drive_controller structure): eta_c = A(q)^-1 (v_c, w_c) from the root's pose\n"
        "error (Kanayama), I+ = clamp(I + ki h (eta_c - eta), +-tau_max),\n"
        "tau = kp (eta_c - eta) + I+.", (),
        (KernelArg("q", "q", tuple(model.q)), KernelArg("qdot", "qdot", tuple(model.qdot)),
         KernelArg("q_des", "q_des", sym["q_des"], "reference q"),
         KernelArg("qdot_des", "qdot_des", sym["qdot_des"], "reference qdot"),
         KernelArg("integral", "integral", sym["integral"], "the integral term [N m]"),
         KernelArg("gains", "config", sym["gains"], "kx, ky, ktheta, kp, ki"),
         KernelArg("limits", "config", sym["limits"], "h, tau_max")),
        (KernelArg("u", "u", tuple(tau)), KernelArg("integral_next", "integral", tuple(i_next))),
    )


REGISTRY: tuple[ControllerSpec, ...] = (
    ControllerSpec(
        "tdc", "TDC", "time-delay control", "(16)-(18)",
        tde=True, switching=False, window=False, bounds=False, adaptive=False, trig=True,
        fields=(*_LYAPUNOV_BASE, ESTIMATOR_FIELD, RATE_WINDOW_FIELD),
        checks=(*BASE_CHECKS, "accel_estimator", "rate_window"),
        kernel=_tdc_kernel,
    ),
    ControllerSpec(
        "tdroc", "TDROC", "time-delayed robust optimal control", "(16)-(18), (22)-(25)",
        tde=True, switching=True, window=True, bounds=False, adaptive=False, trig=True,
        fields=(*_LYAPUNOV_BASE, ESTIMATOR_FIELD, RATE_WINDOW_FIELD, EPS_FIELD, N_FIELD,
                A_FIELD, HOLD_GAIN_FIELD, HELD_GAIN_FIELD),
        checks=(*BASE_CHECKS, "eps", "accel_estimator", "rate_window", "hold_gain",
                "held_gain", "n", "a"),
        kernel=_tdroc_kernel,
    ),
    ControllerSpec(
        "roc", "ROC", "robust control with predefined bounds", "(22), (24)",
        tde=False, switching=True, window=False, bounds=True, adaptive=False, trig=False,
        fields=(*_LYAPUNOV_BASE, EPS_FIELD, ALPHA_FIELD, PHI_FIELD),
        checks=(*BASE_CHECKS, "eps", "alpha", "phi"),
        kernel=_roc_kernel,
    ),
    ControllerSpec(
        "asmc", "ASMC", "adaptive sliding-mode control", "(22), (24)",
        tde=False, switching=True, window=False, bounds=False, adaptive=True, trig=False,
        fields=(*_LYAPUNOV_BASE, EPS_FIELD, GAMMA_FIELD, GAIN0_FIELD),
        checks=(*BASE_CHECKS, "eps", "gamma", "gain0"),
        kernel=_asmc_kernel,
    ),
    ControllerSpec(
        "pi", "PI", "wheel-velocity PI with a pose-correcting path tracker",
        "none (the ros2_control diff_drive_controller structure; Kanayama et al. 1990)",
        tde=False, switching=False, window=False, bounds=False, adaptive=False, trig=False,
        fields=(FORMULATION_FIELD, H_FIELD, TAU_MAX_FIELD, KX_FIELD, KY_FIELD, KTHETA_FIELD,
                KP_FIELD, KI_FIELD),
        checks=("formulation", "h", "tau_max", "kx", "ky", "ktheta", "kp", "ki"),
        kernel=_pi_kernel,
        error_dynamics=False, integrator=True, formulations=("minimal",),
    ),
)
CONTROLLERS = tuple(c.name for c in REGISTRY)


@cache
def kernel(spec: ControllerSpec, formulation: Formulation, model: RobotModel) -> Kernel:
    """``spec``'s law kernel for one formulation of ``model`` (derived once), with the
    staged quantities its outputs read (a staged robot's)."""
    k = spec.kernel(formulation, model)
    if formulation not in model.formulations or not model.staged:
        return k
    exprs = [e for a in k.outputs for e in a.values]
    return replace(k, definitions=control_model(formulation, model).definitions(exprs))


def controller(name: str) -> ControllerSpec:
    """The registry entry of ``name``."""
    for c in REGISTRY:
        if c.name == name:
            return c
    raise ValueError(f"no controller {name!r} (known: {', '.join(CONTROLLERS)})")
