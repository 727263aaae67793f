"""Affine enclosures of the exact values: the dependency interval arithmetic loses.

A determinant ``a c - b b`` of entries that move together over a box is far narrower
than the interval product of its entries says (each input appearing in several entries);
over a parameter box of ±20 % the intervals of the forward dynamics' divisors contain 0
while the divisors never come near it. An affine form ``c + Σ A_i ε_i ± r`` (one noise
symbol ε_i ∈ [-1, 1] per input, the nonlinear rest in one radius ``r``; "reduced" affine
arithmetic) keeps that first-order dependency: products and the nonlinear functions
(``1/y``, sin, cos, sqrt) by a Taylor expansion at the centre with a rigorous remainder
(``|f''| w²/2`` over the enclosure). Every double computation adds ``2^-50`` of its
operands' magnitude to ``r``. The result is intersected with the interval enclosure by
:class:`~codegen.backends.c.certify.analysis.Analysis`; it only ever narrows what is sound.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from codegen.backends.c.certify.program import Program

Array = npt.NDArray[np.float64]
SLACK = 2.0**-50
LIT_REL = 2.0**-53


@dataclass
class Affine:
    c: Array  # (B,)
    a: Array  # (B, d)
    r: Array  # (B,) >= 0

    def radius(self) -> Array:
        return np.abs(self.a).sum(axis=1) + self.r

    def bounds(self) -> tuple[Array, Array]:
        rad = self.radius() * (1 + SLACK)
        return self.c - rad - SLACK * np.abs(self.c), self.c + rad + SLACK * np.abs(self.c)


def _from_interval(lo: Array, hi: Array, d: int) -> Affine:
    c = 0.5 * (lo + hi)
    r = np.maximum(hi - c, c - lo) * (1 + SLACK)
    return Affine(c, np.zeros((len(lo), d)), np.where(np.isfinite(r), r, np.inf))


def _mul(x: Affine, y: Affine) -> Affine:
    ax, ay = np.abs(x.a).sum(axis=1), np.abs(y.a).sum(axis=1)
    c = x.c * y.c
    a = x.c[:, None] * y.a + y.c[:, None] * x.a
    r = (np.abs(x.c) * y.r + np.abs(y.c) * x.r + (ax + x.r) * (ay + y.r)
         + SLACK * (np.abs(c) + np.abs(x.c) * ay + np.abs(y.c) * ax))
    return Affine(c, a, r)


def _taylor(x: Affine, f0: Array, f1: Array, f2max: Array) -> Affine:
    """f(x) ≈ f0 + f1 (x - c), remainder ≤ f2max w²/2 with w the radius of x."""
    w = x.radius()
    r = np.abs(f1) * x.r + 0.5 * f2max * w * w + SLACK * (np.abs(f0) + np.abs(f1) * w) + 1e-300
    return Affine(f0, f1[:, None] * x.a, r)


def affine_bounds(program: Program, lo: Mapping[int, Array], hi: Mapping[int, Array],
                  known: Mapping[int, tuple[float, float]] | None = None
                  ) -> list[tuple[Array, Array] | None]:
    """Per node, an enclosure of its exact value over each box (None: a condition).
    ``known``: proved enclosures of some nodes over the whole box; where a node's form
    does not exclude 0 (or is unbounded) and the proved one does, its form restarts from
    the intersection (a new affine form with no dependency: sound, and it keeps a
    divisor's 1/y finite)."""
    known = known or {}
    inputs = sorted(lo)
    col = {n: k for k, n in enumerate(inputs)}
    d = len(inputs)
    b = len(lo[inputs[0]])
    forms: list[Affine | None] = []
    out: list[tuple[Array, Array] | None] = []
    truth: dict[int, tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]] = {}
    with np.errstate(all="ignore"):
        for idx, node in enumerate(program.nodes):
            op = node.op
            f: Affine | None = None
            args = [forms[i] for i in node.args]
            if op == "in":
                a = np.zeros((b, d))
                c = 0.5 * (lo[idx] + hi[idx])
                a[:, col[idx]] = 0.5 * (hi[idx] - lo[idx])
                f = Affine(c, a, SLACK * np.abs(c) + np.abs(a[:, col[idx]]) * SLACK)
            elif op == "lit":
                v = node.value
                f = Affine(np.full(b, v), np.zeros((b, d)), np.full(b, LIT_REL * abs(v)))
            elif op == "neg":
                x = args[0]
                assert x is not None
                f = Affine(-x.c, -x.a, x.r)
            elif op in ("add", "sub"):
                x, y = args
                assert x is not None and y is not None
                s = 1.0 if op == "add" else -1.0
                c = x.c + s * y.c
                a = x.a + s * y.a
                f = Affine(c, a, x.r + y.r + SLACK * (np.abs(x.c) + np.abs(y.c)
                                                     + np.abs(x.a).sum(axis=1)
                                                     + np.abs(y.a).sum(axis=1)))
            elif op == "mul":
                x, y = args
                assert x is not None and y is not None
                f = _mul(x, y)
            elif op == "div":
                x, y = args
                assert x is not None and y is not None
                ylo, yhi = y.bounds()
                safe = (ylo > 0) | (yhi < 0)
                m = np.where(safe, np.minimum(np.abs(ylo), np.abs(yhi)), 1.0)
                inv = _taylor(y, 1.0 / y.c, -1.0 / (y.c * y.c), 2.0 / (m * m * m))
                f = _mul(x, inv)
                f.r = np.where(safe, f.r, np.inf)
            elif op == "call" and node.name in ("sin", "cos", "sin_bounded", "cos_bounded"):
                x = args[0]
                assert x is not None
                if node.name.startswith("sin"):
                    f = _taylor(x, np.sin(x.c), np.cos(x.c), np.ones(b))
                else:
                    f = _taylor(x, np.cos(x.c), -np.sin(x.c), np.ones(b))
                f.r = f.r + 1e-15
            elif op == "call" and node.name == "sqrt":
                x = args[0]
                assert x is not None
                xlo, _ = x.bounds()
                ok = xlo > 0
                m = np.where(ok, xlo, 1.0)
                sc = np.sqrt(np.maximum(x.c, 0.0))
                f = _taylor(x, sc, np.where(sc > 0, 0.5 / sc, 0.0), 0.25 * m**-1.5)
                f.r = np.where(ok, f.r + 1e-300, np.inf)
            elif op in ("lt", "le", "gt", "ge"):
                x, y = args
                assert x is not None and y is not None
                if op in ("gt", "ge"):
                    x, y = y, x
                xl, xh = x.bounds()
                yl, yh = y.bounds()
                sure_t = xh < yl if op in ("lt", "gt") else xh <= yl
                sure_f = xl >= yh if op in ("lt", "gt") else xl > yh
                truth[idx] = (sure_t, sure_f)
            elif op == "cond":
                x, y = args[1], args[2]
                assert x is not None and y is not None
                st, sf = truth.get(node.args[0], (np.zeros(b, bool), np.zeros(b, bool)))
                xl, xh = x.bounds()
                yl, yh = y.bounds()
                hull = _from_interval(np.minimum(xl, yl), np.maximum(xh, yh), d)
                f = Affine(np.where(st, x.c, np.where(sf, y.c, hull.c)),
                           np.where(st[:, None], x.a, np.where(sf[:, None], y.a, hull.a)),
                           np.where(st, x.r, np.where(sf, y.r, hull.r)))
            elif op == "call":  # fabs, fmax, fmin: from the enclosures of the arguments
                bounds = [a.bounds() for a in args if a is not None]
                if node.name == "fabs":
                    lo_, hi_ = bounds[0]
                    pos, neg = lo_ >= 0, hi_ <= 0
                    x = args[0]
                    assert x is not None
                    mag = np.maximum(np.abs(lo_), np.abs(hi_))
                    mig = np.where(pos | neg, np.minimum(np.abs(lo_), np.abs(hi_)), 0.0)
                    h = _from_interval(mig, mag, d)
                    f = Affine(np.where(pos, x.c, np.where(neg, -x.c, h.c)),
                               np.where(pos[:, None], x.a, np.where(neg[:, None], -x.a, h.a)),
                               np.where(pos | neg, x.r, h.r))
                else:
                    (al, ah), (bl, bh) = bounds
                    g = np.maximum if node.name == "fmax" else np.minimum
                    f = _from_interval(g(al, bl), g(ah, bh), d)
            # and, or, not: conditions with no value
            if f is not None and idx in known:
                flo, fhi = f.bounds()
                klo = np.maximum(np.where(np.isfinite(flo), flo, -np.inf), known[idx][0])
                khi = np.minimum(np.where(np.isfinite(fhi), fhi, np.inf), known[idx][1])
                # a form whose range contains 0 (1/y's Taylor expansion would fail): it
                # restarts; one that excludes 0 keeps its dependencies
                wider = ~((flo > 0) | (fhi < 0)) | ~np.isfinite(f.r)
                h = _from_interval(klo, khi, d)
                f = Affine(np.where(wider, h.c, f.c), np.where(wider[:, None], h.a, f.a),
                           np.where(wider, h.r, f.r))
            forms.append(f)
            if f is None:
                out.append(None)
            else:
                f.r = np.where(np.isnan(f.r) | np.isnan(f.c), np.inf, f.r)
                lo_, hi_ = f.bounds()
                out.append((np.where(np.isfinite(lo_), lo_, -np.inf),
                            np.where(np.isfinite(hi_), hi_, np.inf)))
    return out
