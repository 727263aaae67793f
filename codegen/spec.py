"""What a generated function is, independent of the target language.

`modeling/` produces SymPy expressions; `codegen/` wraps each group of outputs that share
inputs into a :class:`FunctionSpec` and hands it to every backend (C, Python, CasADi).
Backends never do mathematics beyond common-subexpression elimination: every expression
here is final.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

import sympy as sp

ArgKind = Literal["params", "struct", "array"]


@dataclass(frozen=True)
class StatusCode:
    """One value of the ``<prefix>_status_t`` enum (the Python mirror names the same)."""

    name: str
    value: int
    doc: str


@dataclass(frozen=True)
class Field:
    """One named member of a struct argument: a scalar (shape (1, 1)) or a fixed array."""

    name: str
    symbols: tuple[sp.Symbol, ...]  # row-major
    shape: tuple[int, int] = (1, 1)
    doc: str = ""
    c_name: str = ""  # the C struct member where ``name`` cannot be one ("" = ``name``)

    @property
    def c_field(self) -> str:
        """The member's name in C: ``c_name``, else ``name`` (Python's key)."""
        return self.c_name or self.name


@dataclass(frozen=True)
class Argument:
    """An input or output of a generated function.

    kind
        ``"array"``: a flat row-major array of ``symbols`` (C ``const wmr_real_t *name`` for
        inputs, ``wmr_real_t *name`` for outputs; NumPy array in Python).
        ``"params"``: the robot's lumped parameters, C ``const wmr_params_t *name``,
        a mapping with keys ``field.name`` in Python.
        ``"struct"``: a named C struct ``ctype`` with ``fields``; a mapping / object with
        those attribute names in Python.
    For outputs, ``symbols`` is unused and ``exprs`` holds the expressions (row-major).
    """

    name: str
    kind: ArgKind
    shape: tuple[int, int] = (1, 1)
    symbols: tuple[sp.Symbol, ...] = ()
    exprs: tuple[sp.Expr, ...] = ()
    fields: tuple[Field, ...] = ()
    ctype: str = ""
    doc: str = ""

    def all_symbols(self) -> tuple[sp.Symbol, ...]:
        if self.kind == "array":
            return self.symbols
        return tuple(s for f in self.fields for s in f.symbols)


@dataclass(frozen=True)
class Guard:
    """A precondition of a status-returning function: ``condition > 0`` must hold, else the
    function returns ``status`` (C) / raises ``ValueError`` naming it (Python) and writes
    no output. ``condition`` is an expression of the inputs (CSE shares it with the outputs).
    """

    status: str
    condition: sp.Expr
    doc: str


@dataclass(frozen=True)
class FunctionSpec:
    """A pure function: outputs are expressions in the inputs' symbols and the
    ``definitions`` (intermediate quantities evaluated in order).

    ``name`` is the C name without the ``wmr_`` prefix (e.g. ``mass_matrix``) and the
    Python name. ``equations`` cites the paper, e.g. ``("(14)",)``.
    """

    name: str
    doc: str
    inputs: tuple[Argument, ...]
    outputs: tuple[Argument, ...]
    equations: tuple[str, ...] = ()
    returns_status: bool = False
    extra: dict[str, str] = field(default_factory=dict)
    # With ``returns_status``: non-finite inputs return ``nonfinite_input``, guards are
    # checked in order, and non-finite results return ``nonfinite_output``; on any error
    # no output is written.
    guards: tuple[Guard, ...] = ()
    nonfinite_input: str = ""
    nonfinite_output: str = ""
    # With ``returns_status``: the C backend also generates the prepare-parameters API,
    # ``<module>_prepare`` (parameter checks and parameter-only subexpressions, once) and
    # ``<name>_prepared`` (the per-call rest); see :mod:`codegen.prepare`.
    prepared: bool = False
    # Intermediate quantities (``modeling.staged``): each symbol defined by an expression of
    # the inputs and of earlier ones, evaluated in order; outputs and guards may read them.
    definitions: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()
    # A controller kernel: its angles are a step's validated inputs (|x| <= the steps' input
    # bound), so C evaluates sin and cos with the generated reduction alone
    # (``<P>_SIN_BOUNDED``), never libm's: no sinf/cosf and their argument reduction (about
    # 0.5 KB of stack) linked into a firmware image. NaN beyond the bound.
    bounded_trig: bool = False
    # The name of a group of a module's functions that evaluate the definitions they have
    # in common once, in one helper (``codegen.shared``; C: a static function of the
    # module). "" = none. The outputs are the same; only where they are printed differs.
    shares: str = ""
    # With ``prepared``: C prints the function as a call of its prepare-parameters pair
    # (the same arithmetic, bit for bit; written once in the module instead of twice).
    calls_prepared: bool = False

    def checked_spec(self) -> FunctionSpec:
        """This spec with the guard conditions as a trailing output ``guard_`` (for CSE)."""
        if not self.guards:
            return self
        guard_arg = Argument(
            "guard_", "array", shape=(len(self.guards), 1),
            exprs=tuple(g.condition for g in self.guards),
        )
        return replace(self, outputs=(*self.outputs, guard_arg))

    def input_symbols(self) -> tuple[sp.Symbol, ...]:
        return tuple(s for a in self.inputs for s in a.all_symbols())
