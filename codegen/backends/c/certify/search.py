"""The search for the largest float32 error: the printed program evaluated in numpy
float32 (IEEE round to nearest, operation by operation in the printed order) against the
function's own expressions evaluated by mpmath at 113 bits (SymPy's CSE of the spec's
outputs without the printer's shared reciprocals: the same mathematics, another route).

Random points of the box, corners, and points on the robust laws' boundary layer
(:func:`boundary_points`), then a coordinate search from the worst ones: each coordinate
moved by a shrinking step while the error of the output being maximised grows.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import numpy as np
import numpy.typing as npt
import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.certify.divisors import dependencies
from codegen.backends.c.certify.program import Program

F32 = npt.NDArray[np.float32]
EXACT_BITS = 113


def float32_eval(program: Program, inputs: Mapping[sp.Symbol, F32]) -> list[F32]:
    """The outputs of ``program`` in float32 for arrays of inputs (one entry per point).
    sin and cos: the double result rounded once (within the helpers' stated 2 ulp)."""
    vals = node_values(program, inputs, np.float32)
    return [np.asarray(vals[i], dtype=np.float32) for _, i in program.outputs]


def node_values(program: Program, inputs: Mapping[sp.Symbol, npt.NDArray[np.generic]],
                dtype: type[np.floating[Any]] = np.float32) -> list[Any]:
    """Every node's value (``dtype`` arithmetic; booleans for comparisons)."""
    vals: list[Any] = []  # values, or booleans of comparisons
    by_node = {program.inputs[s]: np.asarray(v, dtype=dtype) for s, v in inputs.items()}
    n = len(next(iter(by_node.values())))
    with np.errstate(all="ignore"):
        for idx, node in enumerate(program.nodes):
            a = [vals[i] for i in node.args]
            op = node.op
            if op == "in":
                r: Any = by_node[idx]
            elif op == "lit":
                r = np.full(n, node.value, dtype=dtype)
            elif op == "neg":
                r = -a[0]
            elif op in _ARITH:
                r = _ARITH[op](a[0], a[1])
            elif op == "call":
                r = _call(node.name, a)
            elif op == "cond":
                r = np.where(a[0], a[1], a[2])
            elif op in _COMPARE:
                r = _COMPARE[op](a[0], a[1])
            elif op == "and":
                r = a[0] & a[1]
            elif op == "or":
                r = a[0] | a[1]
            elif op == "not":
                r = ~a[0]
            else:
                raise ValueError(f"cannot evaluate {op}")
            vals.append(r)
    return vals


_ARITH: dict[str, Callable[[npt.NDArray[np.generic], npt.NDArray[np.generic]],
                           npt.NDArray[np.generic]]] = {
    "add": np.add, "sub": np.subtract, "mul": np.multiply, "div": np.divide}
_COMPARE = {"lt": np.less, "le": np.less_equal, "gt": np.greater, "ge": np.greater_equal,
            "eq": np.equal, "ne": np.not_equal}


def _call(name: str, a: Sequence[npt.NDArray[np.generic]]) -> npt.NDArray[np.generic]:
    base = name.removesuffix("_bounded")
    if base in ("sin", "cos"):
        f = np.sin if base == "sin" else np.cos
        return f(a[0].astype(np.float64)).astype(a[0].dtype)
    if name == "sqrt":
        return np.sqrt(a[0])
    if name == "fabs":
        return np.abs(a[0])
    if name == "fmax":
        return np.fmax(a[0], a[1])
    if name == "fmin":
        return np.fmin(a[0], a[1])
    raise ValueError(f"cannot evaluate {name}")


class Exact:
    """The function's outputs at a point, in mpmath with :data:`EXACT_BITS` bits."""

    def __init__(self, ir: FunctionIR, symbols: Sequence[sp.Symbol]) -> None:
        plain = ir.plain
        self.symbols = list(symbols)
        temps = [t for t, _ in plain.temps]
        args = self.symbols + [s for s in ir.spec.input_symbols() if s not in set(symbols)]
        self._extra = len(args) - len(self.symbols)
        self._temps = [sp.lambdify(args + temps[:k], e, modules="mpmath")
                       for k, (_, e) in enumerate(plain.temps)]
        flat = [e for exprs in plain.outputs[:len(ir.spec.outputs)] for e in exprs]
        self._outs = [sp.lambdify(args + temps, e, modules="mpmath") for e in flat]

    def __call__(self, point: Sequence[float]) -> list[mpmath.mpf]:
        with mpmath.workprec(EXACT_BITS):
            vals = [v if isinstance(v, mpmath.mpf) else mpmath.mpf(float(v))
                    for v in point] + [mpmath.mpf(0)] * self._extra
            for f in self._temps:
                vals.append(f(*vals))
            return [mpmath.mpf(f(*vals)) for f in self._outs]


def boundary_layers(program: Program) -> list[tuple[int, int]]:
    """The (2-norm N, width c) of every fmax(N, c) (the robust laws' s/max(||s||, eps))."""
    out: list[tuple[int, int]] = []
    for node in program.nodes:
        if node.op == "call" and node.name == "fmax":
            a, b = node.args
            for n, c in ((a, b), (b, a)):
                if program.nodes[n].op == "call" and program.nodes[n].name == "sqrt":
                    out.append((n, c))
    return out


def boundary_points(program: Program, symbols: Sequence[sp.Symbol],
                    lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64], count: int,
                    rng: np.random.Generator) -> npt.NDArray[np.float64]:
    """Points of the box where a boundary layer's norm is within 5 % of its width
    (||s|| = eps (1 + d), |d| <= 0.05): there the switching term s/max(||s||, eps) turns
    s's rounding into gain/eps times as much torque, and a uniform sample of a box of
    tens of dimensions almost never lands. Each starts at a random point (for half of
    them the inputs N does not read at an end of their range, and the width c at the low
    tenth of its range when it is an input: the largest amplification) and moves
    N's inputs, one at a time (coordinate descent on |N - (1 + d) c| over nested grids, in
    double), until N = (1 + d) c within 1 % of c."""
    deps = dependencies(program)
    col = {program.inputs[s]: k for k, s in enumerate(symbols)}
    found: list[npt.NDArray[np.float64]] = []
    grid = 64
    for n, c in boundary_layers(program):
        movable = [col[i] for i in sorted(deps[n]) if i in col and hi[col[i]] > lo[col[i]]]
        if not movable:
            continue
        base = lo + (hi - lo) * rng.random((count, len(symbols)))
        # the inputs N does not read (gains, parameters, estimates) at an end of their
        # range for half the points: the largest amplification sits at a corner
        ends = np.where(rng.random((count, len(symbols))) < 0.5, lo, hi)
        fixed = np.ones(len(symbols), dtype=bool)
        fixed[movable] = False
        corner = (rng.random(count) < 0.5)[:, None] & fixed[None, :]
        base = np.where(corner, ends, base)
        if c in col:
            k = col[c]
            base[:, k] = lo[k] + 0.1 * (hi[k] - lo[k]) * rng.random(count)
        target = 1.0 + 0.1 * (rng.random(count) - 0.5)
        rows = np.arange(count)

        def gap(p: npt.NDArray[np.float64], n: int = n, c: int = c,
                target: npt.NDArray[np.float64] = target) -> npt.NDArray[np.float64]:
            v = node_values(program, {s: p[:, k] for k, s in enumerate(symbols)}, np.float64)
            reps = len(p) // count
            return np.asarray(v[n] - np.tile(target, reps) * v[c], dtype=np.float64)

        p = base.copy()
        for _ in range(3):  # coordinate descent on |N - (1 + d) c|: every input of N
            for k in rng.permutation(movable):
                span = hi[k] - lo[k]
                centre = p[:, k].copy()
                for width in (1.0, 1.0 / 16, 1.0 / 256):
                    t = np.linspace(-0.5, 0.5, grid) * span * (1.0 if width == 1.0 else width)
                    mid = centre if width < 1.0 else np.full(count, lo[k] + 0.5 * span)
                    vals = np.clip(mid[None, :] + t[:, None], lo[k], hi[k])
                    trial = np.tile(p, (grid, 1))
                    trial[:, k] = vals.reshape(-1)
                    g = np.abs(gap(trial)).reshape(grid, count)
                    g = np.where(np.isfinite(g), g, np.inf)
                    centre = vals[g.argmin(axis=0), rows]
                p[:, k] = centre
        v = node_values(program, {s: p[:, k] for k, s in enumerate(symbols)}, np.float64)
        has = np.abs(v[n] - target * v[c]) <= 0.01 * np.abs(v[c])
        found.append(p[has])
    return np.concatenate(found) if found else np.empty((0, len(symbols)))


def _norm_entries(program: Program, n: int) -> list[int]:
    """The entries x_i of the 2-norm ``n`` = sqrt(x_0*x_0 + x_1*x_1 + ...)."""
    out: list[int] = []
    stack = [program.nodes[n].args[0]]
    while stack:
        node = program.nodes[stack.pop()]
        if node.op == "add":
            stack += list(node.args)
        elif node.op == "mul" and node.args[0] == node.args[1]:
            out.append(node.args[0])
    return out


def cancelling_points(program: Program, symbols: Sequence[sp.Symbol],
                      lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64], count: int,
                      rng: np.random.Generator, jitter: int = 16) -> npt.NDArray[np.float64]:
    """Points where the switching term's float32 error is largest: every input at an end
    of its range (the largest gain and terms of s), the width c of fmax(||s||, c) at its
    low end, and each entry s_i of s brought to a random target t_i (||t|| between 0.5 c
    and 1.5 c: inside the layer and just outside it) by moving one input only it reads,
    so that s_i's terms stay at their largest and cancel; then ``jitter`` float32
    variants of each (a few ulp on every input, which changes the roundings but not the
    place), of which those whose float32 error against the same program in double is
    largest, per output, are kept (the double's own error is 2^-29 times smaller)."""
    deps = dependencies(program)
    col = {program.inputs[s]: k for k, s in enumerate(symbols)}
    found: list[npt.NDArray[np.float64]] = []
    grid = 64
    rows = np.arange(count)

    def values(p: npt.NDArray[np.float64], dtype: type[np.floating[Any]]) -> list[Any]:
        return node_values(program, {s: p[:, k] for k, s in enumerate(symbols)}, dtype)

    for n, c in boundary_layers(program):
        entries = _norm_entries(program, n)
        own = []
        for j, x in enumerate(entries):
            others = set().union(*(deps[y] for i, y in enumerate(entries) if i != j))
            cols = [col[i] for i in sorted(deps[x] - others)
                    if i in col and hi[col[i]] > lo[col[i]]]
            own.append(cols)
        if not all(own):
            continue
        p = np.where(rng.random((count, len(symbols))) < 0.5, lo, hi)
        if c in col:
            k = col[c]
            p[:, k] = np.where(rng.random(count) < 0.5, lo[k],
                               lo[k] + 0.05 * (hi[k] - lo[k]) * rng.random(count))
        width = np.abs(np.asarray(values(p, np.float64)[c], dtype=np.float64))
        direction = rng.normal(size=(count, len(entries)))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        target = direction * (width * rng.uniform(0.5, 1.5, count))[:, None]
        for j, x in enumerate(entries):  # each entry's own inputs: the one that meets t_j
            best, gap = p.copy(), np.full(count, np.inf)
            for k in own[j]:
                trial_p = p.copy()
                span = hi[k] - lo[k]
                centre = np.full(count, lo[k] + 0.5 * span)
                for scale in (1.0, 1.0 / 16, 1.0 / 256, 1.0 / 4096):
                    t = np.linspace(-0.5, 0.5, grid) * span * scale
                    vals = np.clip(centre[None, :] + t[:, None], lo[k], hi[k])
                    trial = np.tile(trial_p, (grid, 1))
                    trial[:, k] = vals.reshape(-1)
                    v = np.asarray(values(trial, np.float64)[x], dtype=np.float64)
                    g = np.abs(v.reshape(grid, count) - target[None, :, j])
                    g = np.where(np.isfinite(g), g, np.inf)
                    centre = vals[g.argmin(axis=0), rows]
                    here = g.min(axis=0)
                trial_p[:, k] = centre
                better = here < gap
                best[better], gap[better] = trial_p[better], here[better]
            p = best
        # float32 variants: a few ulp on every input, within the box
        jit = np.repeat(p, jitter, axis=0).astype(np.float32)
        steps = rng.integers(-4, 5, size=jit.shape)
        for _ in range(4):
            jit = np.where(steps > 0, np.nextafter(jit, np.float32(np.inf)),
                           np.where(steps < 0, np.nextafter(jit, np.float32(-np.inf)), jit))
            steps = steps - np.sign(steps)
        cand = np.clip(jit.astype(np.float64), lo, hi).astype(np.float32).astype(np.float64)
        got = values(cand, np.float32)
        ref = values(cand, np.float64)
        err = np.stack([np.abs(np.asarray(got[i], np.float64) - np.asarray(ref[i], np.float64))
                        for _, i in program.outputs], axis=1)
        err = np.where(np.isfinite(err), err, 0.0)
        keep = {int(i) for col_err in err.T for i in np.argsort(-col_err)[:max(1, count // 8)]}
        found.append(cand[sorted(keep)])
    return np.concatenate(found) if found else np.empty((0, len(symbols)))


@dataclass(frozen=True)
class Found:
    """The largest error found per output, where, and how many points were tried."""

    errors: tuple[float, ...]
    points: tuple[tuple[float, ...], ...]
    evaluated: int


def errors_at(program: Program, exact: Exact, pts: npt.NDArray[np.float32]
              ) -> npt.NDArray[np.float64]:
    """|float32 - exact| per point (rows) and output (columns)."""
    got = float32_eval(program, {s: pts[:, k] for k, s in enumerate(exact.symbols)})
    out = np.empty((len(pts), len(got)))
    for i, row in enumerate(pts):
        try:
            ref = exact([float(v) for v in row])
        except ZeroDivisionError:  # the mathematics is undefined there (a singular M-hat
            out[i] = 0.0  # of independent box entries): no exact value to compare
            continue
        for j, g in enumerate(got):
            out[i, j] = float(abs(mpmath.mpf(float(g[i])) - ref[j]))
    return out


def box_rounder(lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64]
                ) -> Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float32]]:
    """Points clipped to the box [lo, hi] and rounded to float32, stepped back in by an ulp
    where the rounding left the box (by half an ulp)."""
    def inside(p: npt.NDArray[np.float64]) -> npt.NDArray[np.float32]:
        q = np.clip(p, lo, hi).astype(np.float32)
        q = np.where(q < lo, np.nextafter(q, np.float32(np.inf)), q)
        return np.where(q > hi, np.nextafter(q, np.float32(-np.inf)), q).astype(np.float32)
    return inside


def climb(program: Program, exact: Exact,
          inside: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float32]],
          start: npt.NDArray[np.float32], cur: float, j: int, step: npt.NDArray[np.float64],
          rounds: int, rng: np.random.Generator
          ) -> tuple[float, npt.NDArray[np.float64], int]:
    """A coordinate search for output ``j``'s largest error from ``start`` (error ``cur``):
    each round tries ± ``step`` along every input in a random order, keeping what raises the
    error, then quarters the step. Returns the error reached, its point and the points
    evaluated."""
    x = start.astype(np.float64)
    evaluated = 0
    for _ in range(rounds):
        for k in rng.permutation(len(x)):
            if step[k] == 0:
                continue
            trial = np.stack([x, x])
            trial[0, k] += step[k]
            trial[1, k] -= step[k]
            t32 = inside(trial)
            e = errors_at(program, exact, t32)[:, j]
            evaluated += 2
            if e.max() > cur:
                cur = float(e.max())
                x = t32[int(e.argmax())].astype(np.float64)
        step = step / 4
    return cur, x, evaluated


def climbed(program: Program, exact: Exact,
            inside: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float32]],
            pts32: npt.NDArray[np.float32], step: npt.NDArray[np.float64], *, climbs: int,
            rounds: int, rng: np.random.Generator, top: int | None = None) -> Found:
    """Each output's largest error over ``pts32``, then :func:`climb` from its ``climbs``
    worst points (every output in order, or the ``top`` outputs with the largest errors)."""
    err = errors_at(program, exact, pts32)
    evaluated = len(pts32)
    best = err.max(axis=0)
    where = [pts32[i] for i in err.argmax(axis=0)]
    order = range(err.shape[1]) if top is None else np.argsort(-best)[:top]
    for j in order:
        for start in np.argsort(-err[:, j])[:climbs]:
            cur, x, n = climb(program, exact, inside, pts32[start], float(err[start, j]), j,
                              step, rounds, rng)
            evaluated += n
            if cur > best[j]:
                best[j] = cur
                where[j] = inside(x[None, :])[0]
    return Found(tuple(float(b) for b in best),
                 tuple(tuple(float(v) for v in w) for w in where), evaluated)


def search(program: Program, ir: FunctionIR, box: Mapping[sp.Symbol, tuple[float, float]],
           *, random_points: int = 200, climbs: int = 4, rounds: int = 3,
           seed: int = 0, exact_of: Callable[[list[sp.Symbol]], Exact] | None = None
           ) -> Found:
    """Random points, corners and points on the boundary layers (:func:`boundary_points`),
    then a coordinate search over ``box`` for each output's largest error (``exact_of``:
    the exact reference for the inputs in order, if not ``ir``'s outputs)."""
    rng = np.random.default_rng(seed)
    symbols = sorted(program.inputs, key=lambda s: program.inputs[s])
    exact = exact_of(symbols) if exact_of is not None else Exact(ir, symbols)
    lo = np.array([box[s][0] for s in symbols], dtype=np.float64)
    hi = np.array([box[s][1] for s in symbols], dtype=np.float64)

    inside = box_rounder(lo, hi)
    corners = rng.integers(0, 2, size=(random_points // 4, len(symbols)))
    pts = np.concatenate([lo + (hi - lo) * rng.random((random_points, len(symbols))),
                          np.where(corners == 1, hi, lo),
                          boundary_points(program, symbols, lo, hi, random_points, rng),
                          cancelling_points(program, symbols, lo, hi, random_points, rng)])
    pts32 = inside(pts)
    return climbed(program, exact, inside, pts32, 0.25 * (hi - lo), climbs=climbs,
                   rounds=rounds, rng=rng)
