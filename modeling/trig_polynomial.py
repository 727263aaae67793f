"""Expressions of a few angles as trigonometric polynomials with constant coefficients.

A trailer's M̂(q) depends on q only through sin and cos of its hitch angles: each entry is
a polynomial in ``s = sin ψ``, ``c = cos ψ`` whose coefficients are parameter expressions
(one trailer: ``m0 + m1 c² + m2 s c``). Written so, a controller evaluates the coefficients
once (``_init`` keeps every parameter-only subexpression) and a step only the monomials
and one multiply-add per coefficient: what a careful engineer writes by hand (the trailer
entries as ``m0 + mc cos 2ψ + ms sin 2ψ``). The staged form evaluates M̂ through the
chain's congruences instead, which grows linearly with the bodies where this form's
monomials multiply (75 per entry for three trailers): the caller keeps the form with fewer
per-step operations, and ``budget`` stops the expansion once it cannot win.

``s² = 1 − c²`` reduces every monomial to degree at most one in each ``s``, so the basis
``s^a c^b`` (a ≤ 1) is unique. The polynomial is built through the staged quantities'
definitions (each once, not substituted into a tree), so its cost follows the monomials.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import sympy as sp

Monomial = tuple[int, ...]  # (power of sin a0, of cos a0, power of sin a1, ...)
Polynomial = dict[Monomial, sp.Expr]


class _TooLarge(Exception):
    """A polynomial grew past the budget."""


class _NotTrigonometric(Exception):
    """A coordinate enters otherwise than through sin and cos."""


def trig_polynomial(exprs: Sequence[sp.Expr], coordinates: Sequence[sp.Symbol],
                    definitions: Sequence[tuple[sp.Symbol, sp.Expr]] = (),
                    budget: int | None = None) -> list[sp.Expr] | None:
    """``exprs`` (which may read the quantities ``definitions`` defines, in evaluation
    order) as ``Σ coefficient · monomial``: each monomial a product of powers of ``sin a``
    and ``cos a`` over the arguments ``a`` of the sines and cosines that involve
    ``coordinates`` (sin to the power 0 or 1), each coefficient free of ``coordinates``
    and of the defined quantities. Mathematically equal to ``exprs``. None when a
    coordinate enters otherwise (bare, or in a denominator), or when a polynomial on the
    way has more than ``budget`` monomials."""
    builder = _Builder(frozenset(coordinates), dict(definitions), budget)
    try:
        polys = [builder.of(sp.sympify(e)) for e in exprs]
    except (_TooLarge, _NotTrigonometric):
        return None
    return [builder.expression(p) for p in polys]


class _Builder:
    def __init__(self, coordinates: frozenset[sp.Symbol], definitions: Mapping[sp.Symbol, sp.Expr],
                 budget: int | None) -> None:
        self.coordinates = coordinates
        self.definitions = definitions
        self.budget = budget
        self.arguments: list[sp.Expr] = []  # the angles met so far, in order
        self.memo: dict[sp.Basic, Polynomial] = {}

    def of(self, e: sp.Basic) -> Polynomial:
        hit = self.memo.get(e)
        if hit is None:
            hit = self._of(e)
            if self.budget is not None and len(hit) > self.budget:
                raise _TooLarge
            self.memo[e] = hit
        return hit

    def _of(self, e: sp.Basic) -> Polynomial:
        if e in self.definitions:
            return self.of(self.definitions[e])
        if not self._varies(e):  # the defined quantities it reads are constants too
            value = {s: self.of(s).get((), sp.S.Zero)
                     for s in e.free_symbols if s in self.definitions}
            return {(): sp.sympify(e).xreplace(value)}
        if isinstance(e, (sp.sin, sp.cos)):
            if e.args[0] not in self.arguments:
                self.arguments.append(e.args[0])
            k = self.arguments.index(e.args[0])
            return {(0,) * (2 * k) + ((1, 0) if isinstance(e, sp.sin) else (0, 1)): sp.S.One}
        if isinstance(e, sp.Add):
            total: Polynomial = {}
            for a in e.args:
                _accumulate(total, self.of(a))
            return total
        if isinstance(e, sp.Mul):
            product: Polynomial = {(): sp.S.One}
            for a in e.args:
                product = self._product(product, self.of(a))
            return product
        if isinstance(e, sp.Pow) and e.exp.is_Integer and int(e.exp) > 0:
            base = self.of(e.base)
            power: Polynomial = {(): sp.S.One}
            for _ in range(int(e.exp)):
                power = self._product(power, base)
            return power
        raise _NotTrigonometric  # a bare coordinate, a varying denominator, ...

    def _varies(self, e: sp.Basic) -> bool:
        """Whether ``e`` reads a coordinate, directly or through a definition."""
        for s in e.free_symbols:
            if s in self.coordinates:
                return True
            if s in self.definitions and self.of(s).keys() - {()}:
                return True
        return False

    def _product(self, a: Polynomial, b: Polynomial) -> Polynomial:
        out: Polynomial = {}
        for ma, ca in a.items():
            for mb, cb in b.items():
                for m, sign in _reduced(_added(ma, mb)):
                    out[m] = out.get(m, sp.S.Zero) + sign * ca * cb
        out = {m: c for m, c in out.items() if c != 0}
        if self.budget is not None and len(out) > self.budget:
            raise _TooLarge
        return out

    def expression(self, poly: Polynomial) -> sp.Expr:
        width = 2 * len(self.arguments)
        gens = [f(a) for a in self.arguments for f in (sp.sin, sp.cos)]
        terms = sorted((m + (0,) * (width - len(m)), c) for m, c in poly.items())
        return sp.Add(*(sp.Mul(c, *(g ** p for g, p in zip(gens, m, strict=True)))
                        for m, c in terms if c != 0))


def _accumulate(total: Polynomial, part: Polynomial) -> None:
    """``total += part``, dropping the monomials that cancel."""
    for m, c in part.items():
        key = _trimmed(m)
        total[key] = total.get(key, sp.S.Zero) + c
        if total[key] == 0:
            del total[key]


def _added(a: Monomial, b: Monomial) -> Monomial:
    n = max(len(a), len(b))
    return tuple((a[i] if i < len(a) else 0) + (b[i] if i < len(b) else 0) for i in range(n))


def _trimmed(m: Monomial) -> Monomial:
    """``m`` without trailing zero powers: one key for each monomial, whatever the number
    of angles known when it was made."""
    end = len(m)
    while end and m[end - 1] == 0:
        end -= 1
    return m[:end]


def _reduced(m: Monomial) -> list[tuple[Monomial, int]]:
    """``m`` with ``sin² = 1 − cos²`` applied until every sine's power is 0 or 1, as signed
    monomials."""
    m = (*m, *(0,) * (len(m) % 2))  # a trimmed monomial may end at a sine
    for k in range(0, len(m), 2):
        if m[k] >= 2:
            lower = (*m[:k], m[k] - 2, *m[k + 1:])
            raised = (*m[:k], m[k] - 2, m[k + 1] + 2, *m[k + 2:])
            return [*_reduced(lower), *((r, -s) for r, s in _reduced(raised))]
    return [(_trimmed(m), 1)]
