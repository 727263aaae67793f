"""Certified enclosures of the divisors over the whole declared box, by subdivision in the
few inputs each divisor depends on.

A mass-matrix determinant such as ``det(S^T M S)`` depends on the configuration angles and
the parameters only, never on the rates or torques beside it in the box; and over two
turns of an angle, interval and affine enclosures of its rotated entries contain 0 unless
the angle is cut fine. Splitting the whole box (rates and torques included) to that
fineness is out of reach; splitting only the divisor's own inputs is not: the inputs a
node depends on are read off the expression graph, and a branch and bound over those
dimensions (every other input at its declared range, on which the node does not depend)
proves an interval ``[lo, hi]`` of one sign enclosing the node's exact value over the
whole box. :class:`~codegen.backends.c.certify.analysis.Analysis` intersects it with its
own enclosure in every box of the main subdivision (it holds in each sub-box), so the
division's error rule ``Ea/|fb| + |xa| Eb/(|fb||xb|)`` is carried with that denominator
bound. The enclosure is sound because each piece's is (the pieces cover the box), and a
node of one sign on every piece of a connected box needs no continuity argument: the
union of the pieces' enclosures is the enclosure.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from codegen.backends.c.certify.analysis import (
    Analysis,
    Array,
    Value,
    _div_iv,
    _down,
    _mul_iv,
    _trig_iv,
    _up,
)
from codegen.backends.c.certify.program import Program

DEBUG = False


@dataclass(frozen=True)
class Pieces:
    """The final pieces of a divisor's branch and bound: boxes over the input nodes
    ``dims`` (rows of ``lo``/``hi``, columns in ``dims``' order) that cover the declared
    box's extent in them, split finest where the divisor's magnitude is smallest."""

    dims: tuple[int, ...]
    lo: npt.NDArray[np.float64]
    hi: npt.NDArray[np.float64]


@dataclass(frozen=True)
class Enclosure:
    """A proved enclosure of node ``node``'s exact value over the whole box."""

    node: int
    lo: float
    hi: float
    dims: tuple[int, ...]  # the input nodes it depends on (split)
    boxes: int
    seconds: float


def dependencies(program: Program) -> list[frozenset[int]]:
    """Per node, the input nodes its value depends on."""
    deps: list[frozenset[int]] = []
    for idx, node in enumerate(program.nodes):
        if node.op == "in":
            deps.append(frozenset((idx,)))
        else:
            deps.append(frozenset().union(*(deps[a] for a in node.args)))
    return deps


def _prefix(program: Program, node: int) -> Program:
    """The program up to ``node``, with ``node`` its only output (no guards)."""
    sub = Program(program.function, program.nodes[:node + 1],
                  {s: n for s, n in program.inputs.items() if n <= node},
                  {s: a for s, a in program.input_names.items() if program.inputs[s] <= node})
    sub.outputs.append(("divisor", node))
    return sub


def divisor_enclosures(program: Program, lo: Mapping[int, float], hi: Mapping[int, float],
                       *, seconds: float = 4.0, max_boxes: int = 20000, batch: int = 64,
                       pieces: dict[int, Pieces] | None = None,
                       ) -> tuple[dict[int, tuple[float, float]], list[str]]:
    """Enclosures of the exact value of every divisor that the interval and affine
    enclosures over the whole box (``lo``/``hi`` per input node) do not prove nonzero.
    Returns the proved enclosures (node -> (lo, hi)) and, per divisor left unproved, why.
    ``pieces``, if given, receives per proved divisor the branch and bound's final pieces
    (:class:`Pieces`: they cover the box in the divisor's inputs, finest where it is
    smallest)."""
    deps = dependencies(program)
    known: dict[int, tuple[float, float]] = {}
    failed: list[str] = []
    start = time.process_time()
    one = {n: np.array([lo[n]]) for n in lo}
    two = {n: np.array([hi[n]]) for n in hi}
    for idx, node in enumerate(program.nodes):
        if node.op != "div":
            continue
        d = node.args[1]
        while program.nodes[d].op == "neg" or (program.nodes[d].op == "call"
                                               and program.nodes[d].name == "fabs"):
            d = program.nodes[d].args[0]  # |x| or -x excludes 0 where x does
        if d in known:
            continue
        sub = _prefix(program, d)
        analysis = Analysis(sub, known=known)
        vals, _, _ = analysis.run({n: one[n] for n in deps[d] | _inputs(sub)},
                                  {n: two[n] for n in deps[d] | _inputs(sub)})
        if vals[0].xlo[0] > 0 or vals[0].xhi[0] < 0:
            continue
        budget = max(seconds - (time.process_time() - start), 0.0)
        found = _branch_and_bound(sub, sorted(deps[d]), one, two, known, budget, max_boxes,
                                  batch, pieces, d)
        if found is None:
            failed.append(f"node {idx} (div): its divisor's enclosure over "
                          f"{len(deps[d])} inputs still contains 0")
        else:
            known[d] = found
    return known, failed


def derivatives(program: Program, values: Sequence[object], wrt: list[int]
                ) -> tuple[Array, Array]:
    """Interval enclosures (lo, hi: boxes x ``wrt``) of the partial derivatives of the
    last node of ``program`` with respect to the input nodes ``wrt``, over the boxes
    whose node enclosures ``values`` are (forward mode, interval arithmetic on the
    enclosures; an operation with no derivative rule here gives an unbounded one)."""
    first = next(v for v in values if isinstance(v, Value))
    assert isinstance(first, Value)
    b, k = len(first.xlo), len(wrt)
    col = {n: j for j, n in enumerate(wrt)}
    zero = np.zeros((b, k))
    inf = np.full((b, k), np.inf)
    d: list[tuple[Array, Array]] = []

    def x(i: int) -> tuple[Array, Array]:
        v = values[i]
        assert isinstance(v, Value)
        return v.xlo[:, None], v.xhi[:, None]

    with np.errstate(all="ignore"):
        for idx, node in enumerate(program.nodes):
            op, a = node.op, node.args
            if op == "in":
                lo = zero.copy()
                if idx in col:
                    lo[:, col[idx]] = 1.0
                d.append((lo, lo.copy()))
            elif op == "lit":
                d.append((zero, zero))
            elif op == "neg":
                d.append((-d[a[0]][1], -d[a[0]][0]))
            elif op == "add":
                d.append((_down(d[a[0]][0] + d[a[1]][0]), _up(d[a[0]][1] + d[a[1]][1])))
            elif op == "sub":
                d.append((_down(d[a[0]][0] - d[a[1]][1]), _up(d[a[0]][1] - d[a[1]][0])))
            elif op == "mul":  # da y + x db
                p = _mul_iv(*d[a[0]], *x(a[1]))
                q = _mul_iv(*x(a[0]), *d[a[1]])
                d.append((_down(p[0] + q[0]), _up(p[1] + q[1])))
            elif op == "div":  # (da - (x/y) db) / y
                qlo, qhi = _div_iv(*x(a[0]), *x(a[1]))
                p = _mul_iv(qlo, qhi, *d[a[1]])
                num = (_down(d[a[0]][0] - p[1]), _up(d[a[0]][1] - p[0]))
                d.append(_div_iv(*num, *x(a[1])))
            elif op == "call" and node.name in ("sin", "cos", "sin_bounded", "cos_bounded"):
                xl, xh = x(a[0])
                # d sin = cos dx, d cos = -sin dx
                if node.name.startswith("sin"):
                    fl, fh = _trig_iv("cos", xl, xh)
                else:
                    sl, sh = _trig_iv("sin", xl, xh)
                    fl, fh = -sh, -sl
                d.append(_mul_iv(fl, fh, *d[a[0]]))
            elif op == "call" and node.name == "fabs":  # +-dx where x has one sign
                xl, xh = x(a[0])
                dl, dh = d[a[0]]
                d.append((np.where(xl > 0, dl, np.where(xh < 0, -dh, -np.inf)),
                          np.where(xl > 0, dh, np.where(xh < 0, -dl, np.inf))))
            elif op == "call" and node.name == "sqrt":  # dx / (2 sqrt x)
                sl, sh = x(idx)
                d.append(_div_iv(*d[a[0]], _down(2 * sl), _up(2 * sh)))
            else:
                d.append((-inf, inf))
    lo, hi = d[-1]
    bad = np.isnan(lo) | np.isnan(hi)
    return np.where(bad, -np.inf, lo), np.where(bad, np.inf, hi)


def _inputs(program: Program) -> set[int]:
    return set(program.inputs.values())


def _branch_and_bound(sub: Program, dims: list[int], lo: Mapping[int, Array],
                      hi: Mapping[int, Array], known: Mapping[int, tuple[float, float]],
                      seconds: float, max_boxes: int, batch: int,
                      pieces: dict[int, Pieces] | None = None, node: int = -1,
                      ) -> tuple[float, float] | None:
    """Split the pieces (over ``dims``) whose lower bound of the node's magnitude is
    smallest, each along the dimension whose halving raises that bound most, until every
    piece excludes 0 with the sign of the node at the box's centre and the smallest
    bound is within a factor 2 of the smallest value seen at a piece's centre (or the
    budget ends with 0 excluded); None if 0 is not excluded when the budget ends. The
    final pieces go to ``pieces[node]`` when given."""
    start = time.process_time()
    others = sorted(_inputs(sub) - set(dims))
    analysis = Analysis(sub, known=known)
    # the parameters (struct fields): a mean-value form over them
    mv = [k for k, n in enumerate(dims) if "->" in sub.nodes[n].name]

    def enclose(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]
                ) -> tuple[Array, Array, Array]:
        """The node's enclosure over each piece, and each dimension's share of its width
        (|derivative| x width: the dimension to split)."""
        la = {n: a[:, k] for k, n in enumerate(dims)}
        hb = {n: b[:, k] for k, n in enumerate(dims)}
        for n in others:
            la[n] = np.full(len(a), float(lo[n][0]))
            hb[n] = np.full(len(a), float(hi[n][0]))
        vals, _, _ = analysis.run(la, hb)
        xl, xh = vals[0].xlo, vals[0].xhi
        glo, ghi = derivatives(sub, analysis.values, dims)
        with np.errstate(invalid="ignore"):
            smear = np.maximum(np.abs(glo), np.abs(ghi)) * (b - a)
        smear = np.where(np.isnan(smear), np.inf, smear)
        if not mv:
            return xl, xh, smear
        # mean value in the parameters: f(c) + G (p - c), f(c) with the parameters at the
        # piece's centre (the other dimensions over the piece), G the derivatives' enclosure
        c = a.copy()
        c[:, mv] = 0.5 * (a[:, mv] + b[:, mv])
        cb = b.copy()
        cb[:, mv] = c[:, mv]
        la2 = {n: c[:, k] for k, n in enumerate(dims)}
        hb2 = {n: cb[:, k] for k, n in enumerate(dims)}
        for n in others:
            la2[n], hb2[n] = la[n], hb[n]
        cv, _, _ = analysis.run(la2, hb2)
        ml, mh = cv[0].xlo, cv[0].xhi
        for k in mv:
            tl, th = _mul_iv(glo[:, k], ghi[:, k], _down(a[:, k] - c[:, k]),
                             _up(b[:, k] - c[:, k]))
            ml, mh = _down(ml + tl), _up(mh + th)
        ml = np.where(np.isfinite(ml), ml, -np.inf)
        mh = np.where(np.isfinite(mh), mh, np.inf)
        return np.maximum(xl, ml), np.minimum(xh, mh), smear

    blo = np.array([[float(lo[n][0]) for n in dims]])
    bhi = np.array([[float(hi[n][0]) for n in dims]])
    width = np.where(bhi[0] > blo[0], bhi[0] - blo[0], 1.0)
    mid = 0.5 * (blo + bhi)
    c_lo, c_hi, _ = enclose(mid, mid)
    sign = 1.0 if c_lo[0] > 0 else -1.0 if c_hi[0] < 0 else 0.0
    if sign == 0.0:
        return None  # 0 at (or within the enclosure of) the centre
    smallest = float(min(abs(c_lo[0]), abs(c_hi[0])))

    def bound(xl: Array, xh: Array) -> Array:
        return np.where(sign > 0, xl, -xh)  # the lower bound of sign * node

    xlo, xhi, smear = enclose(blo, bhi)
    while True:
        low = bound(xlo, xhi)
        if low.min() > 0 and float(low.min()) >= 0.5 * smallest:
            break
        if len(blo) + batch > max_boxes or time.process_time() - start > seconds:
            if low.min() > 0:
                break
            return None
        if DEBUG:
            print(len(blo), float(low.min()), smallest,
                  np.round(np.log2(width / (bhi - blo)[np.argmin(low)]), 1))
        chosen = np.argsort(low)[:batch]
        # halve each along the side that contributes most to its enclosure's width
        # (|derivative| x width; the widest relative side where a derivative is unbounded)
        sm = smear[chosen]
        rel = (bhi[chosen] - blo[chosen]) / width
        k = np.where(np.isfinite(sm).all(axis=1), np.where(np.isfinite(sm), sm, 0).argmax(axis=1),
                     rel.argmax(axis=1))
        rows = np.arange(len(chosen))
        m = 0.5 * (blo[chosen, k] + bhi[chosen, k])
        alo, ahi = blo[chosen].copy(), bhi[chosen].copy()
        ahi[rows, k] = m
        clo, chi = blo[chosen].copy(), bhi[chosen].copy()
        clo[rows, k] = m
        nlo, nhi = np.concatenate([alo, clo]), np.concatenate([ahi, chi])
        nxlo, nxhi, nsm = enclose(nlo, nhi)
        cm = 0.5 * (nlo + nhi)
        cl, ch, _ = enclose(cm, cm)
        smallest = min(smallest, float(np.min(np.minimum(np.abs(cl), np.abs(ch)))))
        keep = np.ones(len(blo), dtype=bool)
        keep[chosen] = False
        blo, bhi = np.concatenate([blo[keep], nlo]), np.concatenate([bhi[keep], nhi])
        xlo = np.concatenate([xlo[keep], nxlo])
        xhi = np.concatenate([xhi[keep], nxhi])
        smear = np.concatenate([smear[keep], nsm])
    if pieces is not None:
        pieces[node] = Pieces(tuple(dims), blo, bhi)
    return float(xlo.min()), float(xhi.max())
