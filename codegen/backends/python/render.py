"""Render FunctionSpecs as one NumPy-only Python module ``<module>.py``.

Calling convention of a generated function ``name(...)``:

* arguments in the spec's input order, except that ``"params"`` arguments come last;
* ``"array"``: anything ``np.asarray`` accepts with the right number of elements,
  flattened row-major (a (3, 1) column may be passed as shape (3,), (3, 1) or a list);
* ``"params"`` and ``"struct"``: a mapping with the field names as keys, or any object with
  them as attributes (a dataclass, a cffi struct); array fields as for arrays;
* results: an ``"array"`` output of shape (R, C) with R, C > 1 is an (R, C) ndarray, any
  other array output (vector or (1, 1)) a 1-D ndarray; a ``"struct"`` output is a
  ``dict`` of field name -> float (scalar field) or ndarray (same rule). Several outputs
  are returned as a tuple in spec order.

Expressions are evaluated on Python floats with ``math`` (fast for scalars); where C would
return NaN/inf, Python raises (``math.sqrt`` of a negative, division by zero).
"""

from __future__ import annotations

import keyword
from collections.abc import Callable, Sequence
from pathlib import Path

import sympy as sp

from codegen import template_util
from codegen.backend import FunctionIR, function_ir
from codegen.backends.python.config import PythonConfig
from codegen.backends.python.printer import PyPrinter
from codegen.cse import op_count_from
from codegen.layout import (
    InputSlot,
    input_slots,
    is_scalar,
    is_vector,
    local_names,
    rows,
    split_fields,
)
from codegen.spec import Argument, FunctionSpec

TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"


def _usable(reserved: frozenset[str]) -> Callable[[str], bool]:
    def usable(name: str) -> bool:
        return (
            name.isidentifier()
            and name.isascii()
            and not keyword.iskeyword(name)
            and not name.startswith("_")
            and name not in reserved
        )

    return usable


def _value(
    shape: tuple[int, int], values: Sequence[str], scalar_as_float: bool
) -> dict[str, object]:
    """How one array or field is laid out: a float, a 1-D array or a 2-D array."""
    if scalar_as_float and is_scalar(shape):
        return {"kind": "scalar", "value": values[0]}
    if is_scalar(shape) or is_vector(shape):
        # Short vectors on one line, long ones one element per line.
        multiline = sum(len(v) + 2 for v in values) > 60
        return {"kind": "vector", "values": list(values), "multiline": multiline}
    return {"kind": "matrix", "rows": rows(values, shape)}


def _signature_order(spec: FunctionSpec) -> list[Argument]:
    return [a for a in spec.inputs if a.kind != "params"] + [
        a for a in spec.inputs if a.kind == "params"
    ]


def _loads(
    arg: Argument,
    slots: list[InputSlot],
    names: dict[sp.Symbol, str],
    used: frozenset[sp.Symbol],
) -> list[dict[str, object]]:
    """Statements reading ``arg`` into locals (only what is used)."""
    mine = [s for s in slots if s.arg is arg]
    if not any(s.symbol in used for s in mine):
        return [{"kind": "unused", "arg": arg.name}]
    if arg.kind == "array":
        targets = [names[s.symbol] if s.symbol in used else "_" for s in mine]
        return [
            {
                "kind": "flat",
                "targets": targets,
                "source": arg.name,
                "size": len(mine),
                "label": arg.name,
            }
        ]
    loads: list[dict[str, object]] = []
    for f in arg.fields:
        fslots = [s for s in mine if s.field is f]
        if not any(s.symbol in used for s in fslots):
            continue
        source = f'_field({arg.name}, "{f.name}")'
        if is_scalar(f.shape):
            loads.append({"kind": "scalar", "target": names[fslots[0].symbol], "source": source})
        else:
            targets = [names[s.symbol] if s.symbol in used else "_" for s in fslots]
            loads.append(
                {
                    "kind": "flat",
                    "targets": targets,
                    "source": source,
                    "size": len(fslots),
                    "label": f"{arg.name}.{f.name}",
                }
            )
    return loads


def _describe(arg: Argument) -> str:
    if arg.kind == "array":
        r, c = arg.shape
        text = f"array of {r * c} (shape {r}x{c}, row-major)"
        if arg.symbols:
            text += ": " + ", ".join(str(s) for s in arg.symbols)
    else:
        text = f"{arg.kind} with fields " + ", ".join(f.name for f in arg.fields)
    return text + (f". {arg.doc}" if arg.doc else "")


def _function_context(ir: FunctionIR, config: PythonConfig) -> dict[str, object]:
    spec, result = ir.spec, ir.cse
    slots = input_slots(spec)
    reserved = frozenset(config.reserved_names)
    arg_names = {a.name for a in (*spec.inputs, *spec.outputs)}
    if arg_names & reserved:
        raise ValueError(f"{spec.name}: argument names {sorted(arg_names & reserved)} are reserved")
    names = local_names(slots, arg_names | reserved, _usable(reserved))
    used = result.used_symbols()
    printer_names = dict(names)
    printer_names.update({s: str(s) for s, _ in result.temps})
    printer = PyPrinter(config, printer_names)

    args = _signature_order(spec)
    loads = [load for a in args for load in _loads(a, slots, names, used)]
    temps = [(str(s), printer.expr_code(e)) for s, e in result.temps]
    guard_values = result.outputs[len(spec.outputs):]
    guards = [
        (printer.expr_code(e), g.status, g.doc.replace('"', "'"))
        for g, e in zip(spec.guards, guard_values[0] if guard_values else (), strict=True)
    ]
    outputs: list[dict[str, object]] = []
    for arg, exprs in zip(spec.outputs, result.outputs[: len(spec.outputs)], strict=True):
        if arg.kind == "array":
            value = _value(arg.shape, [printer.expr_code(e) for e in exprs], False)
            outputs.append({"name": arg.name, "struct": False, "value": value})
        else:
            fields = [
                (f.name, _value(f.shape, [printer.expr_code(e) for e in chunk], True))
                for f, chunk in split_fields(arg, exprs)
            ]
            outputs.append({"name": arg.name, "struct": True, "fields": fields})
    ops = op_count_from(printer.ops)

    returns = ["dict[str, Any]" if o["struct"] else "NDArray[np.float64]" for o in outputs]
    doc = [line.rstrip() for line in spec.doc.strip().replace('"""', "'''").splitlines()]
    if spec.equations:
        doc += ["", "Paper equations: " + ", ".join(spec.equations) + "."]
    doc += ["", "Args:"] + [f"    {a.name}: {_describe(a)}" for a in args]
    doc += ["", "Returns:"] + [f"    {a.name}: {_describe(a)}" for a in spec.outputs]
    doc += ["", ops.comment()]
    return {
        "name": spec.name,
        "params": [f"{a.name}: {'ArrayLike' if a.kind == 'array' else 'Any'}" for a in args],
        "return_type": returns[0] if len(returns) == 1 else f"tuple[{', '.join(returns)}]",
        "doc_lines": doc,
        "loads": loads,
        "temps": temps,
        "outputs": outputs,
        "returns": [o["name"] for o in outputs],
        "guards": guards,
        "input_check": spec.returns_status and bool(spec.nonfinite_input),
        "nonfinite_input": spec.nonfinite_input,
        "input_names": [t for load in loads for t in _load_targets(load)],
        "nonfinite_output": spec.nonfinite_output if spec.returns_status else "",
    }


def _load_targets(load: dict[str, object]) -> list[str]:
    if load["kind"] == "scalar":
        return [str(load["target"])]
    if load["kind"] == "flat":
        return [str(t) for t in load["targets"] if t != "_"]  # type: ignore[attr-defined]
    return []


def render(
    specs: Sequence[FunctionSpec],
    module: str,
    config: PythonConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """``{"<module>.py": text}`` for ``specs``; ``source`` goes into the preamble."""
    return render_module([function_ir(s) for s in specs], module, config, source=source)


def render_module(
    functions: Sequence[FunctionIR],
    module: str,
    config: PythonConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """:func:`render` from the functions' shared form (no CSE here)."""
    config = config or PythonConfig()
    if not module.isidentifier():
        raise ValueError(f"module name {module!r} is not an identifier")
    names = [f.name for f in functions]
    if len(set(names)) != len(names):
        raise ValueError(f"{module}: duplicate function names {names}")
    bad = [n for n in names if n.startswith("_") or n in config.reserved_names]
    if bad:
        raise ValueError(f"{module}: function names {bad} clash with the module's own names")
    template = "module.py.jinja"
    text = template_util.render(
        TEMPLATE_DIR,
        template,
        preamble=template_util.preamble_lines(source, TEMPLATE_DIR, template),
        module=module,
        exports=sorted(names),
        functions=[_function_context(f, config) for f in functions],
    )
    return {module + ".py": text}
