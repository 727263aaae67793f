"""Shape bookkeeping shared by all backends: sizes, field offsets and spec validation.

Every backend lays data out the same way: an argument is a flat row-major sequence of
scalars; a ``params``/``struct`` argument is its fields in declaration order, each field
row-major. For a ``struct`` *output*, ``Argument.exprs`` is that concatenation (the
fields' ``symbols`` are unused).
"""

from __future__ import annotations

import keyword
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import sympy as sp

from codegen.spec import Argument, Field, FunctionSpec

Shape = tuple[int, int]


def shape_size(shape: Shape) -> int:
    """Number of scalars in a (rows, cols) shape."""
    return shape[0] * shape[1]


def is_scalar(shape: Shape) -> bool:
    """True for shape (1, 1)."""
    return shape == (1, 1)


def is_vector(shape: Shape) -> bool:
    """True for (n, 1) and (1, n) with n > 1: printed as a 1-D array."""
    return not is_scalar(shape) and (shape[0] == 1 or shape[1] == 1)


def argument_size(arg: Argument) -> int:
    """Number of scalars in an argument (all fields for params/struct)."""
    if arg.kind == "array":
        return shape_size(arg.shape)
    return sum(shape_size(f.shape) for f in arg.fields)


def split_fields(arg: Argument, values: Sequence[sp.Expr]) -> list[tuple[Field, list[sp.Expr]]]:
    """Cut a flat sequence (struct output expressions) into per-field row-major chunks."""
    chunks: list[tuple[Field, list[sp.Expr]]] = []
    offset = 0
    for f in arg.fields:
        n = shape_size(f.shape)
        chunks.append((f, list(values[offset : offset + n])))
        offset += n
    return chunks


def rows(values: Sequence[str], shape: Shape) -> list[list[str]]:
    """Split row-major printed values into rows (for matrix layouts in templates)."""
    r, c = shape
    return [list(values[i * c : (i + 1) * c]) for i in range(r)]


def _check_identifier(name: str, what: str) -> None:
    if not name.isidentifier() or keyword.iskeyword(name):
        raise ValueError(f"{what} {name!r} is not a valid identifier")


def check_spec(spec: FunctionSpec) -> None:
    """Raise ``ValueError`` if a spec is inconsistent (sizes, names, free symbols)."""
    _check_identifier(spec.name, "function name")
    names = [a.name for a in (*spec.inputs, *spec.outputs)]
    if len(set(names)) != len(names):
        raise ValueError(f"{spec.name}: argument names are not unique: {names}")
    for arg in (*spec.inputs, *spec.outputs):
        _check_identifier(arg.name, f"{spec.name}: argument")
        if arg.kind not in ("array", "params", "struct"):
            raise ValueError(f"{spec.name}.{arg.name}: unknown kind {arg.kind!r}")
        if arg.kind != "array":
            if not arg.fields:
                raise ValueError(f"{spec.name}.{arg.name}: {arg.kind} argument without fields")
            fnames = [f.name for f in arg.fields]
            if len(set(fnames)) != len(fnames):
                raise ValueError(f"{spec.name}.{arg.name}: field names are not unique")
            for f in arg.fields:
                _check_identifier(f.name, f"{spec.name}.{arg.name}: field")
        if arg.kind == "struct" and not arg.ctype:
            raise ValueError(f"{spec.name}.{arg.name}: struct argument needs a ctype")
    for arg in spec.inputs:
        if arg.kind == "array" and len(arg.symbols) != shape_size(arg.shape):
            raise ValueError(f"{spec.name}.{arg.name}: {len(arg.symbols)} symbols for {arg.shape}")
        for f in arg.fields:
            if len(f.symbols) != shape_size(f.shape):
                raise ValueError(
                    f"{spec.name}.{arg.name}.{f.name}: {len(f.symbols)} symbols for {f.shape}"
                )
    inputs = spec.input_symbols()
    if len(set(inputs)) != len(inputs):
        raise ValueError(f"{spec.name}: an input symbol appears twice")
    known = set(inputs)
    for sym, e in spec.definitions:  # each from the inputs and earlier definitions
        if sym in known:
            raise ValueError(f"{spec.name}: definition {sym} shadows an input or definition")
        unknown = e.free_symbols - known
        if unknown:
            missing = ", ".join(sorted(str(s) for s in unknown))
            raise ValueError(f"{spec.name}: definition {sym} reads unknown symbols {missing}")
        known.add(sym)
    for arg in spec.outputs:
        if arg.kind == "params":
            raise ValueError(f"{spec.name}.{arg.name}: params cannot be an output")
        if len(arg.exprs) != argument_size(arg):
            raise ValueError(
                f"{spec.name}.{arg.name}: {len(arg.exprs)} expressions, expected "
                f"{argument_size(arg)}"
            )
        for e in arg.exprs:
            if not isinstance(e, sp.Expr):
                raise ValueError(f"{spec.name}.{arg.name}: {e!r} is not a SymPy expression")
            unknown = e.free_symbols - known
            if unknown:
                missing = ", ".join(sorted(str(s) for s in unknown))
                raise ValueError(f"{spec.name}.{arg.name}: unknown symbols {missing}")


@dataclass(frozen=True)
class InputSlot:
    """Where one input symbol lives: argument, field (None for arrays), row-major index
    inside that field or array, and position in the argument's flattened vector."""

    symbol: sp.Symbol
    arg: Argument
    field: Field | None
    index: int
    flat_index: int

    @property
    def shape(self) -> Shape:
        """Shape of the array or field holding the symbol."""
        return self.field.shape if self.field is not None else self.arg.shape


def input_slots(spec: FunctionSpec) -> list[InputSlot]:
    """Every input symbol with its location, in argument order."""
    slots: list[InputSlot] = []
    for arg in spec.inputs:
        if arg.kind == "array":
            slots += [InputSlot(s, arg, None, i, i) for i, s in enumerate(arg.symbols)]
            continue
        offset = 0
        for f in arg.fields:
            slots += [InputSlot(s, arg, f, i, offset + i) for i, s in enumerate(f.symbols)]
            offset += len(f.symbols)
    return slots


def local_names(
    slots: Iterable[InputSlot],
    reserved: Iterable[str],
    usable: Callable[[str], bool],
) -> dict[sp.Symbol, str]:
    """A local variable name for each input symbol: the symbol's own name when it is
    ``usable`` and free (readable code: ``theta``), else ``<arg>_<field>[_<i>]``.

    Names are chosen in slot order, so the result is deterministic.
    """
    taken = set(reserved)
    names: dict[sp.Symbol, str] = {}
    for slot in slots:
        candidates = [str(slot.symbol)]
        stem = slot.arg.name if slot.field is None else f"{slot.arg.name}_{slot.field.name}"
        candidates.append(stem if is_scalar(slot.shape) else f"{stem}_{slot.index}")
        chosen = next((c for c in candidates if usable(c) and c not in taken), None)
        n = 1
        while chosen is None:
            c = f"{candidates[-1]}_{n}"
            chosen = c if usable(c) and c not in taken else None
            n += 1
        taken.add(chosen)
        names[slot.symbol] = chosen
    return names
