"""Quantities a module's functions have in common, evaluated by one helper (issue 51).

A staged robot's model functions (``codegen.robot_functions.model_specs``) each read the
same staged quantities (``modeling.staged``): S(q), M̄ = SᵀMS and H̄ = Sᵀ(MṠη + H) of (9)
are defined once in the stage, but every function printed them again, so a five-cart
train's ``<prefix>_model.c`` held its S(q) and M̄ about four times. Functions whose specs
name the same group (``FunctionSpec.shares``) instead call one helper that evaluates the
definitions they all read, the rest of each function reading its results.

What is shared is decided here, language-independently: the helper's spec and CSE, and
each user's own CSE with the shared quantities as inputs. A backend may print the call
(C: a static function of the module) or ignore it (``FunctionIR.cse`` stays the whole
function: the Python and CasADi backends, and the op counts, are those of one call).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import sympy as sp

from codegen.cse import CseResult, cse_function
from codegen.spec import Argument, FunctionSpec

SHARED_ARG = "shared_quantities"  # the helper's output, and the users' extra input


@dataclass(frozen=True, eq=False)
class SharedQuantities:
    """One group's helper: ``spec`` (inputs: the users' common leading inputs; output
    ``shared_quantities``, the shared definitions' symbols in order) and its ``cse``."""

    spec: FunctionSpec
    cse: CseResult
    symbols: tuple[sp.Symbol, ...]


@dataclass(frozen=True, eq=False)
class SharedCall:
    """A user of ``quantities``: its own CSE (``cse``, of ``spec.checked_spec()`` without
    the shared definitions, which it reads as the input ``shared_quantities``)."""

    quantities: SharedQuantities
    cse: CseResult


def common_definitions(specs: Sequence[FunctionSpec]) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
    """The definitions every spec of ``specs`` has (the same symbol and expression), in the
    first spec's order (each after those it reads: a subset closed under reading, as
    every definition a shared one reads is shared too)."""
    first, *rest = specs
    others = [dict(s.definitions) for s in rest]
    common = tuple((sym, e) for sym, e in first.definitions
                   if all(o.get(sym) == e for o in others))
    defined = {sym for sym, _ in common}
    everyone = {sym for sym, _ in first.definitions}
    for sym, e in common:  # closed: a shared quantity reads only shared ones and inputs
        if (e.free_symbols & everyone) - defined:
            raise ValueError(f"shared quantity {sym} reads a quantity not shared")
    return common


def shared_inputs(specs: Sequence[FunctionSpec]) -> tuple[Argument, ...]:
    """The leading inputs every spec of ``specs`` has alike (same name, kind, symbols):
    what the helper takes, passed through by each caller."""
    common: list[Argument] = []
    for args in zip(*(s.inputs for s in specs), strict=False):
        if any(a != args[0] for a in args[1:]):
            break
        common.append(args[0])
    return tuple(common)


def share(specs: Sequence[FunctionSpec], name: str) -> tuple[SharedQuantities,
                                                             tuple[SharedCall, ...]]:
    """The helper ``name`` of the group ``specs`` and each spec's call of it.

    ValueError when they have no definition in common or the shared definitions read an
    input that is not among their common leading inputs."""
    if len(specs) < 2:
        raise ValueError(f"{name}: a shared group needs two functions or more")
    common = common_definitions(specs)
    if not common:
        raise ValueError(f"{name}: {[s.name for s in specs]} share no quantity")
    inputs = shared_inputs(specs)
    known = {s for a in inputs for s in a.all_symbols()} | {sym for sym, _ in common}
    for sym, e in common:
        if e.free_symbols - known:
            raise ValueError(f"{name}: shared quantity {sym} reads an input the functions "
                             "do not all take first")
    symbols = tuple(sym for sym, _ in common)
    helper = FunctionSpec(
        name, "The quantities " + ", ".join(s.name for s in specs) + " all read.",
        inputs, (Argument(SHARED_ARG, "array", shape=(len(symbols), 1), exprs=symbols),),
        definitions=common)
    quantities = SharedQuantities(helper, cse_function(helper, reciprocals=True), symbols)
    shared = Argument(SHARED_ARG, "array", shape=(len(symbols), 1), symbols=symbols)
    calls = []
    for spec in specs:
        if SHARED_ARG in {a.name for a in (*spec.inputs, *spec.outputs)}:
            raise ValueError(f"{spec.name}: an argument is named {SHARED_ARG}")
        own = tuple((sym, e) for sym, e in spec.definitions if sym not in set(symbols))
        rest = replace(spec, inputs=(*spec.inputs, shared), definitions=own, prepared=False)
        calls.append(SharedCall(quantities, cse_function(rest.checked_spec(),
                                                         reciprocals=True)))
    return quantities, tuple(calls)
