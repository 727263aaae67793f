"""A checked function split at its parameters: what can be evaluated once when the
parameters change, and what must be evaluated per call.

A :class:`~codegen.spec.FunctionSpec` with ``prepared=True`` gets, in the C backend, a
prepare-parameters API besides the function itself: ``<module>_prepare(p, prepared)``
validates the parameters and evaluates every parameter-only subexpression once;
``<name>_prepared(prepared, ...)`` reads those values and does only the per-call work.
:func:`prepared_form` decides the split, for any robot, from the function's CSE alone:

* a parameter-only expression is one whose free symbols are parameter symbols (the
  ``"params"`` inputs' symbols) or parameter-only temporaries; a number alone is not one;
* every CSE temporary that is parameter-only is evaluated at prepare time;
* the other temporaries, the guards and the outputs (the per-call part) first have the
  common factors of their sums collected (:func:`collect_factors`: ``a*x + a*y`` ->
  ``a*(x + y)``, one multiplication fewer per collected term); then every maximal
  parameter-only subexpression in them is made a temporary too, and so are the
  parameter-only factors of a product (``x*r*r/b`` -> ``x*_t``, ``_t = r*r/b``) and the
  parameter-only terms of a sum; a numeric coefficient other than ±1 joins its product's
  parameter factors;
* a guard whose condition is parameter-only is checked at prepare time; the others (a
  model whose S^T M S depends on q) stay in the per-call part, in their order;
* the prepared values are the parameters and parameter-only temporaries the per-call
  part reads; temporaries nothing reads any more are dropped.

The function without prepare evaluates the same temporaries in the same order (parameter
part, parameter guards, per-call part), so it and prepare + prepared give bit-identical
results. Temporaries are renamed ``_t0, _t1, ...`` in that order.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from codegen.cse import CseResult, OpCount, _temp_names, op_count_from
from codegen.printer_base import CountingPrinter
from codegen.spec import FunctionSpec

Temp = tuple[sp.Symbol, sp.Expr]


@dataclass(frozen=True)
class PreparedForm:
    """A checked function's CSE, split at its parameters (see the module docstring).

    ``param_temps`` are evaluated by prepare (and first by the unprepared function),
    ``param_guards`` checked after them; ``kept`` (parameter symbols and parameter
    temporaries) are the prepared values the per-call part reads, in struct order;
    ``state_temps``, then ``state_guards``, then ``outputs`` are the per-call part.
    Guards are ``(index into spec.guards, condition)``.
    """

    spec: FunctionSpec
    params: frozenset[sp.Symbol]
    param_temps: tuple[Temp, ...]
    param_guards: tuple[tuple[int, sp.Expr], ...]
    kept: tuple[sp.Symbol, ...]
    state_temps: tuple[Temp, ...]
    state_guards: tuple[tuple[int, sp.Expr], ...]
    outputs: tuple[tuple[sp.Expr, ...], ...]

    def used_params(self) -> frozenset[sp.Symbol]:
        """Parameter symbols prepare reads."""
        used: set[sp.Basic] = set(self.kept)
        for _, e in self.param_temps:
            used |= e.free_symbols
        for _, e in self.param_guards:
            used |= e.free_symbols
        return frozenset(s for s in used if s in self.params and isinstance(s, sp.Symbol))

    def ops(self, part: str = "all") -> OpCount:
        """Operations of the ``"prepare"`` part (parameter temporaries and guards), the
        ``"per_call"`` part or ``"all"`` (the function without prepare), as printed."""
        temps = (*self.param_temps, *self.state_temps)
        names = {s: str(s) for s in (*self.spec.input_symbols(), *(t for t, _ in temps))}
        printer = CountingPrinter(names)
        prepare = [e for _, e in (*self.param_temps, *self.param_guards)]
        per_call = [e for _, e in (*self.state_temps, *self.state_guards)]
        per_call += [e for out in self.outputs for e in out]
        if part not in ("prepare", "per_call", "all"):
            raise ValueError(f"part must be 'prepare', 'per_call' or 'all', not {part!r}")
        exprs = {"prepare": prepare, "per_call": per_call, "all": prepare + per_call}[part]
        for e in exprs:
            printer.expr_code(e)
        return op_count_from(printer.ops)

    def used_state(self) -> frozenset[sp.Symbol]:
        """Non-parameter input symbols the per-call part reads."""
        inputs = set(self.spec.input_symbols()) - self.params
        used: set[sp.Basic] = set()
        for _, e in (*self.state_temps, *self.state_guards):
            used |= e.free_symbols
        for exprs in self.outputs:
            for e in exprs:
                used |= e.free_symbols
        return frozenset(s for s in used if s in inputs and isinstance(s, sp.Symbol))


def _factors(term: sp.Expr) -> list[sp.Symbol]:
    """The symbols a term is a product of (``2*a*b`` -> a, b; ``a`` -> a)."""
    if isinstance(term, sp.Symbol):
        return [term]
    if isinstance(term, sp.Mul):
        return [f for f in term.args if isinstance(f, sp.Symbol)]
    return []


def _without(term: sp.Expr, factor: sp.Symbol) -> sp.Expr:
    if term == factor:
        return sp.S.One
    args = list(term.args)
    args.remove(factor)
    return sp.Mul(*args)


def _collect_terms(terms: list[sp.Expr]) -> sp.Expr:
    counts: dict[sp.Symbol, int] = {}
    for t in terms:
        for f in set(_factors(t)):
            counts[f] = counts.get(f, 0) + 1
    shared = [f for f, n in counts.items() if n >= 2]
    if not shared:
        return sp.Add(*terms)
    best = min(shared, key=lambda f: (-counts[f], str(f)))
    inner = [_without(t, best) for t in terms if best in _factors(t)]
    rest = [t for t in terms if best not in _factors(t)]
    collected = sp.Mul(best, _collect_terms(inner), evaluate=False)
    return sp.Add(collected, _collect_terms(rest)) if rest else collected


def collect_factors(e: sp.Basic) -> sp.Basic:
    """``a*x + a*y + z`` -> ``a*(x + y) + z``, greedily (the symbol shared by most terms
    first, ties by name), in every sum of ``e``: one multiplication fewer per term
    collected."""
    if e.is_Atom:
        return e
    args = [collect_factors(a) for a in e.args]
    if any(a is not b for a, b in zip(args, e.args, strict=True)):
        e = e.func(*args)
    if not isinstance(e, sp.Add):
        return e
    return _collect_terms(list(e.args))


def parameter_symbols(spec: FunctionSpec) -> frozenset[sp.Symbol]:
    """The symbols of the spec's ``"params"`` inputs."""
    return frozenset(s for a in spec.inputs if a.kind == "params" for s in a.all_symbols())


def prepared_form(result: CseResult, spec: FunctionSpec,
                  fixed_inputs: frozenset[str] = frozenset()) -> PreparedForm:
    """Split ``result`` (the CSE of ``spec.checked_spec()``) at the parameters of ``spec``;
    the inputs named in ``fixed_inputs`` count as parameters (values that change only with
    them, e.g. a controller's configuration-derived span)."""
    if not spec.returns_status:
        raise ValueError(f"{spec.name}: a prepared function must return a status")
    params = parameter_symbols(spec) | frozenset(
        s for a in spec.inputs if a.name in fixed_inputs for s in a.all_symbols())
    if not params:
        raise ValueError(f"{spec.name}: a prepared function needs a params input")
    fixed: set[sp.Symbol] = set(params)  # parameter symbols and parameter-only temporaries
    known: dict[sp.Expr, sp.Symbol] = {}  # parameter-only expression -> its temporary
    order: list[tuple[sp.Symbol, sp.Expr, bool]] = []  # (temp, expr, parameter-only)
    fresh = (sp.Symbol(f"_prep{i}") for i in range(10**9))

    def is_fixed(e: sp.Basic) -> bool:
        free = e.free_symbols
        return bool(free) and free <= fixed

    def hoist(e: sp.Expr) -> sp.Expr:
        if e.is_Atom:
            return e
        if e not in known:
            sym = next(fresh)
            known[e] = sym
            fixed.add(sym)
            order.append((sym, e, True))
        return known[e]

    def visit(e: sp.Basic) -> sp.Basic:
        if e.is_Atom:
            return e
        if is_fixed(e):
            return hoist(e)
        if not isinstance(e, (sp.Mul, sp.Add)):
            return e.func(*(visit(a) for a in e.args))
        group = [a for a in e.args if is_fixed(a)]
        rest = [visit(a) for a in e.args if not is_fixed(a)]
        if group:
            numbers = [a for a in rest if a.is_Number]
            if isinstance(e, sp.Mul):
                numbers = [a for a in numbers if a not in (sp.S.One, sp.S.NegativeOne)]
            group += numbers
            rest = [a for a in rest if a not in numbers]
            rest.append(hoist(e.func(*group)))
        return e.func(*rest)

    for sym, e in result.temps:
        if is_fixed(e):
            known.setdefault(e, sym)
            fixed.add(sym)
            order.append((sym, e, True))
        else:
            order.append((sym, visit(collect_factors(e)), False))

    n_out = len(spec.outputs)
    guard_exprs = result.outputs[n_out][0:] if spec.guards else ()
    param_guards: list[tuple[int, sp.Expr]] = []
    state_guards: list[tuple[int, sp.Expr]] = []
    for k, g in enumerate(guard_exprs):
        if g.is_Number or is_fixed(g):
            param_guards.append((k, g))
        else:
            state_guards.append((k, visit(collect_factors(g))))
    outputs = tuple(tuple(visit(collect_factors(e)) for e in exprs)
                    for exprs in result.outputs[:n_out])

    # Liveness: what the per-call part reads, then what prepare needs for that and its
    # guards (backwards over the temporaries).
    def reads(exprs: list[sp.Basic]) -> set[sp.Basic]:
        out: set[sp.Basic] = set()
        for e in exprs:
            out |= e.free_symbols
        return out

    per_call = reads([e for s, e, p in order if not p] + [g for _, g in state_guards]
                     + [e for exprs in outputs for e in exprs])
    kept_set = {s for s in per_call if s in fixed}
    live = kept_set | reads([g for _, g in param_guards])
    param_seq: list[Temp] = []
    for sym, e, p in reversed(order):
        if p and sym in live:
            param_seq.append((sym, e))
            live |= e.free_symbols
    param_seq.reverse()
    state_seq = [(s, e) for s, e, p in order if not p]

    # Final names in evaluation order: parameter part, then per-call part.
    taken = {str(s) for s in spec.input_symbols()}
    names = _temp_names(taken)
    rename = {s: sp.Symbol(next(names)) for s, _ in (*param_seq, *state_seq)}

    def ren(e: sp.Expr) -> sp.Expr:
        return e.xreplace(rename)

    param_temps = tuple((rename[s], ren(e)) for s, e in param_seq)
    slot_order = {s: i for i, s in enumerate(spec.input_symbols())}
    kept_inputs = sorted((s for s in kept_set if s in params), key=slot_order.__getitem__)
    kept_temps = [rename[s] for s, _ in param_seq if s in kept_set]
    return PreparedForm(
        spec=spec,
        params=params,
        param_temps=param_temps,
        param_guards=tuple((k, ren(g)) for k, g in param_guards),
        kept=(*kept_inputs, *kept_temps),
        state_temps=tuple((rename[s], ren(e)) for s, e in state_seq),
        state_guards=tuple((k, ren(g)) for k, g in state_guards),
        outputs=tuple(tuple(ren(e) for e in exprs) for exprs in outputs),
    )
