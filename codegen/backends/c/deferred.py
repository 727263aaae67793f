"""Which inputs of a checked function may have their finiteness checked late: only when a
later check fails (a parameter guard, the finite-output check), before that check's status.

An input qualifies when one path from it to a result is +, -, *, positive integer powers,
sin and cos only (a divisor, a comparison or any other function may turn a NaN or an
infinity into a finite value: 1/inf is 0). Along such a path a NaN or infinite input keeps
every value NaN or infinite (IEEE 754: inf - inf and 0 * inf are NaN, sin(inf) is NaN),
whatever the other operands hold, so the result is not finite and the finite-output check
fails; that check's failure branch then tests the late inputs first and returns the input
status. A guard that fails tests them too, before its own status: the statuses and their
order are the function's (NONFINITE_INPUT, then the guards', then NONFINITE_OUTPUT), with
fewer tests on the path that succeeds. The printed C must be evaluated as written (no
-ffast-math, which the types header already refuses for the generated sin/cos).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp

from codegen.printer_base import FUNCTIONS

Temp = tuple[sp.Symbol, sp.Expr]


def is_input_call(e: sp.Expr, inputs: frozenset[sp.Symbol]) -> bool:
    """A math-library function of inputs only (``sin(theta)``; not fabs, printed inline)."""
    return (type(e) in FUNCTIONS and type(e) is not sp.Abs and bool(e.free_symbols)
            and e.free_symbols <= inputs)


def carried(e: sp.Basic) -> frozenset[sp.Basic]:
    """The symbols whose NaN or infinity ``e``'s value is sure to carry: those reached from
    the top of ``e`` through +, -, *, positive integer powers, sin and cos only (a
    quotient's numerator is a factor of a Mul; its divisor, a negative power, is not)."""
    if e.is_Symbol:
        return frozenset({e})
    if isinstance(e, (sp.Add, sp.Mul)):
        return frozenset().union(*(carried(a) for a in e.args))
    if isinstance(e, sp.Pow):
        return carried(e.base) if (e.exp.is_Integer and e.exp > 0) else frozenset()
    if isinstance(e, (sp.sin, sp.cos)):
        return carried(e.args[0])
    return frozenset()


def late_inputs(inputs: Iterable[sp.Symbol], temps: Sequence[Temp],
                results: Iterable[sp.Expr]) -> frozenset[sp.Symbol]:
    """The ``inputs`` that a NaN or infinity is sure to carry to one of ``results`` through
    the ``temps`` (in evaluation order): :func:`carried`, followed through temporaries."""
    reach: set[sp.Basic] = set()
    for e in results:
        reach |= carried(e)
    for t, e in reversed(temps):  # a temporary's value carries what it carries
        if t in reach:
            reach |= carried(e)
    return frozenset(s for s in inputs if s in reach)
