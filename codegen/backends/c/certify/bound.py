"""A certified float32 error bound per output over a box, tightened by subdivision.

:func:`certify` runs :class:`~codegen.backends.c.certify.analysis.Analysis` on the whole box, then
repeatedly splits the boxes whose bound is worst (relative to each output's current
bound) along the dimension that helps them most: all ``2 d`` halves of each chosen box are
analysed in one batch and the split with the smallest worse half is kept. The bound of an
output is the largest over the final boxes, which cover the declared box, so it holds for
every input in it; the no-overflow proof is that no box has an unsafe node.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
import sympy as sp

from codegen.backends.c.certify.analysis import Analysis
from codegen.backends.c.certify.divisors import Pieces, divisor_enclosures
from codegen.backends.c.certify.program import Program

Box = Mapping[sp.Symbol, tuple[float, float]]
# the divisors' branch and bound: at least this much processor time (it stops earlier once
# the proved bound is within 2x of the smallest value seen)
DIVISOR_SECONDS = 40.0
CHUNK = 512  # boxes analysed in one batch (the affine forms hold boxes x inputs per node)


@dataclass(frozen=True)
class Certificate:
    """What :func:`certify` proved for one function over ``box``."""

    function: str
    outputs: tuple[str, ...]  # C lvalues, in store order
    bounds: tuple[float, ...]  # |float32 - exact| <= bound, per output
    ranges: tuple[tuple[float, float], ...]  # enclosure of each exact output
    proved: bool  # no intermediate may overflow or be NaN, every guard passes
    reason: str  # "" when proved, else the first unsafe node
    boxes: int
    seconds: float
    # guards that may fail somewhere in the box (the function then returns that status
    # and writes nothing): the bounds hold for the calls that return OK
    open_guards: tuple[str, ...] = ()
    # divisors proved nonzero over the whole box by subdivision in their own inputs
    # (:mod:`.divisors`): "node i in [lo, hi]"
    divisors: tuple[str, ...] = ()


def _arrays(program: Program, symbols: list[sp.Symbol], lo: npt.NDArray[np.float64],
            hi: npt.NDArray[np.float64]) -> tuple[dict[int, npt.NDArray[np.float64]],
                                                  dict[int, npt.NDArray[np.float64]]]:
    nodes = [program.inputs[s] for s in symbols]
    return ({n: lo[:, k] for k, n in enumerate(nodes)},
            {n: hi[:, k] for k, n in enumerate(nodes)})


def certify(program: Program, box: Box, in_err: Mapping[sp.Symbol, float] | None = None,
            *, seconds: float = 4.0, max_boxes: int = 4096, batch: int = 8) -> Certificate:
    """The certificate of ``program`` over ``box`` (every input symbol it reads must be in
    it; ``in_err``: inputs' own float32 error bounds). ``seconds``: the subdivision budget
    in processor time (not wall time: the same result on a loaded machine, more slowly).
    When the subdivision leaves a divisor that may be 0, the divisors' enclosures
    (:mod:`.divisors`, a budget of their own) are proved and the subdivision runs again
    with them."""
    t0 = time.process_time()
    missing = [str(s) for s in program.inputs if s not in box]
    if missing:
        raise ValueError(f"{program.function}: no box for {', '.join(missing)}")
    symbols = sorted(program.inputs, key=lambda s: program.inputs[s])
    lo = np.array([[float(box[s][0]) for s in symbols]])
    hi = np.array([[float(box[s][1]) for s in symbols]])
    if np.any(lo > hi):
        raise ValueError(f"{program.function}: an empty box")
    errs = {program.inputs[s]: float(e) for s, e in (in_err or {}).items()
            if s in program.inputs}
    cert = _subdivide(program, symbols, lo, hi, errs, {}, seconds, max_boxes, batch)
    if cert.proved or "divisor may be 0" not in cert.reason:
        return replace(cert, seconds=time.process_time() - t0)
    # a divisor the subdivision did not prove nonzero: a branch and bound over its own
    # inputs, then the subdivision again with the proved enclosures, starting from the
    # branch and bound's pieces (see seeded)
    pieces: dict[int, Pieces] = {}
    known, _ = divisor_enclosures(
        program, {program.inputs[s]: lo[0, k] for k, s in enumerate(symbols)},
        {program.inputs[s]: hi[0, k] for k, s in enumerate(symbols)},
        seconds=max(2 * seconds, DIVISOR_SECONDS), pieces=pieces)
    if not known:
        return replace(cert, seconds=time.process_time() - t0)
    slo, shi = seeded(program, symbols, lo, hi, pieces)
    cert = _subdivide(program, symbols, slo, shi, errs, known, seconds,
                      max_boxes + len(slo) - 1, batch)
    return replace(cert, seconds=time.process_time() - t0)


def seeded(program: Program, symbols: list[sp.Symbol], lo: npt.NDArray[np.float64],
           hi: npt.NDArray[np.float64], pieces: Mapping[int, Pieces]
           ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The boxes the subdivision starts from once a divisor is proved: the declared box
    (one row of ``lo``/``hi``) cut, in the divisor's inputs, into its branch and bound's
    pieces (the divisor with the most; every other input at its whole range).

    A quotient's error ``|a/b| δb/|b|`` is bounded per box by ``b``'s largest rounding
    over the box over ``b``'s smallest magnitude there; over a box two turns wide in the
    angles ``b``'s smallest magnitude is the whole box's, met with the roundings of
    configurations where ``b`` is large. The pieces are finest where ``|b|`` is smallest,
    so each carries ``b``'s magnitude and rounding where it is (the per-box relative
    form of the division rule), and the bisection then spends its budget on the pieces
    whose bound is worst. Sound as the pieces cover the box: their union in ``b``'s
    inputs is the declared extent, and every other input is whole."""
    if not pieces:
        return lo, hi
    chosen = max(pieces.values(), key=lambda p: len(p.lo))
    col = {program.inputs[s]: k for k, s in enumerate(symbols)}
    slo = np.repeat(lo, len(chosen.lo), axis=0)
    shi = np.repeat(hi, len(chosen.lo), axis=0)
    for j, node in enumerate(chosen.dims):
        slo[:, col[node]] = chosen.lo[:, j]
        shi[:, col[node]] = chosen.hi[:, j]
    return slo, shi


def _subdivide(program: Program, symbols: list[sp.Symbol], lo: npt.NDArray[np.float64],
               hi: npt.NDArray[np.float64], errs: Mapping[int, float],
               known: Mapping[int, tuple[float, float]], seconds: float, max_boxes: int,
               batch: int) -> Certificate:
    """The box subdivision of :func:`certify` (``known``: proved enclosures of nodes)."""
    start = time.process_time()
    analysis = Analysis(program, known=known)

    def run(lo: npt.NDArray[np.float64], hi: npt.NDArray[np.float64]
            ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.bool_], list[str],
                       npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        if len(lo) > CHUNK:  # many seeded boxes: in batches, for memory
            parts, guards = [], set()
            for k in range(0, len(lo), CHUNK):
                parts.append(run(lo[k:k + CHUNK], hi[k:k + CHUNK]))
                guards |= set(analysis.open_guards)
            analysis.open_guards = sorted(guards)  # those of every batch
            return (np.concatenate([p[0] for p in parts]),
                    np.concatenate([p[1] for p in parts]),
                    [w for p in parts for w in p[2]],
                    np.concatenate([p[3] for p in parts]),
                    np.concatenate([p[4] for p in parts]))
        a, b = _arrays(program, symbols, lo, hi)
        e = {n: np.full(len(lo), v) for n, v in errs.items()}
        values, unsafe, why = analysis.run(a, b, e)
        err = np.stack([v.err for v in values], axis=1)
        xlo = np.stack([v.xlo for v in values], axis=1)
        xhi = np.stack([v.xhi for v in values], axis=1)
        return err, unsafe, why, xlo, xhi

    err, unsafe, why, xlo, xhi = run(lo, hi)
    # the declared box's extent (the rows may be seeded pieces of it: see seeded)
    top, bottom = hi.max(axis=0), lo.min(axis=0)
    splittable = np.nonzero(top > bottom)[0]
    width = np.where(top > bottom, top - bottom, 1.0)
    while (len(splittable) and len(lo) < max_boxes
           and time.process_time() - start < seconds):
        scale = np.maximum(err.max(axis=0), 1e-300)
        score = np.where(unsafe, np.inf, np.nan_to_num(err / scale, nan=np.inf).max(axis=1))
        chosen = np.argsort(-score)[:batch]
        # every halving of every chosen box, in one batch
        mid = 0.5 * (lo[chosen][:, splittable] + hi[chosen][:, splittable])
        clo = np.repeat(lo[chosen], 2 * len(splittable), axis=0)
        chi = np.repeat(hi[chosen], 2 * len(splittable), axis=0)
        rows = np.arange(len(clo))
        dims = np.tile(np.repeat(splittable, 2), len(chosen))
        half = np.tile([0, 1], len(chosen) * len(splittable))
        mids = np.repeat(mid.reshape(-1), 2)
        chi[rows[half == 0], dims[half == 0]] = mids[half == 0]
        clo[rows[half == 1], dims[half == 1]] = mids[half == 1]
        cerr, cunsafe, cwhy, cxlo, cxhi = run(clo, chi)
        cscore = np.where(cunsafe, np.inf, np.nan_to_num(cerr / scale, nan=np.inf).max(axis=1))
        pair = cscore.reshape(len(chosen), len(splittable), 2).max(axis=2)
        best = pair.argmin(axis=1)
        # no split makes the box safe yet: halve its widest side (relative to the declared
        # box), so that repeated splits shrink every side
        rel = (hi[chosen][:, splittable] - lo[chosen][:, splittable]) / width[splittable]
        stuck = ~np.isfinite(pair.min(axis=1))
        best = np.where(stuck, rel.argmax(axis=1), best)
        keep = np.ones(len(lo), dtype=bool)
        keep[chosen] = False
        pick = np.concatenate([(c * len(splittable) + best[c]) * 2 + np.array([0, 1])
                               for c in range(len(chosen))])
        lo = np.concatenate([lo[keep], clo[pick]])
        hi = np.concatenate([hi[keep], chi[pick]])
        err = np.concatenate([err[keep], cerr[pick]])
        xlo = np.concatenate([xlo[keep], cxlo[pick]])
        xhi = np.concatenate([xhi[keep], cxhi[pick]])
        unsafe = np.concatenate([unsafe[keep], cunsafe[pick]])
        why = [w for w, k in zip(why, keep, strict=True) if k] + [cwhy[i] for i in pick]
    run(lo, hi)  # the final boxes: which guards may refuse somewhere in them
    proved = not bool(unsafe.any())
    reason = "" if proved else next(w for w, u in zip(why, unsafe, strict=True) if u)
    return Certificate(
        program.function, tuple(t for t, _ in program.outputs),
        tuple(float(e) for e in err.max(axis=0)),
        tuple((float(a), float(b)) for a, b in zip(xlo.min(axis=0), xhi.max(axis=0),
                                                      strict=True)),
        proved, reason, len(lo), time.process_time() - start, tuple(analysis.open_guards),
        tuple(f"node {n} in [{a:.4g}, {b:.4g}]" for n, (a, b) in sorted(known.items())))
