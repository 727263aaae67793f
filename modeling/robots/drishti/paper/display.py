"""Presentation of the paper's equations: plain text with the paper's letters, LaTeX
names, grouping in the printed terms, and SI units for the homogeneity check.

No mathematics is decided here: these helpers rewrite an expression for reading (or, for
:func:`dimension_outliers`, report the terms whose units differ from the rest).
"""

from __future__ import annotations

import sympy as sp

from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.paper.symbols import (
    WHEEL_ACC_SUM,
    WHEEL_SQ_DIFF,
    I,
    I_w,
    K,
    b,
    d,
    lam1,
    lam2,
    lam3,
    m,
    r,
    tau_l,
    tau_r,
    thd,
    thd_l,
    thd_r,
    thdd,
    thdd_l,
    thdd_r,
    theta,
    theta_l,
    theta_r,
    x_c,
    xd,
    xdd,
    y_c,
    yd,
    ydd,
)

_WHEEL_RATE_SUM = sp.Dummy("P")  # θ̇_r + θ̇_l, eliminated again

LATEX_NAMES: dict[sp.Symbol, str] = {
    WHEEL_ACC_SUM: r"(\ddot{\theta}_{r} + \ddot{\theta}_{l})",
    WHEEL_SQ_DIFF: r"(\dot{\theta}_{r}^{2} - \dot{\theta}_{l}^{2})",
}

_TEXT_NAMES: dict[sp.Symbol, str] = {
    x_c: "x", y_c: "y", theta: "θ", theta_r: "θr", theta_l: "θl",
    xd: "ẋ", yd: "ẏ", thd: "θ̇", thd_r: "θ̇r", thd_l: "θ̇l",
    xdd: "ẍ", ydd: "ÿ", thdd: "θ̈", thdd_r: "θ̈r", thdd_l: "θ̈l",
    lam1: "λ1", lam2: "λ2", lam3: "λ3", tau_r: "τr", tau_l: "τl",
    I_w: "Iw", WHEEL_ACC_SUM: "(θ̈r+θ̈l)", WHEEL_SQ_DIFF: "(θ̇r²−θ̇l²)",
    wmr.m_P: "mP", wmr.m_w: "mw", wmr.I_P: "IP", wmr.I_m: "Im", wmr.x_P: "xP", wmr.y_P: "yP",
}

# Dimensions (mass, length, time) for the homogeneity check of printed terms.
_MASS, _LENGTH, _TIME = sp.symbols("MASS LENGTH TIME", positive=True)
_DIMENSIONS: dict[sp.Symbol, sp.Expr] = {
    m: _MASS, wmr.m_P: _MASS, wmr.m_w: _MASS,
    K: _MASS * _LENGTH, wmr.K_lat: _MASS * _LENGTH,
    I: _MASS * _LENGTH**2, I_w: _MASS * _LENGTH**2,
    wmr.I_P: _MASS * _LENGTH**2, wmr.I_m: _MASS * _LENGTH**2,
    r: _LENGTH, b: _LENGTH, d: _LENGTH, wmr.x_P: _LENGTH, wmr.y_P: _LENGTH,
    x_c: _LENGTH, y_c: _LENGTH, theta: sp.S.One, theta_r: sp.S.One, theta_l: sp.S.One,
    xd: _LENGTH / _TIME, yd: _LENGTH / _TIME,
    thd: 1 / _TIME, thd_r: 1 / _TIME, thd_l: 1 / _TIME,
    xdd: _LENGTH / _TIME**2, ydd: _LENGTH / _TIME**2,
    thdd: 1 / _TIME**2, thdd_r: 1 / _TIME**2, thdd_l: 1 / _TIME**2,
    lam1: _MASS * _LENGTH / _TIME**2, lam2: _MASS * _LENGTH / _TIME**2,
    lam3: _MASS * _LENGTH / _TIME**2,
    tau_r: _MASS * _LENGTH**2 / _TIME**2, tau_l: _MASS * _LENGTH**2 / _TIME**2,
}


def text(expr: sp.Basic) -> str:
    """A short plain-text rendering with the paper's letters (θ̇r, λ2, …)."""
    names = {s: sp.Symbol(n) for s, n in _TEXT_NAMES.items()}
    out = sp.sstr(expr.xreplace(names))
    return out.replace("**", "^").replace("*", "·")



def heading_coordinates() -> dict[sp.Symbol, sp.Expr]:
    """θ̈r, θ̈l, θ̇r, θ̇l in terms of (θ̈r + θ̈l, θ̈) and (θ̇r + θ̇l, θ̇): an invertible change
    of variables on the manifold, in which each printed term of (10)–(14) is one monomial."""
    p = _WHEEL_RATE_SUM
    return {
        thdd_r: (WHEEL_ACC_SUM + b * thdd / r) / 2,
        thdd_l: (WHEEL_ACC_SUM - b * thdd / r) / 2,
        thd_r: (p + b * thd / r) / 2,
        thd_l: (p - b * thd / r) / 2,
    }


def in_printed_terms(expr: sp.Expr) -> sp.Expr:
    """Rewrite an expression in the wheel variables with the printed shorthands.

    On the constraint manifold θ̇ = r(θ̇r − θ̇l)/b and θ̈ = r(θ̈r − θ̈l)/b; (10)–(14) write
    their right-hand sides with θ̈, θ̇², (θ̈r + θ̈l) and (θ̇r² − θ̇l²). Expressions that do
    not fit (a (θ̇r + θ̇l)² term) are returned collected but otherwise unchanged.
    """
    p = _WHEEL_RATE_SUM
    e = sp.expand(expr.subs(heading_coordinates()))
    c2 = e.coeff(p, 2)
    if c2 != 0:
        return tidy(expr)
    c1 = sp.expand(e.coeff(p, 1) / thd)
    if c1.has(p) or sp.denom(sp.together(c1)).has(thd):
        return tidy(expr)
    out = sp.expand(e.coeff(p, 0) + c1 * r * WHEEL_SQ_DIFF / b)
    return tidy(out)


def tidy(expr: sp.Expr) -> sp.Expr:
    """Collect on sin/cos and on the state variables, factoring each coefficient.

    An expression of the parameters alone is returned as it is."""
    original = expr
    expr = sp.expand(expr)
    if expr == 0:
        return expr
    keys: list[sp.Expr] = sorted(expr.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
    state = [
        s for s in (*wmr.qddot, *wmr.qdot, WHEEL_ACC_SUM, WHEEL_SQ_DIFF, lam1, lam2, lam3,
                    tau_r, tau_l) if expr.has(s)
    ]
    keys += state
    if not keys:
        return original
    collected = sp.collect(expr, keys, evaluate=False)
    if set(collected) == {sp.S.One}:
        return sp.factor(expr)
    # Collect twice: first on monomials of the state, then each coefficient on sin/cos.
    state_mono = sp.collect(expr, state, evaluate=False) if state else {sp.S.One: expr}
    terms = []
    for mono, coeff in sorted(state_mono.items(), key=lambda kv: sp.default_sort_key(kv[0])):
        trig = sorted(coeff.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
        if trig:
            parts = sp.collect(sp.expand(coeff), trig, evaluate=False)
            inner = sp.Add(*[sp.factor(c) * t for t, c in parts.items()])
        else:
            inner = sp.factor(coeff)
        terms.append(inner * mono)
    return sp.Add(*terms)


def dimension_outliers(expr: sp.Expr) -> list[sp.Expr]:
    """Terms of ``expr`` whose dimension differs from that of most terms (empty if homogeneous)."""
    trig = {a: sp.S.One for a in expr.atoms(sp.sin, sp.cos)}
    terms = sp.Add.make_args(sp.expand(expr))
    dims: list[sp.Expr] = []
    for t in terms:
        unit = sp.powsimp(t.xreplace(trig).xreplace(_DIMENSIONS))
        dims.append(unit.as_coeff_Mul()[1] if unit != 0 else sp.S.Zero)
    counts: dict[sp.Expr, int] = {}
    for u in dims:
        counts[u] = counts.get(u, 0) + 1
    if len(counts) <= 1:
        return []
    major = max(counts, key=lambda u: (counts[u], -len(str(u)), str(u)))
    return [t for t, u in zip(terms, dims, strict=True) if u != major]


def unit_text(term: sp.Expr) -> str:
    """The SI unit of a term, e.g. 'kg·m³/s²'."""
    trig = {a: sp.S.One for a in term.atoms(sp.sin, sp.cos)}
    unit = sp.powsimp(term.xreplace(trig).xreplace(_DIMENSIONS)).as_coeff_Mul()[1]
    names = {_MASS: sp.Symbol("kg"), _LENGTH: sp.Symbol("m"), _TIME: sp.Symbol("s")}
    return text(unit.xreplace(names))

