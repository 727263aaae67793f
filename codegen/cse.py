"""Common-subexpression elimination across all outputs of one function, and op counts.

``cse_function`` is the only transformation a backend applies to a spec's expressions:
``sympy.cse`` over every output at once (so a mass matrix and its derivative share their
sines), followed by one printing-driven step: the compound base of a power that prints as
a repeated product (``(a + b)**2`` -> ``_t*_t``) becomes a temporary so it is evaluated
once, and (``reciprocals``, the printed backends) a symbol divided by in several places
is divided by once (its reciprocal a temporary). Temporaries are named ``_t0, _t1, ...``
in order of definition, so the result (and every file printed from it) is the same
whatever the hash seed.
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass

import sympy as sp

from codegen.layout import check_spec
from codegen.printer_base import CountingPrinter
from codegen.spec import FunctionSpec


@dataclass(frozen=True)
class CseResult:
    """A function after CSE: temporaries in evaluation order, then outputs.

    ``outputs[k]`` holds the row-major expressions of ``spec.outputs[k]`` in terms of the
    input symbols and the temporaries.
    """

    spec: FunctionSpec
    temps: tuple[tuple[sp.Symbol, sp.Expr], ...]
    outputs: tuple[tuple[sp.Expr, ...], ...]

    def used_symbols(self) -> frozenset[sp.Symbol]:
        """Input symbols the computation reads (others need not be loaded)."""
        used: set[sp.Basic] = set()
        for _, e in self.temps:
            used |= e.free_symbols
        for exprs in self.outputs:
            for e in exprs:
                used |= e.free_symbols
        inputs = set(self.spec.input_symbols())
        return frozenset(s for s in used if s in inputs and isinstance(s, sp.Symbol))


@dataclass(frozen=True)
class OpCount:
    """Arithmetic after CSE, as printed. Negations are free; ``x**3`` is two ``mul``;
    ``other`` lists remaining calls and comparisons by name (sorted)."""

    add: int = 0
    mul: int = 0
    div: int = 0
    sincos: int = 0
    sqrt: int = 0
    other: tuple[tuple[str, int], ...] = ()

    @property
    def arithmetic(self) -> int:
        """Additions, multiplications, divisions, sin/cos and square roots together (not
        the comparisons and other calls)."""
        return self.add + self.mul + self.div + self.sincos + self.sqrt

    def summary(self) -> str:
        """E.g. ``41 add, 63 mul, 2 div, 2 sin/cos, 0 sqrt`` (+ ``, 1 fmax`` if any)."""
        text = (
            f"{self.add} add, {self.mul} mul, {self.div} div, "
            f"{self.sincos} sin/cos, {self.sqrt} sqrt"
        )
        return text + "".join(f", {n} {name}" for name, n in self.other)

    def comment(self) -> str:
        """The line each generated function's documentation carries."""
        return f"operations after CSE: {self.summary()}"


def _needs_single_base(expr: sp.Pow) -> bool:
    """True if printing ``expr`` repeats its base (|n| >= 2, or n/2 with |n| >= 3)."""
    exponent = expr.exp
    if not isinstance(exponent, sp.Rational) or exponent.q not in (1, 2):
        return False
    return abs(exponent) >= 2 if exponent.q == 1 else abs(exponent) >= sp.Rational(3, 2)


def _temp_names(taken: set[str]) -> Iterator[str]:
    i = 0
    while True:
        name = f"_t{i}"
        if name not in taken:
            yield name
        i += 1


_CACHE: dict[tuple[object, ...], CseResult] = {}


def cse_function(spec: FunctionSpec, reciprocals: bool = False) -> CseResult:
    """Eliminate common subexpressions across all outputs of ``spec``; with
    ``reciprocals``, also divide by each symbol once (the printed backends' form; CasADi's
    graph is left as SymPy's CSE gives it, so that its C is CasADi's own).

    Memoised on the spec's name, inputs and output expressions: every backend and the
    report ask for the same CSE, and it is the expensive step of generation.
    """
    key = (spec.name, spec.input_symbols(), tuple((a.name, a.exprs) for a in spec.outputs),
           spec.definitions, reciprocals)
    hit = _CACHE.get(key)
    if hit is not None and hit.spec == spec:
        return hit
    result = _cse_function(spec, reciprocals)
    _CACHE[key] = result
    return result


def _cse_function(spec: FunctionSpec, reciprocals: bool) -> CseResult:
    check_spec(spec)
    defined = [sym for sym, _ in spec.definitions]
    flat = [e for _, e in spec.definitions] + [e for arg in spec.outputs for e in arg.exprs]
    taken = {str(s) for e in flat for s in e.free_symbols if s not in set(defined)}
    # Placeholder names first; final names are given in definition order below.
    raw = sp.numbered_symbols("_cse_tmp", start=0)
    pairs, reduced = sp.cse(flat, symbols=raw, optimizations=None, order="canonical")
    # The definitions are temporaries too, each after what it reads (CSE's temporaries
    # may read definitions: one order for both, stable, by dependency).
    pairs = _dependency_order(list(pairs) + list(zip(defined, reduced[: len(defined)],
                                                     strict=True)))
    reduced = reduced[len(defined):]
    if defined:
        pairs, reduced = _inline_trivial(pairs, reduced, set(defined))

    # Hoist compound bases of repeated-product powers into temporaries.
    hoisted: list[tuple[sp.Symbol, sp.Expr]] = []
    base_temps: dict[sp.Expr, sp.Symbol] = {}
    memo: dict[sp.Basic, sp.Basic] = {}
    counter = itertools.count()

    def visit(expr: sp.Basic) -> sp.Basic:
        if expr.is_Atom:
            return expr
        if expr in memo:
            return memo[expr]
        args = [visit(a) for a in expr.args]
        out = (
            expr.func(*args)
            if any(a is not b for a, b in zip(args, expr.args, strict=True))
            else expr
        )
        if (
            isinstance(out, sp.Pow)
            and _needs_single_base(out)
            and not isinstance(out.base, sp.Symbol)
            and out.base.free_symbols
        ):
            base = out.base
            if base not in base_temps:
                sym = sp.Symbol(f"_cse_pow{next(counter)}")
                base_temps[base] = sym
                hoisted.append((sym, base))
            out = sp.Pow(base_temps[base], out.exp)
        memo[expr] = out
        return out

    for sym, e in pairs:
        new_e = visit(e)
        hoisted.append((sym, new_e))  # bases found inside e were appended first
    outputs_flat = [visit(e) for e in reduced]
    hoisted, outputs_flat = _merge_equal_temps(hoisted, outputs_flat)
    if reciprocals:
        hoisted, outputs_flat = _share_reciprocals(hoisted, outputs_flat)

    # Final names _t0, _t1, ... in definition order (skipping names of input symbols).
    names = _temp_names(taken)
    rename = {sym: sp.Symbol(next(names)) for sym, _ in hoisted}
    temps = tuple((rename[s], e.xreplace(rename)) for s, e in hoisted)
    outputs_flat = [e.xreplace(rename) for e in outputs_flat]

    outputs: list[tuple[sp.Expr, ...]] = []
    offset = 0
    for arg in spec.outputs:
        n = len(arg.exprs)
        outputs.append(tuple(outputs_flat[offset : offset + n]))
        offset += n
    return CseResult(spec=spec, temps=temps, outputs=tuple(outputs))


def _share_reciprocals(
    temps: list[tuple[sp.Symbol, sp.Expr]], outputs: list[sp.Expr]
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """One division per symbol: a symbol that appears in two or more places with a negative
    integer power (``r/b`` and ``1/(b*b)``: two divisions as printed) gets a temporary
    ``1/x`` right after it is known, and those powers become powers of it (``r*_t``,
    ``_t*_t``). A division costs several multiplications' time on every target."""
    counts: Counter[sp.Symbol] = Counter()
    for e in [e for _, e in temps] + outputs:
        for node in sp.preorder_traversal(e):
            if (isinstance(node, sp.Pow) and isinstance(node.base, sp.Symbol)
                    and node.exp.is_Integer and node.exp < 0):
                counts[node.base] += 1
    shared = {s for s, n in counts.items() if n >= 2}
    if not shared:
        return temps, outputs
    counter = itertools.count()
    inverse = {s: sp.Symbol(f"_cse_inv{next(counter)}")
               for s in sorted(shared, key=sp.default_sort_key)}

    def rewrite(e: sp.Expr) -> sp.Expr:
        return e.replace(
            lambda x: (isinstance(x, sp.Pow) and x.base in inverse and x.exp.is_Integer
                       and x.exp < 0),
            lambda x: inverse[x.base] ** (-x.exp),
        )

    defined = {s for s, _ in temps}
    out = [(inverse[s], sp.Integer(1) / s) for s in sorted(shared - defined,
                                                              key=sp.default_sort_key)]
    for sym, e in temps:
        out.append((sym, rewrite(e)))
        if sym in inverse:
            out.append((inverse[sym], sp.Integer(1) / sym))
    return out, [rewrite(e) for e in outputs]


def _merge_equal_temps(
    temps: list[tuple[sp.Symbol, sp.Expr]], outputs: list[sp.Expr]
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Temporaries equal to an earlier one, or to its negation, read as that one (value
    numbering after CSE). SymPy's CSE matches subexpressions as they were written; two
    definitions of a stage that become equal once their own temporaries are named (the
    root frame's S and its derivative, Ṡ, repeat products of S's entries) or that differ
    by a sign stay apart there. Negation is exact: the values are the same bits."""
    subs: dict[sp.Basic, sp.Expr] = {}
    seen: dict[sp.Expr, sp.Symbol] = {}
    kept: list[tuple[sp.Symbol, sp.Expr]] = []
    for sym, e in temps:
        e = e.xreplace(subs) if subs else e
        if e in seen:
            subs[sym] = seen[e]
        elif not e.is_Atom and -e in seen:
            subs[sym] = -seen[-e]
        else:
            seen[e] = sym
            kept.append((sym, e))
    return kept, [e.xreplace(subs) for e in outputs] if subs else outputs


def _inline_trivial(
    pairs: list[tuple[sp.Symbol, sp.Expr]], reduced: list[sp.Expr], defined: set[sp.Symbol]
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Definitions that CSE reduced to another temporary, a number or its negation,
    substituted where they are read instead of copied (a copy is a line and, negated, an
    operation; negation is exact, so the values are the same bits)."""
    subs: dict[sp.Basic, sp.Expr] = {}
    kept: list[tuple[sp.Symbol, sp.Expr]] = []
    for sym, e in pairs:
        e = e.xreplace(subs) if subs else e
        if sym in defined and (e.is_Atom or (e.is_Mul and len(e.args) == 2
                                             and e.args[0] == -1 and e.args[1].is_Atom)):
            subs[sym] = e
        else:
            kept.append((sym, e))
    return kept, [e.xreplace(subs) for e in reduced] if subs else reduced


def _dependency_order(pairs: list[tuple[sp.Symbol, sp.Expr]]) -> list[tuple[sp.Symbol, sp.Expr]]:
    """``pairs`` (temporaries) reordered so that each comes after every temporary it reads,
    otherwise in their given order (a stable topological sort)."""
    index = {sym: k for k, (sym, _) in enumerate(pairs)}
    needs = [{index[s] for s in e.free_symbols if s in index} for _, e in pairs]
    done: set[int] = set()
    out: list[tuple[sp.Symbol, sp.Expr]] = []
    for start in range(len(pairs)):  # depth-first, iterative: chains can be long
        stack = [(start, iter(sorted(needs[start])))]
        on_stack = {start}
        while stack:
            k, pending = stack[-1]
            j = next((j for j in pending if j not in done), None)
            if j is None:
                stack.pop()
                on_stack.discard(k)
                if k not in done:
                    done.add(k)
                    out.append(pairs[k])
            elif j in on_stack:
                raise ValueError(f"circular definitions through {pairs[j][0]}")
            else:
                stack.append((j, iter(sorted(needs[j]))))
                on_stack.add(j)
    return out


def count_ops(result: CseResult) -> OpCount:
    """Count the operations of a CSE result exactly as the C and Python printers print it."""
    names = {s: str(s) for s in result.spec.input_symbols()}
    names.update({s: str(s) for s, _ in result.temps})
    printer = CountingPrinter(names)
    for _, e in result.temps:
        printer.expr_code(e)
    for exprs in result.outputs:
        for e in exprs:
            printer.expr_code(e)
    return op_count_from(printer.ops)


def op_count_from(ops: Counter[str]) -> OpCount:
    """Fold a printer's raw counter into an :class:`OpCount`."""
    main = {"add", "mul", "div", "sin", "cos", "sqrt"}
    other = tuple(sorted((k, v) for k, v in ops.items() if k not in main and v))
    return OpCount(
        add=ops["add"],
        mul=ops["mul"],
        div=ops["div"],
        sincos=ops["sin"] + ops["cos"],
        sqrt=ops["sqrt"],
        other=other,
    )
