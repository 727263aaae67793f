"""What the laws share: the error dynamics (18)–(20) and the switching term (22), (24)/(25).

  (18)  û_a = q̈_d + K1 e + K2 ė,  K1 = diag(k1), K2 = diag(k2) > 0   (e = q_d − q)
  (22)  u_a = û_a + Δu_a
  (24)/(25)  Δu_a = k s / max(‖s‖, ε)   — k s/‖s‖ outside the boundary layer, k s/ε inside
        s = Bᵀ P e, P from Aᵀ P + P A = −Q (per coordinate, see ``lyapunov_p``):
        s_j = p12_j e_j + p22_j ė_j.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp


def vec(name: str, n: int) -> sp.Matrix:
    """A column of ``n`` real symbols ``<name>0`` .. ``<name><n-1>``."""
    return sp.Matrix(sp.symbols(f"{name}0:{n}", real=True))


def norm(v: sp.Matrix) -> sp.Expr:
    """The Euclidean norm of ``v``'s entries."""
    return sp.sqrt(sum((x**2 for x in v), sp.S.Zero))


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
        e=vec("e", n),
        edot=vec("edot", n),
        qddot_des=vec("qdd_des", n),
        h1=vec("H1hat", n),
        k1=vec("k1_", n),
        k2=vec("k2_", n),
        p12=vec("p12_", n),
        p22=vec("p22_", n),
        gain=sp.Symbol("gain", real=True),
        eps=sp.Symbol("eps", positive=True),
        alpha=sp.Symbol("alpha", real=True),
        phi=sp.Symbol("phi", real=True),
    )


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
    s_norm = norm(s)
    return s * (1 / sp.Max(s_norm, ls.eps)), s_norm


# Up to this many controlled coordinates k the gain is distributed through M-hat (below):
# k^2 more multiply-adds for a shorter chain after the gain. Measured on the step benchmark:
# the trailer's minimal form (k = 2) 67 -> 61 ns; Drishti's paper form (k = 5) 0.95 -> 1.05x
# the hand-written step with it, so not there.
DISTRIBUTED_SWITCHING_MAX_SIZE = 2


def with_switching(mass: sp.Matrix, ua: sp.Matrix, bias: sp.Matrix, gain: sp.Expr,
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
