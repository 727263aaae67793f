"""The robust laws' switching term s/max(||s||, eps), times a gain, as one unit-vector
operation (the rule :class:`~codegen.backends.c.certify.analysis.Analysis` applies to
``fl(s_i * fl(g / fl(fmax(fl||s||, eps))))``, recognised from the program's structure).

The interval rule per operation loses two correlations here: where s is large, ||s|| is
too (the quotient's error is g E/||s||, not g E |s_i|/eps^2), and where ||s|| is small,
s's entries cancel (their rounding is that of their terms, not of s's range over the box).
This module keeps both:

**Split errors** (:func:`split_errors`). For each node n feeding the norm's entries, per
box, ``|f_n - x_n| <= A_n + B_n |x_n|`` (f: the float32 value, x: the exact one at the
same point). Inputs and operations other than + - * and negation: ``A = E`` (the
interval analysis' bound), ``B = 0``. A product, before its rounding,
``|fa fb - xa xb| <= |xa| |eb| + |xb| |ea| + |ea| |eb|`` gives
``A = |xa| Ab (1 + Ba) + |xb| Aa (1 + Bb) + Aa Ab``, ``B = Ba + Bb + Ba Bb``. A sum
``s = xa + xb`` with ``|xa| >= |xb|`` somewhere in the box (a the term of larger magnitude
bound): ``|xa| <= |s| + |xb|``, so ``Ba |xa| + Bb |xb| <= Ba |s| + (Ba + Bb) |xb|``:
``A = Aa + Ab + (Ba + Bb) max|xb|``, ``B = Ba``; the cancelling part is paid only at the
smaller term's magnitude. Each rounding ``|fl(p) - p| <= u |p| + 2^-150`` with
``|p| <= |x| + A + B |x|``: ``A <- A (1 + u) + 2^-150``, ``B <- B + u (1 + B)``. Where
``E <= A`` the node takes ``(E, 0)`` instead (both hold).

**The unit vector.** With ``M(v) = max(||v||, c)`` (exact norm, exact c) and
``P(v) = v / M(v)``, for the float entries f and exact entries x, in each of the four
cases (each of f, x inside or outside the layer ||v|| < c):
``|P(f)_i - P(x)_i| <= (|f_i - x_i| + |P(f)_i| ||f - x||) / M(x)``
(e.g. both outside: ``f_i/||f|| - x_i/||x|| = (f_i - x_i)/||x|| + P(f)_i (||x|| - ||f||)/||x||``;
f inside, x outside: ``||x|| - c <= ||x|| - ||f||``; both inside: ``(f_i - x_i)/c``). With
``|P(f)_i| <= 1``, ``|x_i| <= M(x)`` and the split errors,
``|P(f)_i - P(x)_i| <= (A_i + ||A||_2) / M_lo + B_i + max_j B_j``, where
``M_lo = max(c_lo, ||x||_lo) <= M(x)``. Inside the layer the cancelling entries' rounding
is amplified by 1/eps, outside it by 1/||s|| only.

The float32 denominator ``fM = fmax(fl||f||, fc)`` against ``M(f)``: ``|fl||f|| - ||f|| |
<= rel ||f|| + fl`` (the norm's roundings, :meth:`Analysis._norm_error`: rel = (gamma_n
+ 2u)(1 + gamma_n), fl = sqrt(n 2^-150)), ``|fc - c| <= Ec``, and max is 1-Lipschitz in
each argument, so ``|f_i/fM - f_i/M(f)| <= |M(f) - fM| / fM <= max(rel (1 + fl/fM)/(1 - rel)
+ fl/fM, Ec/fM)`` (``|f_i| <= M(f)``; ``||f|| <= (fl||f|| + fl)/(1 - rel)``).

Then ``fl(f_i fl(fg/fM)) - x_i xg/M(x)`` is ``fg (f_i/fM - x_i/M(x)) + (fg - xg) P(x)_i``
plus the two roundings: ``|result - exact| <= |fg| (TA + TB) + Eg u_max + u |fg| r +
2^-150 |f_i|`` and the product's own rounding, where ``u_max = min(1, max|x_i| / M_lo)``
bounds ``|P(x)_i|`` and ``r = (1 + fl/fM)/(1 - rel)`` bounds ``|f_i/fM|``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from codegen.backends.c.certify.program import Program

Array = npt.NDArray[np.float64]
U = 2.0**-24
TINY = 2.0**-150
UP = 1.0 + 2.0**-50
MAX_DEPTH = 200  # split errors this far up an entry's graph (Python's recursion limit)


class Enclosed:
    """What this module reads of a node's analysis value (``analysis.Value``)."""

    xlo: Array
    xhi: Array
    flo: Array
    fhi: Array
    err: Array


def magnitude(lo: Array, hi: Array) -> Array:
    """The largest |x| over the interval [lo, hi], elementwise."""
    return np.maximum(np.abs(lo), np.abs(hi))


def split_errors(program: Program, nid: int, val: Callable[[int], Enclosed],
                 memo: dict[int, tuple[Array, Array]], depth: int = 0) -> tuple[Array, Array]:
    """``(A, B)`` per box with ``|f - x| <= A + B |x|`` for node ``nid`` (module
    docstring); ``memo`` caches the nodes already split in this run. Beyond
    :data:`MAX_DEPTH` operations up the graph a node takes ``(E, 0)``."""
    if nid in memo:
        return memo[nid]
    node = program.nodes[nid]
    v = val(nid)
    zero = np.zeros_like(v.err)
    a_err, b_rel = v.err, zero
    if depth >= MAX_DEPTH:
        return a_err, b_rel
    if node.op == "neg":
        a_err, b_rel = split_errors(program, node.args[0], val, memo, depth + 1)
    elif node.op == "mul":
        ia, ib = node.args
        aa, ba = split_errors(program, ia, val, memo, depth + 1)
        ab, bb = split_errors(program, ib, val, memo, depth + 1)
        xa, xb = val(ia), val(ib)
        ma, mb = magnitude(xa.xlo, xa.xhi), magnitude(xb.xlo, xb.xhi)
        a_err = ma * ab * (1 + ba) + mb * aa * (1 + bb) + aa * ab
        b_rel = ba + bb + ba * bb
        a_err, b_rel = a_err * (1 + U) + TINY, b_rel + U * (1 + b_rel)
    elif node.op in ("add", "sub"):
        ia, ib = node.args
        aa, ba = split_errors(program, ia, val, memo, depth + 1)
        ab, bb = split_errors(program, ib, val, memo, depth + 1)
        xa, xb = val(ia), val(ib)
        ma, mb = magnitude(xa.xlo, xa.xhi), magnitude(xb.xlo, xb.xhi)
        # the larger term's |x| is at most |s| plus the smaller's
        a_big = ma >= mb
        a_err = aa + ab + (ba + bb) * np.where(a_big, mb, ma)
        b_rel = np.where(a_big, ba, bb)
        a_err, b_rel = a_err * (1 + U) + TINY, b_rel + U * (1 + b_rel)
    a_err, b_rel = a_err * UP, b_rel * UP
    # the interval bound holds too: keep it where it is the smaller absolute part
    use_err = v.err <= a_err
    out = (np.where(use_err, v.err, a_err), np.where(use_err, 0.0, b_rel))
    memo[nid] = out
    return out


@dataclass(frozen=True)
class Layer:
    """One switching term's structure: entry ``a`` (a member of ``members``, the entries of
    the 2-norm ``norm``), ``width`` the c of fmax(norm, c) (-1: M is the norm itself)."""

    members: tuple[int, ...]
    norm: int
    width: int


def norm_rounding(n: int) -> tuple[float, float]:
    """(rel, floor) of a printed n-entry 2-norm's own roundings (:meth:`Analysis._norm_error`):
    ``|fl||f|| - ||f||| <= rel ||f|| + floor``."""
    gamma = n * U / (1 - n * U)
    return (gamma + 2 * U) * (1 + gamma), math.sqrt(n * TINY)


def entry_error(a_i: Array, b_i: Array, a_norm: Array, b_max: Array, m_lo: Array) -> Array:
    """``|P(f)_i - P(x)_i|`` for entry i's split error ``(a_i, b_i)``, the entries' ``||A||_2``
    and ``max B``, and ``M_lo <= max(||x||, c)`` (the module docstring)."""
    return (a_i + a_norm) / m_lo + b_i + b_max


def unit_component(program: Program, layer: Layer, a: int, g: Enclosed, m: Enclosed,
                   val: Callable[[int], Enclosed],
                   memo: dict[int, tuple[Array, Array]]
                   ) -> tuple[Array, Array, Array, Array]:
    """For ``fl(f_a * fl(fg / fM))``: (propagated error before the product's own rounding,
    bound on |f_a fl(fg/fM)|, exact enclosure's magnitude bound, fM's smallest magnitude)
    by the module docstring's rule (``inf`` where fM may be 0)."""
    splits = [split_errors(program, j, val, memo) for j in layer.members]
    a_i, b_i = split_errors(program, a, val, memo)
    a_norm = np.sqrt(sum((s[0] * s[0] for s in splits), np.zeros_like(a_i))) * UP
    b_max = np.max(np.stack([s[1] for s in splits]), axis=0)
    n = val(layer.norm)
    if layer.width >= 0:
        c = val(layer.width)
        c_lo, e_c = np.maximum(c.xlo, 0.0), c.err
    else:
        c_lo, e_c = np.zeros_like(a_i), np.zeros_like(a_i)
    m_lo = np.maximum(c_lo, np.maximum(n.xlo, 0.0))  # <= M(x)
    f_m = np.where((m.flo > 0) | (m.fhi < 0), np.minimum(np.abs(m.flo), np.abs(m.fhi)), 0.0)
    rel, floor = norm_rounding(len(layer.members))
    ok = (m_lo > 0) & (f_m > 0)
    x_a = val(a)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        unit_b = entry_error(a_i, b_i, a_norm, b_max, m_lo)
        unit_a = np.maximum(rel * (1 + floor / f_m) / (1 - rel) + floor / f_m, e_c / f_m)
        u_max = np.minimum(1.0, magnitude(x_a.xlo, x_a.xhi) / m_lo)
        ratio = np.minimum((1 + floor / f_m) / (1 - rel),  # bounds |f_a / fM|
                           magnitude(x_a.flo, x_a.fhi) / f_m)
        gmag_f, gmag_x = magnitude(g.flo, g.fhi), magnitude(g.xlo, g.xhi)
        prop = (gmag_f * (unit_a + unit_b) + g.err * u_max
                + U * gmag_f * ratio + TINY * magnitude(x_a.flo, x_a.fhi)) * UP
        bound_f = gmag_f * ratio * (1 + U) + TINY * magnitude(x_a.flo, x_a.fhi)
    inf = np.full_like(a_i, np.inf)
    return (np.where(ok, prop, inf), np.where(ok, bound_f, inf),
            np.where(ok, gmag_x * u_max, inf), f_m)


def layer_of(program: Program, members: Sequence[int], norm: int, m: int) -> Layer:
    """The :class:`Layer` of M = ``m``: fmax(norm, c) or the norm itself."""
    node = program.nodes[m]
    width = -1
    if node.op == "call" and node.name == "fmax":
        a, b = node.args
        width = b if a == norm else a
    return Layer(tuple(members), norm, width)
