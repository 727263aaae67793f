"""Sound float32 rounding-error and range analysis of a printed :class:`Program`.

Every node carries, for each box of a batch (numpy arrays, one entry per box):

* ``X``: an enclosure of its exact real value (interval arithmetic, bounds rounded
  outward in double),
* ``F``: an enclosure of the value float32 computes (round-to-nearest is monotone, so a
  float32 result lies in the rounded image of its operands' enclosures),
* ``E``: a bound on ``|float32 value - exact value|``, propagated through each operation
  (``|fa*fb - xa*xb| <= |fa| Eb + |xb| Ea``, ``|fa/fb - xa/xb| <= Ea/|fb| + |xa| Eb/(|fb||xb|)``,
  sin/cos 1-Lipschitz, ``|sqrt a - sqrt b| <= min(sqrt|a-b|, |a-b|/(sqrt a + sqrt b))``)
  plus each operation's own rounding: ``2^-24 |result| + 2^-150`` (IEEE round to
  nearest, subnormals included), for sin and cos the helpers' stated 2 ulp
  (``wmr_types.h``: ``2^-22 |result| + 2^-148``).

This is first order only in the sense that it keeps no correlation between errors: every
bound is a rigorous upper bound (the products of errors are kept). The error bound of the
double computations themselves is absorbed by rounding ``E`` up by ``2^-50`` relatively
at every node, and every interval bound outward by one double ulp.

A node is *unsafe* in a box when its float32 value might be non-finite there: a result
enclosure reaching ``FLT_MAX``, a divisor or its exact value not excluding 0, a square
root of an enclosure reaching below 0, a bounded sin/cos argument beyond ``2e6``, or an
undecided guard. The certificate requires no unsafe node in any box.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from codegen.backends.c.certify.affine import affine_bounds
from codegen.backends.c.certify.program import Node, Program
from codegen.backends.c.certify.unitvector import layer_of, unit_component
from codegen.backends.c.certify.unitvector import magnitude as _mag

Array = npt.NDArray[np.float64]
U = 2.0**-24  # float32 unit roundoff
TINY = 2.0**-150  # half the smallest subnormal: a rounding's absolute error floor
FLT_MAX = float(np.finfo(np.float32).max)
TRIG_ULPS = 2.0  # wmr_sincos_bounded and _checked: stated accuracy in float32 (wmr_types.h)
TRIG_BOUND = 2.0e6  # wmr_trig_in_range: where the bounded reduction is exact
LIT_REL = 2.0**-53  # a printed literal is the double nearest the exact constant
UP = 1.0 + 2.0**-50  # rounds an error bound computed in double up past its own errors


@dataclass
class Value:
    """Per box: exact enclosure [xlo, xhi], float32 enclosure [flo, fhi], error bound."""

    xlo: Array
    xhi: Array
    flo: Array
    fhi: Array
    err: Array


@dataclass
class Truth:
    """A condition per box: ``may_true`` / ``may_false`` for the float32 evaluation and
    the exact one (a branch is decided when one of the two is False for both)."""

    f_true: npt.NDArray[np.bool_]
    f_false: npt.NDArray[np.bool_]
    x_true: npt.NDArray[np.bool_]
    x_false: npt.NDArray[np.bool_]


def _down(a: Array) -> Array:
    return np.nextafter(a, -np.inf)


def _up(a: Array) -> Array:
    return np.nextafter(a, np.inf)


def _mig(lo: Array, hi: Array) -> Array:
    """The smallest magnitude in [lo, hi] (0 if it contains 0)."""
    return np.where((lo > 0) | (hi < 0), np.minimum(np.abs(lo), np.abs(hi)), 0.0)


def _mul_iv(alo: Array, ahi: Array, blo: Array, bhi: Array) -> tuple[Array, Array]:
    with np.errstate(invalid="ignore", over="ignore"):
        c = np.stack([alo * blo, alo * bhi, ahi * blo, ahi * bhi])
    c = np.where(np.isnan(c), 0.0, c)  # 0 * inf of an unbounded enclosure: an unsafe node
    return _down(c.min(axis=0)), _up(c.max(axis=0))


def _sq_iv(lo: Array, hi: Array) -> tuple[Array, Array]:
    m = _mag(lo, hi)
    n = _mig(lo, hi)
    return np.maximum(_down(n * n), 0.0), _up(m * m)


def _div_iv(alo: Array, ahi: Array, blo: Array, bhi: Array) -> tuple[Array, Array]:
    safe = (blo > 0) | (bhi < 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        c = np.stack([alo / blo, alo / bhi, ahi / blo, ahi / bhi])
    lo = np.where(safe, _down(np.nan_to_num(c.min(axis=0), nan=-np.inf)), -np.inf)
    hi = np.where(safe, _up(np.nan_to_num(c.max(axis=0), nan=np.inf)), np.inf)
    return lo, hi


def _trig_iv(name: str, lo: Array, hi: Array) -> tuple[Array, Array]:
    """An enclosure of sin or cos over [lo, hi] (extrema where a critical point is in)."""
    shift = 0.0 if name == "cos" else np.pi / 2  # sin x = cos(x - pi/2)
    a, b = lo - shift, hi - shift
    vlo = np.minimum(np.cos(a), np.cos(b))
    vhi = np.maximum(np.cos(a), np.cos(b))
    # cos has maxima at 2k pi, minima at (2k+1) pi: is one inside [a, b]?
    k_max = np.ceil(a / (2 * np.pi) - 1e-12)
    has_max = k_max * 2 * np.pi <= b + 1e-12
    k_min = np.ceil((a - np.pi) / (2 * np.pi) - 1e-12)
    has_min = k_min * 2 * np.pi + np.pi <= b + 1e-12
    vhi = np.where(has_max | ~np.isfinite(a + b), 1.0, vhi)
    vlo = np.where(has_min | ~np.isfinite(a + b), -1.0, vlo)
    # math library error of the double cos and of the shift: a few 1e-16; widen by 1e-15
    return np.maximum(vlo - 1e-15, -1.0), np.minimum(vhi + 1e-15, 1.0)


class Analysis:
    """Evaluates a program over a batch of boxes. ``unsafe[k]`` collects, per box, whether
    any node might be non-finite, and ``why`` the first such node's description."""

    def __init__(self, program: Program, affine: bool = True,
                 known: Mapping[int, tuple[float, float]] | None = None) -> None:
        self.program = program
        self.affine = affine
        # proved enclosures of exact values over the whole declared box (per node; see
        # :mod:`.divisors`): they hold in every sub-box, intersected with the box's own
        self.known = dict(known or {})
        self._tight: tuple[Array, Array] | None = None
        self._norm_parts: dict[int, tuple[Array, float]] = {}
        self._splits: dict[int, tuple[Array, Array]] = {}  # :func:`.unitvector.split_errors`
        self.open_guards: list[str] = []  # statuses of guards the last run did not prove
        self.values: list[Value | Truth | None] = []

    def run(self, lo: Mapping[int, Array], hi: Mapping[int, Array],
            in_err: Mapping[int, Array] | None = None,
            ) -> tuple[list[Value], npt.NDArray[np.bool_], list[str]]:
        """``lo``/``hi`` per input node; ``in_err``: an input's own error bound (an input
        computed upstream in float32, e.g. a step's ``e = q_des - q``)."""
        n = len(next(iter(lo.values())))
        values: list[Value | Truth | None] = []
        unsafe = np.zeros(n, dtype=bool)
        why: list[str] = [""] * n
        zero = np.zeros(n)

        def flag(mask: npt.NDArray[np.bool_], text: str) -> None:
            nonlocal unsafe
            for k in np.nonzero(mask & ~unsafe)[0]:
                why[k] = text
            unsafe = unsafe | mask

        def val(i: int) -> Value:
            v = values[i]
            assert isinstance(v, Value), f"node {i} is not a value"
            return v

        def truth(i: int) -> Truth:
            v = values[i]
            assert isinstance(v, Truth), f"node {i} is not a condition"
            return v

        self._norm_parts = {}
        self._splits = {}
        tight = affine_bounds(self.program, lo, hi, self.known) if self.affine else []
        for idx, node in enumerate(self.program.nodes):
            self._tight = tight[idx] if tight else None
            if idx in self.known:
                klo, khi = self.known[idx]
                self._tight = ((np.maximum(self._tight[0], klo), np.minimum(self._tight[1], khi))
                               if self._tight is not None else (zero + klo, zero + khi))
            values.append(self._node(idx, node, val, truth, lo, hi, in_err, zero, flag))
        out = [val(i) for _, i in self.program.outputs]
        # a guard that may fail is no overflow: the function then returns its status and
        # writes nothing; the certificate holds for the calls that return OK
        self.open_guards = sorted({status for g, status in self.program.guards
                                   if not np.all(val(g).flo > 0)})
        self.values = values  # every node's, for :mod:`.divisors`' derivatives
        return out, unsafe, why

    def _rounded(self, rlo: Array, rhi: Array, prop: Array, xlo: Array, xhi: Array,
                 flag: object, text: str, rel: float = U, floor: float = TINY) -> Value:
        """A float32 result whose exact-operand image is [rlo, rhi] (of the float
        operands), propagated error ``prop``, exact enclosure [xlo, xhi]."""
        if self._tight is not None:  # the affine enclosure of the exact value
            xlo, xhi = np.maximum(xlo, self._tight[0]), np.minimum(xhi, self._tight[1])
        mag = _mag(rlo, rhi)
        assert callable(flag)
        flag(~(mag < FLT_MAX), f"{text}: may overflow")
        rnd = rel * mag + floor
        flo = _down(rlo - rel * np.abs(rlo) - floor)
        fhi = _up(rhi + rel * np.abs(rhi) + floor)
        # rounding to nearest is monotone and keeps 0: a result of one sign keeps it
        flo = np.where(rlo >= 0, np.maximum(flo, 0.0), flo)
        fhi = np.where(rhi <= 0, np.minimum(fhi, 0.0), fhi)
        err = (prop + rnd) * UP
        # the float value is also within err of the exact one
        flo = np.maximum(flo, _down(xlo - err))
        fhi = np.minimum(fhi, _up(xhi + err))
        return Value(xlo, xhi, flo, fhi, err)

    def _node(self, idx: int, node: Node, val: object, truth: object,
              lo: Mapping[int, Array], hi: Mapping[int, Array],
              in_err: Mapping[int, Array] | None, zero: Array, flag: object
              ) -> Value | Truth:
        assert callable(val) and callable(truth) and callable(flag)
        op = node.op
        where = f"node {idx} ({op}{' ' + node.name if node.name else ''})"
        if op == "in":
            e = in_err.get(idx, zero) if in_err else zero
            return Value(lo[idx], hi[idx], _down(lo[idx] - e), _up(hi[idx] + e), e)
        if op == "lit":
            v = node.value
            f = float(np.float32(v))
            lit_err = abs(f - v) + LIT_REL * abs(v)
            return Value(zero + (v - LIT_REL * abs(v)), zero + (v + LIT_REL * abs(v)),
                         zero + f, zero + f, zero + lit_err)
        if op == "neg":
            a = val(node.args[0])
            return Value(-a.xhi, -a.xlo, -a.fhi, -a.flo, a.err)
        if op in ("add", "sub"):
            a, b = val(node.args[0]), val(node.args[1])
            if op == "add":
                xlo, xhi = _down(a.xlo + b.xlo), _up(a.xhi + b.xhi)
                rlo, rhi = _down(a.flo + b.flo), _up(a.fhi + b.fhi)
                # a sum of non-negative numbers is non-negative (in double too)
                xlo = np.where((a.xlo >= 0) & (b.xlo >= 0), np.maximum(xlo, 0.0), xlo)
                rlo = np.where((a.flo >= 0) & (b.flo >= 0), np.maximum(rlo, 0.0), rlo)
            else:
                xlo, xhi = _down(a.xlo - b.xhi), _up(a.xhi - b.xlo)
                rlo, rhi = _down(a.flo - b.fhi), _up(a.fhi - b.flo)
            return self._rounded(rlo, rhi, a.err + b.err, xlo, xhi, flag, where)
        if op == "mul":
            a, b = val(node.args[0]), val(node.args[1])
            for ia, ib in (node.args, node.args[::-1]):
                normalised = self._normalised(ia, ib)
                if normalised is not None:
                    g, m = normalised
                    old = self._scaled_component(val(ia), val(g), val(m), flag, where,
                                                 self._relative_part(m, val))
                    return self._unit_vector(old, ia, g, m, val, flag, where)
            if node.args[0] == node.args[1]:  # a square of one value: never negative
                xlo, xhi = _sq_iv(a.xlo, a.xhi)
                rlo, rhi = _sq_iv(a.flo, a.fhi)
                prop = (_mag(a.flo, a.fhi) + _mag(a.xlo, a.xhi)) * a.err
            else:
                xlo, xhi = _mul_iv(a.xlo, a.xhi, b.xlo, b.xhi)
                rlo, rhi = _mul_iv(a.flo, a.fhi, b.flo, b.fhi)
                prop = _mag(a.flo, a.fhi) * b.err + _mag(b.xlo, b.xhi) * a.err
                if self._nonnegative(idx):  # (x*y)*y with x >= 0: never negative
                    xlo, rlo = np.maximum(xlo, 0.0), np.maximum(rlo, 0.0)
            return self._rounded(rlo, rhi, prop, xlo, xhi, flag, where)
        if op == "div":
            a, b = val(node.args[0]), val(node.args[1])
            fmig, xmig = _mig(b.flo, b.fhi), _mig(b.xlo, b.xhi)
            flag(~((fmig > 0) & (xmig > 0)), f"{where}: divisor may be 0")
            xlo, xhi = _div_iv(a.xlo, a.xhi, b.xlo, b.xhi)
            rlo, rhi = _div_iv(a.flo, a.fhi, b.flo, b.fhi)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                prop = a.err / fmig + _mag(a.xlo, a.xhi) * b.err / (fmig * xmig)
            prop = np.where((fmig > 0) & (xmig > 0), prop, np.inf)
            return self._rounded(rlo, rhi, prop, xlo, xhi, flag, where)
        if op == "call":
            value = self._call(node, [val(i) for i in node.args], where, flag)
            members = self._square_sum(node.args[0]) if node.name == "sqrt" else None
            if members:  # a 2-norm: 1-Lipschitz in its entries, see _norm_error
                lip, rel = self._norm_error([val(i) for i in members], value)
                self._norm_parts[idx] = (lip, rel)
                value.err = np.minimum(value.err, (lip + (_mag(value.xlo, value.xhi) + lip)
                                                   * rel + math.sqrt(len(members) * TINY))
                                       * UP)
            return value
        if op == "cond":
            c = truth(node.args[0])
            a, b = val(node.args[1]), val(node.args[2])
            only_a = ~c.f_false & ~c.x_false
            only_b = ~c.f_true & ~c.x_true
            # undecided: the float and the exact value may take different branches
            cross = np.maximum(
                np.maximum(np.abs(a.fhi - b.xlo), np.abs(a.flo - b.xhi)),
                np.maximum(np.abs(b.fhi - a.xlo), np.abs(b.flo - a.xhi)))
            both = np.maximum(np.maximum(a.err, b.err), cross)
            return Value(
                np.where(only_a, a.xlo, np.where(only_b, b.xlo, np.minimum(a.xlo, b.xlo))),
                np.where(only_a, a.xhi, np.where(only_b, b.xhi, np.maximum(a.xhi, b.xhi))),
                np.where(only_a, a.flo, np.where(only_b, b.flo, np.minimum(a.flo, b.flo))),
                np.where(only_a, a.fhi, np.where(only_b, b.fhi, np.maximum(a.fhi, b.fhi))),
                np.where(only_a, a.err, np.where(only_b, b.err, both)))
        if op in ("lt", "le", "gt", "ge"):
            a, b = val(node.args[0]), val(node.args[1])
            if op in ("gt", "ge"):  # a > b is b < a
                a, b = b, a
            strict = op in ("lt", "gt")
            # a < b surely true when a.hi < b.lo; surely false when a.lo >= b.hi
            def decide(alo: Array, ahi: Array, blo: Array, bhi: Array
                       ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
                sure_true = ahi < blo if strict else ahi <= blo
                sure_false = alo >= bhi if strict else alo > bhi
                return ~sure_false, ~sure_true
            ft, ff = decide(a.flo, a.fhi, b.flo, b.fhi)
            xt, xf = decide(a.xlo, a.xhi, b.xlo, b.xhi)
            return Truth(ft, ff, xt, xf)
        if op in ("and", "or", "not"):
            ts = [truth(i) for i in node.args]
            if op == "not":
                t = ts[0]
                return Truth(t.f_false, t.f_true, t.x_false, t.x_true)
            p, q = ts
            if op == "and":
                return Truth(p.f_true & q.f_true, p.f_false | q.f_false,
                             p.x_true & q.x_true, p.x_false | q.x_false)
            return Truth(p.f_true | q.f_true, p.f_false & q.f_false,
                         p.x_true | q.x_true, p.x_false & q.x_false)
        raise ValueError(f"cannot analyse {where}")

    def _norm_members(self, nid: int) -> set[int]:
        """The nodes x whose x*x the square root ``nid`` sums (empty if it is not one)."""
        node = self.program.nodes[nid]
        if node.op != "call" or node.name != "sqrt":
            return set()
        members: set[int] = set()
        stack = [node.args[0]]
        while stack:
            n = self.program.nodes[stack.pop()]
            if n.op == "add":
                stack += list(n.args)
            elif n.op == "mul" and n.args[0] == n.args[1]:
                members.add(n.args[0])
        return members

    def _nonnegative(self, nid: int) -> bool:
        """Whether node ``nid`` is >= 0 by its structure, in exact and in float32 arithmetic
        (rounding to nearest keeps signs): a square, (x*y)*y with x >= 0, a product or sum
        of such, a square root, an absolute value, a non-negative literal."""
        node = self.program.nodes[nid]
        if node.op == "lit":
            return node.value >= 0
        if node.op == "call":
            return node.name in ("sqrt", "fabs")
        if node.op == "add":
            return all(self._nonnegative(a) for a in node.args)
        if node.op != "mul":
            return False
        a, b = node.args
        if a == b:
            return True
        inner = self.program.nodes[a]
        if inner.op == "mul" and inner.args[1] == b and self._nonnegative(inner.args[0]):
            return True
        return self._nonnegative(a) and self._nonnegative(b)

    def _square_sum(self, nid: int) -> list[int] | None:
        """The entries x_i of a sum of squares x_0*x_0 + x_1*x_1 + ... (None otherwise)."""
        members: list[int] = []
        stack = [nid]
        while stack:
            n = self.program.nodes[stack.pop()]
            if n.op == "add":
                stack += list(n.args)
            elif n.op == "mul" and n.args[0] == n.args[1]:
                members.append(n.args[0])
            else:
                return None
        return members

    @staticmethod
    def _norm_error(entries: Sequence[Value], norm: Value) -> tuple[Array, float]:
        """|fl(sqrt(sum fl(x^2))) - ||x||| for entries with errors E_i: the norm is
        1-Lipschitz (<= sqrt(sum E_i^2)), and the squares, the n - 1 additions and the root
        round by at most gamma_n + 2u relative (gamma_n = n u / (1 - n u)), plus the
        squares' subnormal floors (sqrt(n) 2^-75)."""
        n = len(entries)
        lip = np.sqrt(sum((e.err * e.err for e in entries), np.zeros_like(norm.err)))
        gamma = n * U / (1 - n * U)
        rel = (gamma + 2 * U) * (1 + gamma)
        return lip * UP, rel  # |error| <= lip + (|N| + lip) rel + sqrt(n) 2^-75

    def _normalised(self, ia: int, ib: int) -> tuple[int, int] | None:
        """``(g, M)`` when node ``ib`` is ``g / M`` with ``M`` = fmax(N, c) or N, N a
        2-norm one of whose entries is node ``ia``: then |a| <= M exactly, and a * b is
        a component of a normalised vector times g (the switching term s/max(||s||, eps)
        of the robust laws), bounded by |g| whatever the box."""
        b = self.program.nodes[ib]
        if b.op != "div":
            return None
        g, m = b.args
        mn = self.program.nodes[m]
        norms = [m]
        if mn.op == "call" and mn.name == "fmax":
            norms = list(mn.args)
        if any(ia in self._norm_members(n) for n in norms):
            return g, m
        return None

    def _relative_part(self, m: int, val: object) -> tuple[Array, float] | None:
        """M = fmax(N, c) or N, N a 2-norm: (absolute part, relative part) of M's error
        (|fM - xM| <= max(|fN - xN|, Ec) <= abs + rel |fN| <= abs + rel |fM|)."""
        assert callable(val)
        node = self.program.nodes[m]
        if m in self._norm_parts:
            return self._norm_parts[m]
        if node.op == "call" and node.name == "fmax":
            a, b = node.args
            if a in self._norm_parts or b in self._norm_parts:
                n, c = (a, b) if a in self._norm_parts else (b, a)
                lip, rel = self._norm_parts[n]
                tiny = math.sqrt(8 * TINY)
                return np.maximum(lip, val(c).err) + tiny, rel
        return None

    def _scaled_component(self, a: Value, g: Value, m: Value, flag: object,
                          where: str, parts: tuple[Array, float] | None = None) -> Value:
        """fl(a * fl(g / M)) with |a| <= M in exact arithmetic (see :meth:`_normalised`):
        |fa fg/fM - xa xg/xM| <= Ea |fg|/|fM| + |xa| |fg/fM - xg/xM|, and
        |xa| |fg/fM - xg/xM| <= Eg xM/|fM| + |xg| EM/|fM| because |xa|/xM <= 1."""
        assert callable(flag)
        fm = _mig(m.flo, m.fhi)
        flag(~(fm > 0), f"{where}: normalising divisor may be 0")
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = 1.0 + (m.err + a.err) / fm  # bounds |fa / fM|
            gmag_f, gmag_x = _mag(g.flo, g.fhi), _mag(g.xlo, g.xhi)
            m_rel = m.err / fm  # bounds |fM - xM| / |fM|
            if parts is not None:
                m_rel = np.minimum(m_rel, parts[0] / fm + parts[1] * (1 + U))
            prop = (a.err * gmag_f / fm + g.err * (1.0 + m_rel) + gmag_x * m_rel)
            # fl(g/M) = (fg/fM)(1 + d): times fa, u |fg| |fa/fM| (and a subnormal's floor)
            quotient_round = U * gmag_f * ratio + TINY * _mag(a.flo, a.fhi)
        prop = np.where(fm > 0, prop + quotient_round, np.inf)
        bound_f = np.where(fm > 0, gmag_f * ratio * (1 + U) ** 2, np.inf)
        return self._rounded(-bound_f, bound_f, prop, -gmag_x, gmag_x, flag, where)

    def _unit_vector(self, old: Value, ia: int, g: int, m: int, val: object, flag: object,
                     where: str) -> Value:
        """fl(a * fl(g / M)) by :mod:`.unitvector`'s rule (s/max(||s||, c) as one unit
        vector, its entries' cancellation kept), intersected with ``old`` (the rule of
        :meth:`_scaled_component`): both hold, so does the tighter of the two per box."""
        assert callable(val)
        norms = [m]
        mn = self.program.nodes[m]
        if mn.op == "call" and mn.name == "fmax":
            norms = list(mn.args)
        norm = next(n for n in norms if ia in self._norm_members(n))
        members = self._square_sum(self.program.nodes[norm].args[0])
        if not members:
            return old
        layer = layer_of(self.program, members, norm, m)
        prop, bound_f, bound_x, _ = unit_component(self.program, layer, ia, val(g), val(m),
                                                   val, self._splits)
        # where the rule does not apply (M's lower bound 0): the old rule's enclosures
        bound_f = np.where(np.isfinite(bound_f), bound_f, _mag(old.flo, old.fhi))
        bound_x = np.where(np.isfinite(bound_x), bound_x, _mag(old.xlo, old.xhi))
        new = self._rounded(-bound_f, bound_f, prop, -bound_x, bound_x, flag, where)
        return Value(np.maximum(old.xlo, new.xlo), np.minimum(old.xhi, new.xhi),
                     np.maximum(old.flo, new.flo), np.minimum(old.fhi, new.fhi),
                     np.minimum(old.err, new.err))

    def _call(self, node: Node, args: Sequence[Value], where: str, flag: object) -> Value:
        assert callable(flag)
        name = node.name
        if name in ("sin", "cos", "sin_bounded", "cos_bounded"):
            a = args[0]
            base = name.split("_")[0]
            if name.endswith("_bounded"):
                flag(~(_mag(a.flo, a.fhi) <= TRIG_BOUND),
                     f"{where}: argument beyond the bounded reduction's 2e6")
            xlo, xhi = _trig_iv(base, a.xlo, a.xhi)
            rlo, rhi = _trig_iv(base, a.flo, a.fhi)
            prop = np.minimum(a.err, 2.0)
            v = self._rounded(rlo, rhi, prop, xlo, xhi, flag, where,
                              rel=TRIG_ULPS * 2.0 * U, floor=TRIG_ULPS * 2.0**-149)
            return v
        if name == "sqrt":
            a = args[0]
            flag(~(a.flo >= 0), f"{where}: square root of a value that may be negative")
            flag(~(a.xlo >= 0), f"{where}: exact square root argument may be negative")
            xl, fl = np.maximum(a.xlo, 0.0), np.maximum(a.flo, 0.0)
            xlo, xhi = _down(np.sqrt(xl)), _up(np.sqrt(np.maximum(a.xhi, 0.0)))
            rlo, rhi = _down(np.sqrt(fl)), _up(np.sqrt(np.maximum(a.fhi, 0.0)))
            with np.errstate(divide="ignore", invalid="ignore"):
                lip = a.err / (np.sqrt(xl) + np.sqrt(fl))
            prop = np.minimum(np.sqrt(a.err), np.nan_to_num(lip, nan=np.inf, posinf=np.inf))
            return self._rounded(rlo, rhi, prop, xlo, xhi, flag, where)
        if name == "fabs":
            a = args[0]
            xlo, xhi = _mig(a.xlo, a.xhi), _mag(a.xlo, a.xhi)
            flo, fhi = _mig(a.flo, a.fhi), _mag(a.flo, a.fhi)
            return Value(xlo, xhi, flo, fhi, a.err)
        if name in ("fmax", "fmin"):
            a, b = args
            f = np.maximum if name == "fmax" else np.minimum
            return Value(f(a.xlo, b.xlo), f(a.xhi, b.xhi), f(a.flo, b.flo), f(a.fhi, b.fhi),
                         np.maximum(a.err, b.err))
        raise ValueError(f"cannot analyse {where}: no model of {name}")

