"""The adversarial search where a divisor is smallest: the points a uniform sample of the
box misses and where a quotient's error is largest.

A quotient ``a / b`` turns ``b``'s rounding ``δb`` into ``|a/b| δb / |b|``: the error grows
as ``1/|b|²`` where ``b`` (a mass-matrix determinant, say) is smallest. ``b`` depends on
a few of the box's inputs only (the angles and parameters, read off the expression graph
by :func:`~codegen.backends.c.certify.divisors.dependencies`), and its smallest magnitude
sits in a thin region of them (a hitch angle near where the determinant dips, the
parameters at their ends), which random points of a box of 16-21 dimensions rarely come
near. :func:`divisor_points` minimises ``|b|`` over those inputs (coordinate descent over
nested grids, in double, from the sampled points of smallest ``|b|``), and puts the other
inputs (rates, torques: what the numerators read) at random or at an end of their range.
:func:`search_divisors` evaluates the printed program there in float32 against the same
113-bit reference as :func:`~codegen.backends.c.certify.search.search` and climbs from
the worst points, with small steps in ``b``'s inputs (to stay where ``b`` is small) and
large ones in the others.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import numpy.typing as npt
import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.certify.divisors import dependencies
from codegen.backends.c.certify.program import Program
from codegen.backends.c.certify.search import (
    Exact,
    Found,
    box_rounder,
    climbed,
    node_values,
)

F64 = npt.NDArray[np.float64]


def divisors(program: Program) -> list[int]:
    """The divisor nodes of ``program``'s divisions that are computed (not an input or a
    literal), a negation or absolute value taken off, each once."""
    out: list[int] = []
    for node in program.nodes:
        if node.op != "div":
            continue
        d = node.args[1]
        while program.nodes[d].op == "neg" or (program.nodes[d].op == "call"
                                               and program.nodes[d].name == "fabs"):
            d = program.nodes[d].args[0]
        if program.nodes[d].op not in ("in", "lit") and d not in out:
            out.append(d)
    return out


def divisor_points(program: Program, symbols: list[sp.Symbol], lo: F64, hi: F64,
                   count: int, rng: np.random.Generator, *, sample: int = 2000,
                   sweeps: int = 3) -> tuple[F64, F64]:
    """Per computed divisor ``b``, ``count`` points of the box where ``|b|`` is locally
    smallest over ``b``'s inputs: the ``count`` of ``sample`` random points with the
    smallest ``|b|``, then each of ``b``'s inputs in turn moved to the minimum of ``|b|``
    on nested grids (64 points over the whole range, then 1/16 and 1/256 of it around
    the best), ``sweeps`` times. The inputs ``b`` does not read: random for half the
    points, at an end of their range for the other half. Returns the points and ``|b|``
    at each (double)."""
    deps = dependencies(program)
    col = {program.inputs[s]: k for k, s in enumerate(symbols)}
    found: list[F64] = []
    mags: list[F64] = []
    grid = 64
    rows = np.arange(count)

    def magnitude(p: F64, b: int) -> F64:
        v = node_values(program, {s: p[:, k] for k, s in enumerate(symbols)}, np.float64)
        m = np.abs(np.asarray(v[b], dtype=np.float64))
        return np.where(np.isfinite(m), m, np.inf)

    for b in divisors(program):
        movable = [col[i] for i in sorted(deps[b]) if i in col and hi[col[i]] > lo[col[i]]]
        if not movable:
            continue
        start = lo + (hi - lo) * rng.random((sample, len(symbols)))
        p = start[np.argsort(magnitude(start, b))[:count]].copy()
        for _ in range(sweeps):
            for k in rng.permutation(movable):
                span = hi[k] - lo[k]
                centre = p[:, k].copy()
                for width in (1.0, 1.0 / 16, 1.0 / 256):
                    t = np.linspace(-0.5, 0.5, grid) * span * width
                    mid = centre if width < 1.0 else np.full(len(p), lo[k] + 0.5 * span)
                    vals = np.clip(mid[None, :] + t[:, None], lo[k], hi[k])
                    trial = np.tile(p, (grid, 1))
                    trial[:, k] = vals.reshape(-1)
                    m = magnitude(trial, b).reshape(grid, len(p))
                    centre = vals[m.argmin(axis=0), rows[:len(p)]]
                p[:, k] = centre
        others = np.ones(len(symbols), dtype=bool)
        others[movable] = False
        spread = lo + (hi - lo) * rng.random(p.shape)
        ends = np.where(rng.random(p.shape) < 0.5, lo, hi)
        pick = np.where((rng.random(len(p)) < 0.5)[:, None], ends, spread)
        p[:, others] = pick[:, others]
        found.append(p)
        mags.append(magnitude(p, b))
    if not found:
        return np.empty((0, len(symbols))), np.empty(0)
    return np.concatenate(found), np.concatenate(mags)


def search_divisors(program: Program, ir: FunctionIR,
                    box: Mapping[sp.Symbol, tuple[float, float]], *, points: int = 40,
                    climbs: int = 1, rounds: int = 2, seed: int = 0, outputs: int = 8,
                    exact_of: Callable[[list[sp.Symbol]], Exact] | None = None) -> Found:
    """The largest error per output at :func:`divisor_points` (``points`` per divisor) and
    on a coordinate search from the worst of them, for the ``outputs`` outputs with the
    largest errors there (a linearization's hundred outputs would each cost a climb of
    mpmath evaluations): each input moved by a step shrinking
    fourfold a round, starting at 1/4 of its range for the inputs no divisor reads and
    1/1000 for those one does (a step of 1/4 would leave the thin region where the divisor
    is small). A program with no computed divisor: nothing evaluated, errors 0."""
    rng = np.random.default_rng(seed)
    symbols = sorted(program.inputs, key=lambda s: program.inputs[s])
    lo = np.array([box[s][0] for s in symbols], dtype=np.float64)
    hi = np.array([box[s][1] for s in symbols], dtype=np.float64)
    pts, _ = divisor_points(program, symbols, lo, hi, points, rng)
    if not len(pts):
        return Found(tuple(0.0 for _ in program.outputs),
                     tuple(tuple(float(v) for v in lo) for _ in program.outputs), 0)
    exact = exact_of(symbols) if exact_of is not None else Exact(ir, symbols)
    deps = dependencies(program)
    col = {program.inputs[s]: k for k, s in enumerate(symbols)}
    near = np.zeros(len(symbols), dtype=bool)
    for b in divisors(program):
        near[[col[i] for i in deps[b] if i in col]] = True

    inside = box_rounder(lo, hi)
    pts32 = inside(pts)
    return climbed(program, exact, inside, pts32, np.where(near, 1e-3, 0.25) * (hi - lo),
                   climbs=climbs, rounds=rounds, rng=rng, top=outputs)


def merge(first: Found, second: Found) -> Found:
    """Per output, the larger of two searches' errors (and its point)."""
    pick = [a >= b for a, b in zip(first.errors, second.errors, strict=True)]
    return Found(tuple(a if p else b for a, b, p in zip(first.errors, second.errors, pick,
                                                        strict=True)),
                 tuple(a if p else b for a, b, p in zip(first.points, second.points, pick,
                                                        strict=True)),
                 first.evaluated + second.evaluated)
