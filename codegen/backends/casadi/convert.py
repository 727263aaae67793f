"""SymPy expression -> ``casadi.SX`` by walking the expression tree.

The walk is memoized on SymPy subexpressions, and it converts the CSE result (temporaries
first), so a subexpression shared in SymPy is one shared node in the SX graph.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import casadi as ca
import sympy as sp

_UNARY: Mapping[type, Callable[[ca.SX], ca.SX]] = {
    sp.sin: ca.sin,
    sp.cos: ca.cos,
    sp.tan: ca.tan,
    sp.asin: ca.asin,
    sp.acos: ca.acos,
    sp.atan: ca.atan,
    sp.sinh: ca.sinh,
    sp.cosh: ca.cosh,
    sp.tanh: ca.tanh,
    sp.exp: ca.exp,
    sp.log: ca.log,
    sp.Abs: ca.fabs,
}


class SXConverter:
    """Converts SymPy expressions whose symbols are bound in ``env`` to SX."""

    def __init__(self, env: Mapping[sp.Symbol, ca.SX]) -> None:
        self.env = dict(env)
        self._memo: dict[sp.Basic, ca.SX] = {}

    def bind(self, symbol: sp.Symbol, value: ca.SX) -> None:
        """Make ``symbol`` stand for ``value`` (used for CSE temporaries)."""
        self.env[symbol] = value

    def __call__(self, expr: sp.Basic) -> ca.SX:
        if expr in self._memo:
            return self._memo[expr]
        out = self._convert(expr)
        self._memo[expr] = out
        return out

    def _convert(self, expr: sp.Basic) -> ca.SX:
        if isinstance(expr, sp.Symbol):
            try:
                return self.env[expr]
            except KeyError:
                raise KeyError(f"symbol {expr} is not an input") from None
        if expr is sp.true:
            return ca.SX(1.0)
        if expr is sp.false:
            return ca.SX(0.0)
        if isinstance(expr, sp.Expr) and expr.is_number:
            value = complex(expr.evalf(30))
            if value.imag != 0:
                raise ValueError(f"complex constant {expr}")
            return ca.SX(value.real)
        if isinstance(expr, sp.Add):
            args = [self(a) for a in expr.as_ordered_terms()]
            acc = args[0]
            for a in args[1:]:
                acc = acc + a
            return acc
        if isinstance(expr, sp.Mul):
            args = [self(a) for a in expr.as_ordered_factors()]
            acc = args[0]
            for a in args[1:]:
                acc = acc * a
            return acc
        if isinstance(expr, sp.Pow):
            return self._pow(expr)
        if isinstance(expr, sp.Piecewise):
            *pieces, (last, cond) = expr.args
            if cond is not sp.true:
                raise ValueError(f"Piecewise without a default branch: {expr}")
            out = self(last)
            for e, c in reversed(pieces):
                out = ca.if_else(self(c), self(e), out)
            return out
        if isinstance(expr, (sp.Max, sp.Min)):
            f = ca.fmax if isinstance(expr, sp.Max) else ca.fmin
            args = [self(a) for a in sp.ordered(expr.args)]
            out = args[-1]
            for a in reversed(args[:-1]):
                out = f(a, out)
            return out
        if type(expr) in _UNARY:
            return _UNARY[type(expr)](self(expr.args[0]))
        if isinstance(expr, sp.atan2):
            return ca.atan2(self(expr.args[0]), self(expr.args[1]))
        if isinstance(expr, sp.core.relational.Relational):
            lhs, rhs = self(expr.lhs), self(expr.rhs)
            ops: Mapping[str, Callable[[ca.SX, ca.SX], ca.SX]] = {
                "<": ca.lt,
                "<=": ca.le,
                ">": ca.gt,
                ">=": ca.ge,
                "==": ca.eq,
                "!=": ca.ne,
            }
            return ops[expr.rel_op](lhs, rhs)
        if isinstance(expr, (sp.And, sp.Or)):
            f2 = ca.logic_and if isinstance(expr, sp.And) else ca.logic_or
            args = [self(a) for a in sp.ordered(expr.args)]
            out = args[0]
            for a in args[1:]:
                out = f2(out, a)
            return out
        if isinstance(expr, sp.Not):
            return ca.logic_not(self(expr.args[0]))
        raise TypeError(f"cannot convert {type(expr).__name__} to CasADi: {expr}")

    def _pow(self, expr: sp.Pow) -> ca.SX:
        base = self(expr.base)
        e = expr.exp
        if isinstance(e, sp.Integer):
            n = int(e)
            return base**n if n > 0 else 1 / base ** (-n)
        if isinstance(e, sp.Rational) and e.q == 2:
            root = ca.sqrt(base)
            whole = abs(int(e.p)) // 2
            out = root * base**whole if whole else root
            return 1 / out if e.is_negative else out
        if e.free_symbols:
            return ca.power(base, self(e))
        return ca.power(base, ca.SX(float(e)))
