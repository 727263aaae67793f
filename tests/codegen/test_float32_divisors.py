"""The float32 certificate where a divisor comes near 0 (issue 50): the subdivision seeded
with the divisor's branch-and-bound pieces stays sound (a search at 113 bits, seeded where
the divisor is smallest, never beats it; the seeded boxes cover the box) and is tighter
than the unseeded one, and the divisor search reaches the divisor's smallest magnitude."""

from __future__ import annotations

from collections.abc import Sequence

import mpmath
import numpy as np
import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.certify.bound import _subdivide, certify, seeded
from codegen.backends.c.certify.divisor_search import divisor_points, divisors, search_divisors
from codegen.backends.c.certify.divisors import Pieces, divisor_enclosures
from codegen.backends.c.certify.program import Program, parse_only
from codegen.backends.c.certify.search import Exact, errors_at
from codegen.backends.c.config import CConfig

NAMES = ["t", "s", "k", "a", "b"]
# D = 1 - k (cos t cos s + sin t sin s) = 1 - k cos(t - s) over two angles of a full turn:
# its interval enclosure contains 0 (the bracket in [-2, 2]), its smallest value
# 1 - 0.98 = 0.02 at t = s
TEXT = ("(a*WMR_COS_BOUNDED(t) + b)/(WMR_LIT(1.0) - k*(WMR_COS_BOUNDED(t)*WMR_COS_BOUNDED(s)"
        " + WMR_SIN_BOUNDED(t)*WMR_SIN_BOUNDED(s)))")
K_MAX = 0.98
BOX = {"t": (-np.pi, np.pi), "s": (-np.pi, np.pi), "k": (0.9, K_MAX), "a": (-10.0, 10.0),
       "b": (-10.0, 10.0)}


def _program() -> tuple[Program, dict[sp.Symbol, tuple[float, float]]]:
    prog = parse_only(TEXT, NAMES, CConfig())
    return prog, {sp.Symbol(n): BOX[n] for n in NAMES}


class _Exact(Exact):
    """The quotient at 113 bits, at the float32 inputs."""

    def __init__(self, symbols: Sequence[sp.Symbol]) -> None:
        self.symbols = list(symbols)

    def __call__(self, point: Sequence[float]) -> list[mpmath.mpf]:
        with mpmath.workprec(113):
            v = dict(zip((str(s) for s in self.symbols), map(mpmath.mpf, point), strict=True))
            return [(v["a"] * mpmath.cos(v["t"]) + v["b"])
                    / (1 - v["k"] * mpmath.cos(v["t"] - v["s"]))]


def _exact(symbols: list[sp.Symbol]) -> Exact:
    return _Exact(symbols)


def _no_ir() -> FunctionIR:
    return None  # type: ignore[return-value]  # the reference is _exact's


def test_seeded_bound_holds_near_the_singular_divisor_and_means_something() -> None:
    """The certificate (divisor proved, subdivision seeded with its pieces) against the
    largest error of 400 random points and the divisor search's (|D| near 0.02): never
    beaten, and within 100x of it."""
    prog, box = _program()
    cert = certify(prog, box, seconds=4.0, max_boxes=400)
    assert cert.proved and cert.divisors, cert.reason
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    rng = np.random.default_rng(7)
    lo = np.array([box[s][0] for s in symbols])
    hi = np.array([box[s][1] for s in symbols])
    uniform = errors_at(prog, _Exact(symbols), (lo + (hi - lo) * rng.random((400, 5)))
                        .astype(np.float32)).max()
    near = search_divisors(prog, _no_ir(), box, points=60, exact_of=_exact).errors[0]
    worst = max(uniform, near)
    assert worst <= cert.bounds[0], (worst, cert.bounds)
    assert cert.bounds[0] <= 100 * worst, (cert.bounds, worst)


def test_seeded_boxes_cover_the_box_and_tighten_the_bound() -> None:
    """Every random point of the box lies in one of the seeded boxes (the pieces cover the
    divisor's inputs, the other inputs whole), and the subdivision from them (the pieces
    are the divisor proof's, paid for already) bounds the quotient tighter than the same
    200 further boxes from the whole box with the same proved divisor (the certificate
    before the seeding)."""
    prog, box = _program()
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    lo = np.array([[box[s][0] for s in symbols]])
    hi = np.array([[box[s][1] for s in symbols]])
    pieces: dict[int, Pieces] = {}
    known, failed = divisor_enclosures(
        prog, {prog.inputs[s]: lo[0, k] for k, s in enumerate(symbols)},
        {prog.inputs[s]: hi[0, k] for k, s in enumerate(symbols)}, seconds=60.0,
        pieces=pieces)
    assert known and not failed and pieces
    slo, shi = seeded(prog, symbols, lo, hi, pieces)
    assert len(slo) > 1
    rng = np.random.default_rng(8)
    pts = lo + (hi - lo) * rng.random((3000, 5))
    pts[:500, 1] = pts[:500, 0]  # and on t = s, where D is smallest
    inside = ((slo[None, :, :] <= pts[:, None, :]) & (pts[:, None, :] <= shi[None, :, :]))
    assert inside.all(axis=2).any(axis=1).all()
    whole = _subdivide(prog, symbols, lo, hi, {}, known, 600.0, 200, 8)
    split = _subdivide(prog, symbols, slo, shi, {}, known, 600.0, len(slo) + 200, 8)
    assert split.proved and split.bounds[0] < whole.bounds[0], (split, whole)


def test_divisor_points_reach_the_smallest_divisor() -> None:
    """The divisor search's points put |D| within 1 % of its smallest value over the box
    (1 - k_max at t = s), which 2000 uniform points do not."""
    prog, box = _program()
    symbols = sorted(prog.inputs, key=lambda s: prog.inputs[s])
    lo = np.array([box[s][0] for s in symbols])
    hi = np.array([box[s][1] for s in symbols])
    assert len(divisors(prog)) == 1
    pts, mags = divisor_points(prog, symbols, lo, hi, 20, np.random.default_rng(9))
    assert len(pts) == 20 and np.all(mags <= 1.01 * (1 - K_MAX)), mags
    assert np.all((lo <= pts) & (pts <= hi))
