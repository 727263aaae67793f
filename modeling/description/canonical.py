"""A faster equivalent of ``lagrange.default_simplify`` for robots with many parameters.

``lagrange.trig_canonical`` reduces modulo sin² + cos² − 1 by polynomial division in sin(a)
over a coefficient domain holding every other symbol; with the 24 parameters of a tractor
and trailer that domain (SymPy's EX, with ``cancel`` on every coefficient) takes minutes
per matrix. The same canonical form — expanded, each sin(a) to degree ≤ 1 — is reached
term by term: in a term c·sin(a)^k with k ≥ 2, sin(a)^k = sin(a)^(k mod 2) (1 − cos²(a))^(k div 2),
and only the rewritten terms are expanded again. Terms with a trigonometric function in a
denominator are left alone, as ``trig_canonical`` does.
"""

from __future__ import annotations

import sympy as sp


def _reduce_term(term: sp.Expr) -> sp.Expr | None:
    """The term with sin(a)^k (k ≥ 2) rewritten, or None if it has no such power."""
    powers = term.as_powers_dict()
    changed = False
    factors: list[sp.Expr] = []
    for base, exp in powers.items():
        if isinstance(base, sp.sin) and exp.is_Integer and exp >= 2:
            k = int(exp)
            cos = sp.cos(base.args[0])
            factors.append(base ** (k % 2) * (1 - cos**2) ** (k // 2))
            changed = True
        else:
            factors.append(base**exp)
    return sp.Mul(*factors) if changed else None


def trig_reduce(expr: sp.Expr) -> sp.Expr:
    """expand(expr) with sin²(a) → 1 − cos²(a) for every angle a: a canonical form (see the
    module docstring), equal to ``lagrange.default_simplify(expr)`` when no trigonometric
    function is in a denominator (then trig_canonical gives up on the whole expression,
    this reduces the other terms)."""
    expr = sp.expand(expr)
    for _ in range(4):  # a rewritten term cannot create a new sin power: one pass suffices
        keep, rewritten = [], []
        for term in sp.Add.make_args(expr):
            new = _reduce_term(term)
            if new is None:
                keep.append(term)
            else:
                rewritten.append(new)
        if not rewritten:
            return expr
        expr = sp.Add(*keep) + sp.expand(sp.Add(*rewritten))
    return expr
