"""Expression printing shared by the C and Python printers and by the operation counter.

One mixin decides the *structure* of every printed expression (how a product splits into
numerator and denominator, how ``x**3`` becomes ``x*x*x``, how a ``Piecewise`` nests);
each backend only supplies the spelling (literals, function names, ternaries). Because the
operation counter is the same mixin with a spelling that counts, the "operations after
CSE" comment in every generated function is exactly what was printed.

Every construct is dispatched explicitly in :meth:`ExpressionPrinterMixin._print`:
anything not listed is an error, never a silent fallback to SymPy's default spelling
(which, in C, would be a double ``pow`` or an ``M_PI`` that does not exist in C99).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import sympy as sp

# SymPy function class -> neutral function name. Backends spell the neutral name
# (C: WMR_<NAME>, Python: math.<name>); the counter counts calls by neutral name.
FUNCTIONS: Mapping[type, str] = {
    sp.sin: "sin",
    sp.cos: "cos",
    sp.tan: "tan",
    sp.asin: "asin",
    sp.acos: "acos",
    sp.atan: "atan",
    sp.atan2: "atan2",
    sp.sinh: "sinh",
    sp.cosh: "cosh",
    sp.tanh: "tanh",
    sp.exp: "exp",
    sp.log: "log",
    sp.Abs: "fabs",
}

_RELATIONAL_OPS: Mapping[str, str] = {
    "<": "<",
    "<=": "<=",
    ">": ">",
    ">=": ">=",
    "==": "==",
    "!=": "!=",
}


def float_text(value: float) -> str:
    """Shortest round-trip decimal for a finite non-negative double, always a floating
    literal in C and Python (``2.0``, ``0.1``, ``1e-05``)."""
    if value != value or value in (float("inf"), float("-inf")):
        raise ValueError(f"cannot print non-finite literal {value}")
    text = repr(float(value))
    if "." not in text and "e" not in text:
        text += ".0"
    return text


def norm_terms(base: sp.Expr) -> tuple[sp.Expr, ...] | None:
    """The x_i of a base x0**2 + x1**2 + ... (two or more plain squares, in printed order):
    its square root is a 2-norm, printed through the backend's overflow-safe norm (an
    entry beyond ~1.8e19 overflows a float32 sum of squares while the norm is finite)."""
    if not isinstance(base, sp.Add):
        return None
    terms = base.as_ordered_terms()
    if not all(isinstance(t, sp.Pow) and t.exp == 2 for t in terms):
        return None
    return tuple(t.base for t in terms)


def _is_exact_binary(r: sp.Rational) -> bool:
    """True if p/q is exactly a double (q a power of two, p small): print as one literal."""
    q = int(r.q)
    return q & (q - 1) == 0 and abs(int(r.p)) < 2**53


def _is_sqrt(expr: sp.Expr) -> bool:
    """Whether ``expr`` prints as a square root (a power 1/2 of something variable)."""
    return isinstance(expr, sp.Pow) and expr.exp == sp.S.Half and bool(expr.free_symbols)


class ExpressionPrinterMixin:
    """Structure of printed arithmetic; subclasses provide the spelling hooks.

    Attributes set by the backend before printing: ``symbol_names`` maps every input
    symbol and every CSE temporary to the identifier that holds it.
    """

    symbol_names: Mapping[sp.Symbol, str]
    ops: Counter[str]

    # ----- spelling hooks (overridden by each backend) -----
    def lit(self, value: float) -> str:
        """A non-negative floating literal."""
        raise NotImplementedError

    def call(self, name: str, args: Sequence[str]) -> str:
        """A call of neutral function ``name`` (``sin``, ``sqrt``, ``fmax``, ``pow``...)."""
        raise NotImplementedError

    def ternary(self, cond: str, if_true: str, if_false: str) -> str:
        """A conditional expression, parenthesized."""
        raise NotImplementedError

    def infinity(self) -> str:
        """Positive infinity."""
        raise NotImplementedError

    def norm_call(self, args: Sequence[str]) -> str:
        """sqrt(args[0]**2 + args[1]**2 + ...), the sum as written out while it is finite,
        never overflowing when the norm itself is finite."""
        raise NotImplementedError

    logic_and = " && "
    logic_or = " || "
    logic_not = "!"
    true_text = "1"
    false_text = "0"

    # ----- public -----
    def expr_code(self, expr: sp.Basic) -> str:
        """Print one expression (counting its operations into ``self.ops``)."""
        return self._print(expr)

    # ----- dispatch -----
    def _print(self, expr: Any, **kwargs: Any) -> str:
        if isinstance(expr, sp.Symbol):
            try:
                return self.symbol_names[expr]
            except KeyError:
                raise KeyError(f"no variable holds symbol {expr}") from None
        if isinstance(expr, sp.Rational):  # includes Integer
            return self._rational(expr)
        if isinstance(expr, sp.Float):
            return self._signed_lit(float(expr))
        if expr is sp.S.Infinity:
            return self.infinity()
        if expr is sp.S.NegativeInfinity:
            return "-" + self.infinity()
        if isinstance(expr, sp.NumberSymbol):
            return self._signed_lit(float(expr.evalf(30)))
        if isinstance(expr, sp.Add):
            return self._add(expr)
        if isinstance(expr, sp.Mul):
            return self._mul(expr)
        if isinstance(expr, sp.Pow):
            return self._pow(expr)[0]
        if isinstance(expr, sp.Piecewise):
            return self._piecewise(expr)
        if isinstance(expr, (sp.Max, sp.Min)):
            return self._minmax(expr)
        if isinstance(expr, sp.Function) and type(expr) in FUNCTIONS:
            return self._function(expr)
        if isinstance(expr, sp.core.relational.Relational):
            return self._relational(expr)
        if isinstance(expr, (sp.And, sp.Or)):
            op = self.logic_and if isinstance(expr, sp.And) else self.logic_or
            parts = [f"({self._print(a)})" for a in sp.ordered(expr.args)]
            return "(" + op.join(parts) + ")"
        if isinstance(expr, sp.Not):
            return f"{self.logic_not}({self._print(expr.args[0])})"
        if expr is sp.true:
            return self.true_text
        if expr is sp.false:
            return self.false_text
        raise TypeError(f"cannot print {type(expr).__name__}: {expr}")

    # ----- numbers -----
    def _signed_lit(self, value: float) -> str:
        return "-" + self.lit(-value) if value < 0 else self.lit(value)

    def _rational(self, r: sp.Rational) -> str:
        if r.is_Integer or _is_exact_binary(r):
            return self._signed_lit(float(r))
        # A constant quotient: folded by the compiler, so not counted as an operation.
        sign = "-" if r < 0 else ""
        return f"{sign}{self.lit(float(abs(r.p)))}/{self.lit(float(r.q))}"

    def _constant(self, expr: sp.Expr) -> str:
        """A symbol-free subexpression (sqrt(2), sin(pi/7)) printed as one literal."""
        value = complex(expr.evalf(30))
        if value.imag != 0:
            raise ValueError(f"complex constant {expr}")
        return self._signed_lit(value.real)

    # ----- arithmetic -----
    def _add(self, expr: sp.Add) -> str:
        terms = expr.as_ordered_terms()
        out = self._print(terms[0])
        for term in terms[1:]:
            text = self._print(term)
            out += f" - {text[1:]}" if text.startswith("-") else f" + {text}"
        self.ops["add"] += len(terms) - 1
        return out

    def _factor(self, expr: sp.Expr) -> tuple[str, bool]:
        """Print one factor of a product; the flag says it is a single operand (no
        operators at top level), so it needs no parentheses after ``/``."""
        if isinstance(expr, sp.Pow):
            return self._pow(expr)
        text = self._print(expr)
        if isinstance(expr, sp.Add):
            return f"({text})", True
        if isinstance(expr, sp.Mul):  # unevaluated nested product
            return f"({text})", True
        return text, True

    def _mul(self, expr: sp.Mul) -> str:
        if not expr.free_symbols:
            return self._constant(expr)
        coeff, rest = expr.as_coeff_Mul()
        factors = list(rest.as_ordered_factors())
        constants = [f for f in factors if not f.free_symbols]
        if constants:  # pi/2*x: one literal, as a compiler would fold it
            coeff = sp.Float(sp.Mul(coeff, *constants).evalf(30), 30)
            factors = [f for f in factors if f.free_symbols]
        sign = ""
        if coeff.is_negative:
            sign, coeff = "-", -coeff
        num: list[tuple[str, bool]] = []
        den: list[tuple[str, bool]] = []
        for factor in factors:
            if (
                isinstance(factor, sp.Pow)
                and factor.exp.is_Rational
                and factor.exp.is_negative
                and factor.free_symbols
            ):
                den.append(self._factor(sp.Pow(factor.base, -factor.exp)))
            else:
                num.append(self._factor(factor))
        if coeff != 1:
            # One literal, the double nearest the coefficient (2/3*x: 0.6666666666666666*x):
            # a multiplication where p*x/q would divide at run time (the compiler may not
            # fold x/3 into a product); at most one rounding more, as CasADi's C prints it.
            num.insert(0, (self.lit(float(coeff)), True))
        if not num:
            num.append((self.lit(1.0), True))
        out = "*".join(text for text, _ in num)
        self.ops["mul"] += len(num) - 1
        if den:
            self.ops["div"] += 1
            self.ops["mul"] += len(den) - 1
            divisor = den[0][0] if len(den) == 1 and den[0][1] else (
                "(" + "*".join(text for text, _ in den) + ")")
            if any(_is_sqrt(f) for f in factors):
                # sqrt(a)/d as sqrt(a)*(1/d): the reciprocal runs beside the square root
                # instead of after it (||Mhat^-1||_F of (25) is on a step's chain to tau;
                # the trailer's frozen step 1.04-1.10x -> 0.97-1.00x its hand-written one)
                self.ops["mul"] += 1
                out += "*(" + self.lit(1.0) + "/" + divisor + ")"
            else:
                out += "/" + divisor
        return sign + out

    def _repeat(self, base: sp.Expr, n: int) -> str:
        """``base`` multiplied by itself ``n`` times; printed (and counted) ``n`` times
        because that is what runs (CSE hoists compound bases, so it is a variable)."""
        parts = []
        for _ in range(n):
            text = self._print(base)
            parts.append(text if isinstance(base, (sp.Symbol, sp.Function)) else f"({text})")
        self.ops["mul"] += n - 1
        return "*".join(parts)

    def _pow(self, expr: sp.Pow) -> tuple[str, bool]:
        """Integer powers as repeated products, half-integer powers through sqrt, other
        exponents through pow. The flag is True if the text is a single operand."""
        if not expr.free_symbols:
            return self._constant(expr), True
        base, exponent = expr.base, expr.exp
        if exponent in (sp.S.Half, -sp.S.Half) and (terms := norm_terms(base)) is not None:
            text = self._norm(terms)
            if exponent.is_negative:
                self.ops["div"] += 1
                return f"{self.lit(1.0)}/{text}", False
            return text, True
        if isinstance(exponent, sp.Rational) and exponent.q in (1, 2):
            whole = abs(int(exponent.p)) // int(exponent.q)
            parts: list[str] = []
            if whole:
                parts.append(self._repeat(base, whole))
            if exponent.q == 2:
                self.ops["sqrt"] += 1
                parts.append(self.call("sqrt", [self._print(base)]))
            self.ops["mul"] += len(parts) - 1
            text = "*".join(parts)
            single = len(parts) == 1 and (whole <= 1)
            if exponent.is_negative:
                self.ops["div"] += 1
                return f"{self.lit(1.0)}/{text if single else f'({text})'}", False
            return text, single
        self.ops["pow"] += 1
        return self.call("pow", [self._print(base), self._print(exponent)]), True

    def _norm(self, terms: Sequence[sp.Expr]) -> str:
        """A 2-norm: the squares and their sum, the test that the sum is finite, the root."""
        self.ops["mul"] += len(terms)
        self.ops["add"] += len(terms) - 1
        self.ops["cmp"] += 1
        self.ops["sqrt"] += 1
        return self.norm_call([self._print(t) for t in terms])

    # ----- functions and branches -----
    def _function(self, expr: sp.Function) -> str:
        if not expr.free_symbols:
            return self._constant(expr)
        name = FUNCTIONS[type(expr)]
        self.ops[name] += 1
        return self.call(name, [self._print(a) for a in expr.args])

    def _minmax(self, expr: sp.Expr) -> str:
        name = "fmax" if isinstance(expr, sp.Max) else "fmin"
        args = [self._print(a) for a in sp.ordered(expr.args)]
        out = args[-1]
        for a in reversed(args[:-1]):
            self.ops[name] += 1
            out = self.call(name, [a, out])
        return out

    def _relational(self, expr: sp.Expr) -> str:
        self.ops["cmp"] += 1
        op = _RELATIONAL_OPS[expr.rel_op]
        return f"{self._print(expr.lhs)} {op} {self._print(expr.rhs)}"

    def _piecewise(self, expr: sp.Piecewise) -> str:
        pieces = list(expr.args)
        last_expr, last_cond = pieces[-1]
        if last_cond is not sp.true:
            raise ValueError(f"Piecewise without a default branch: {expr}")
        out = self._print(last_expr)
        for e, c in reversed(pieces[:-1]):
            out = self.ternary(self._print(c), self._print(e), out)
        return out


class CountingPrinter(ExpressionPrinterMixin):
    """The mixin with placeholder spelling: printing an expression counts its operations."""

    def __init__(self, symbol_names: Mapping[sp.Symbol, str]) -> None:
        self.symbol_names = symbol_names
        self.ops = Counter()

    def lit(self, value: float) -> str:
        return float_text(value)

    def call(self, name: str, args: Sequence[str]) -> str:
        return f"{name}({', '.join(args)})"

    def ternary(self, cond: str, if_true: str, if_false: str) -> str:
        return f"({cond} ? {if_true} : {if_false})"

    def infinity(self) -> str:
        return "inf"

    def norm_call(self, args: Sequence[str]) -> str:
        return f"norm({', '.join(args)})"
