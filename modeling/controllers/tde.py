"""The time-delay estimate (17) and the laws built on it (TDC, TDROC): shared pieces.

(16)  u = M̂(q) u_a + Ĥ1,  (17)  Ĥ1(t) = u(t − h) − M̂(q(t − h)) q̈(t − h).

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

from dataclasses import dataclass

import sympy as sp

from modeling.controllers.common import (
    Law,
    LawSymbols,
    law_symbols,
    nominal_acceleration,
    sliding_variable,
    switching_direction,
    vec,
    with_switching,
)
from modeling.controllers.model import Formulation, control_model
from modeling.robot_model import RobotModel


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
        u = with_switching(cm.mass, ua, ls.h1, gain, direction)
    else:
        s_norm, gain = sp.S.Zero, sp.S.Zero
        u = cm.mass * ua + ls.h1
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
        q_prev=vec("qp", rm.nq),
        u_prev=vec("up", n),
        qdot_now=vec("qd_now", n),
        qdot_then=vec("qd_then", n),
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
