"""The prepare-parameters API of a module with a ``prepared`` function
(:mod:`codegen.prepare` splits it): ``<module>_prepare``, which checks the parameters and
evaluates the parameter-only subexpressions once, and ``<name>_prepared``, the per-call
rest. This module lowers both to C statements (with :mod:`.lowering`'s pieces); the
module's files write them after the function itself.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.config import CConfig
from codegen.backends.c.lowering import (
    PREPARED_ARG,
    LazyLoads,
    Line,
    Temp,
    access,
    any_nonfinite,
    c_local_names,
    commit,
    decl,
    guard_lines,
    nonfinite_check,
    output_stores,
    param_decl,
    param_doc,
    printer_for,
    size_macros,
    temp_lines,
    unread_doc,
    with_late_check,
)
from codegen.cse import op_count_from
from codegen.layout import input_slots
from codegen.prepare import PreparedForm
from codegen.printer_base import FUNCTIONS


@dataclass(frozen=True)
class PreparedApi:
    """The prepare-parameters API of a module with a ``prepared`` function."""

    ctype: str  # <module>_prepared_t
    magic_macro: str  # <MODULE>_PREPARED_MAGIC
    magic: str
    field: str  # the struct's array of prepared values: the function's name
    size: int
    doc: str  # what the array holds
    prepare: str  # <module>_prepare
    function: str  # <prefix><name>


def prepared_magic(config: CConfig) -> str:
    """The prepared struct's magic word: the prefix's first three letters and ``P`` in
    ASCII (``0x574d5250``, "WMRP"); positive in a 32-bit ``long``."""
    return "0x" + (config.prefix.rstrip("_").upper()[:3] + "P").encode().hex()


def prepared_api(ir: FunctionIR, module: str, config: CConfig) -> PreparedApi:
    form = ir.prepared
    assert form is not None
    not_init = f"{config.macro_prefix}ERR_NOT_INITIALISED"
    if not_init not in {c.name for c in config.status_codes}:
        raise ValueError(f"{module}: a prepared function needs the status {not_init}")
    params = [str(s) for s in form.kept if s in form.params]
    n_temps = len(form.kept) - len(params)
    listed = ", ".join([*params, f"{n_temps} parameter-only subexpressions"] if n_temps
                       else params)
    return PreparedApi(
        ctype=f"{module}_prepared_t",
        magic_macro=f"{module.upper()}_PREPARED_MAGIC",
        magic=prepared_magic(config),
        field=ir.spec.name,
        size=len(form.kept),
        doc=f"{listed}, for {config.prefix}{ir.spec.name}_prepared",
        prepare=f"{module}_prepare",
        function=f"{config.prefix}{ir.spec.name}",
    )


def prepare_context(ir: FunctionIR, api: PreparedApi, config: CConfig) -> dict[str, object]:
    """``<module>_prepare(p, prepared)``: the parameter checks and parameter-only
    temporaries of the prepared function, stored with the magic word on success."""
    spec, form = ir.spec, ir.prepared
    assert form is not None
    slots = input_slots(spec)
    names = c_local_names(spec, slots)
    used = form.used_params()
    printer = printer_for(names, form.param_temps, config, spec)
    param_args = [a for a in spec.inputs if a.kind == "params"]
    param_slots = [s for s in slots if s.symbol in form.params]
    loads = [(names[s.symbol], access(s.arg, s.field, s.index))
             for s in param_slots if s.symbol in used]
    body = [decl(n, v) for n, v in loads]
    body += nonfinite_check([n for n, _ in loads], spec.nonfinite_input, config)
    body += [decl(str(s), printer.expr_code(e)) for s, e in form.param_temps]
    guards = guard_lines(spec, form.param_guards, printer, config)
    body += guards
    body.append(Line("store", f"{PREPARED_ARG}->magic", api.magic_macro))
    body += [Line("store", f"{PREPARED_ARG}->{api.field}[{k}]", names.get(s, str(s)))
             for k, s in enumerate(form.kept)]
    ops = op_count_from(printer.ops)
    ok = config.status_codes[0].name
    doc = [
        f"Checks the parameters of {api.function} and evaluates, once, every",
        "subexpression that depends on the parameters only; "
        f"{api.function}_prepared then does",
        "only the per-call rest. Call it again whenever the parameters change (a prepared",
        "struct keeps the values of the call that filled it).",
        "",
        *[param_doc(a, True, config, spec) for a in param_args],
        f"@param[out] {PREPARED_ARG} {api.ctype} -- written only on success",
        f"@return {ok} on success; on error *{PREPARED_ARG} is not written:",
    ]
    if spec.nonfinite_input:
        first, *rest = unread_doc(param_slots, used, config, "a parameter")
        doc.append(f"        {spec.nonfinite_input} {first}")
        doc += [f"        {line}" for line in rest]
    doc += [f"        {line.status} if not ({line.doc})," for line in guards]
    doc[-1] = doc[-1].removesuffix(",") + "."
    doc += ["", ops.comment()]
    return {
        "name": api.prepare,
        "return_type": config.status_type,
        "params": [*(param_decl(a, True, config) for a in param_args),
                   f"{api.ctype} *{PREPARED_ARG}"],
        "doc_lines": doc,
        "size_macros": [],
        "ops": ops.comment(),
        "norms": sorted(printer.norms),
        "body": body,
        "status_ok": ok,
    }


def _is_call(e: sp.Expr, inputs: frozenset[sp.Symbol]) -> bool:
    """A math-library function of inputs only (``sin(theta)``; not fabs, printed inline)."""
    return (type(e) in FUNCTIONS and type(e) is not sp.Abs and bool(e.free_symbols)
            and e.free_symbols <= inputs)


def _keeps_nonfinite(e: sp.Basic, tainted: set[sp.Basic]) -> bool:
    """True if every path from a ``tainted`` symbol to the value of ``e`` is +, -, * and
    positive integer powers: then a NaN or infinite tainted value makes ``e`` NaN or
    infinite (IEEE 754: inf - inf and 0 * inf are NaN), and no library function or
    divisor sees it. Subexpressions without a tainted symbol are leaves."""
    if not (e.free_symbols & tainted) or e.is_Symbol:
        return True
    if isinstance(e, (sp.Add, sp.Mul)):
        return all(_keeps_nonfinite(a, tainted) for a in e.args)
    if isinstance(e, sp.Pow):
        return (bool(e.exp.is_Integer and e.exp > 0)
                and _keeps_nonfinite(e.base, tainted))
    return False


@dataclass(frozen=True)
class _StateInputs:
    """How a prepared form's state inputs are checked (both C functions do the same).

    ``calls``: the math-library calls of inputs (``sin(theta)``), evaluated first;
    ``early``: the inputs they read, checked before them; ``late``: the other inputs read.
    ``lazy``: every late input reaches a result, and only through +, -, * and positive
    integer powers, so a non-finite one makes a result non-finite; the prepared function
    then checks them only when a later check fails (a per-call guard, the finite-output
    check), before that check's status: the same statuses, one check fewer when all is
    well. (Not in the function without prepare: its parameter guards come first, and
    checking the late inputs on their failure paths would load them before the library
    calls, to be held across them.)
    """

    calls: tuple[Temp, ...]
    early: frozenset[sp.Symbol]
    late: frozenset[sp.Symbol]
    lazy: bool


def _state_inputs(form: PreparedForm) -> _StateInputs:
    used = form.used_state()
    calls = tuple((s, e) for s, e in form.state_temps if _is_call(e, used))
    early = frozenset().union(*(e.free_symbols for _, e in calls)) if calls else used
    late = used - early
    tainted: set[sp.Basic] = set(late)  # the late inputs and what is computed from them
    for t, e in form.state_temps:
        if e.free_symbols & tainted:
            tainted.add(t)
    results = [e for exprs in form.outputs for e in exprs]
    reach: set[sp.Basic] = {v for e in results for v in e.free_symbols}
    for t, e in reversed(form.state_temps):  # what the results depend on
        if t in reach:
            reach |= e.free_symbols
    lazy = (bool(late) and bool(form.spec.nonfinite_output) and late <= reach
            and all(_keeps_nonfinite(e, tainted)
                    for e in [*(e for _, e in form.state_temps), *results]))
    return _StateInputs(calls, frozenset(early), frozenset(late), lazy)


def prepared_context(ir: FunctionIR, api: PreparedApi, config: CConfig) -> dict[str, object]:
    """``<name>_prepared(prepared, inputs..., outputs...)``: the per-call part, reading
    the prepared values instead of the parameters.

    Ordered for the call: the magic word; the inputs of the math-library calls of inputs
    (``sin(theta)``), their check and the calls; the other inputs and their check; then
    the rest, each prepared value read just before its first use (nothing is held across
    a library call that the call does not need). When the other inputs reach the results
    through +, -, * only, their check moves into the finite-output check's failure branch
    (see ``lazy``): the same statuses, one check fewer on the path that succeeds."""
    spec, form = ir.spec, ir.prepared
    assert form is not None
    slots = input_slots(spec)
    names = c_local_names(spec, slots)
    used = form.used_state()
    printer = printer_for(names, (*form.param_temps, *form.state_temps), config, spec)
    state_args = [a for a in spec.inputs if a.kind != "params"]
    state_slots = [s for s in slots if s.symbol not in form.params]
    not_init = f"{config.macro_prefix}ERR_NOT_INITIALISED"

    inputs = _state_inputs(form)
    calls = inputs.calls
    body = [Line("void", a.name) for a in state_args
            if not any(s in used for s in a.all_symbols())]
    body.append(Line("check", value=f"{PREPARED_ARG}->magic != {api.magic_macro}",
                      status=not_init))
    late_names: list[str] = []
    for part in (inputs.early, inputs.late):
        loads = [(names[s.symbol], access(s.arg, s.field, s.index))
                 for s in state_slots if s.symbol in part]
        body += [decl(n, v) for n, v in loads]
        if part is inputs.early or not inputs.lazy:
            body += nonfinite_check([n for n, _ in loads], spec.nonfinite_input, config)
        else:
            late_names = [n for n, _ in loads]
        if part is inputs.early:
            body += [decl(str(s), printer.expr_code(e)) for s, e in calls]
    load_for = LazyLoads({s: decl(names.get(s, str(s)), f"{PREPARED_ARG}->{api.field}[{k}]")
                           for k, s in enumerate(form.kept)})
    body += temp_lines([(s, e) for s, e in form.state_temps if (s, e) not in calls],
                        load_for, printer)
    body += load_for([g for _, g in form.state_guards])
    guards = guard_lines(spec, form.state_guards, printer, config)
    body += with_late_check(guards, late_names, spec.nonfinite_input, config)
    body += load_for([e for exprs in form.outputs for e in exprs])
    body += commit(spec, output_stores(spec, form.outputs, printer, config), config,
                    late_names)
    ops = op_count_from(printer.ops)

    name = f"{api.function}_prepared"
    own = replace(spec, name=f"{spec.name}_prepared", inputs=tuple(state_args))
    ok = config.status_codes[0].name
    doc = [
        f"{api.function} with the parameters prepared by {api.prepare}: the same",
        "results, bit for bit, and the same statuses, except that the checks of the",
        "parameters alone were made by the prepare call.",
        "",
        f"@param[in]  {PREPARED_ARG} {api.ctype} -- filled by {api.prepare}",
        *[param_doc(a, True, config, own) for a in state_args],
        *[param_doc(a, False, config, own) for a in spec.outputs],
        f"@return {ok} on success; on error no output is written:",
        f"        {not_init} if {PREPARED_ARG} was not filled by {api.prepare},",
    ]
    if spec.nonfinite_input:
        first, *rest = unread_doc(state_slots, used, config, "an input")
        doc.append(f"        {spec.nonfinite_input} {first}")
        doc += [f"        {line}" for line in rest]
    doc += [f"        {line.status} if not ({line.doc})," for line in guards]
    if spec.nonfinite_output:
        doc.append(f"        {spec.nonfinite_output} if a result is not finite.")
    doc += ["", ops.comment()]
    return {
        "name": name,
        "return_type": config.status_type,
        "params": [f"const {api.ctype} *{PREPARED_ARG}",
                   *(param_decl(a, True, config) for a in state_args),
                   *(param_decl(a, False, config) for a in spec.outputs)],
        "doc_lines": doc,
        "size_macros": size_macros(own, config),
        "ops": ops.comment(),
        "norms": sorted(printer.norms),
        "body": body,
        "status_ok": ok,
    }



def prepared_wrapper(ir: FunctionIR, api: PreparedApi, config: CConfig) -> list[str]:
    """The body of ``<name>`` as a call of its prepare-parameters pair (C statements; the
    function's own ``body`` stays its straight-line evaluation, which the pair's is, bit
    for bit): the state inputs' check first, so that the statuses come in the function's
    order (every input's non-finiteness before any guard), then ``<module>_prepare`` and
    ``<name>_prepared``. One copy of the arithmetic in the module where there were two."""
    spec, form = ir.spec, ir.prepared
    assert form is not None
    slots = input_slots(spec)
    names = c_local_names(spec, slots)
    used = form.used_state()
    status = "prepare_status"
    if status in names.values():
        raise ValueError(f"{spec.name}: an input's local is named {status}")
    loads = [(names[s.symbol], access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used and s.symbol not in form.params]
    lines = [f"const {config.real_type} {n} = {v};" for n, v in loads]
    if loads and spec.nonfinite_input:
        lines += [f"if ({any_nonfinite([n for n, _ in loads], config)}) {{",
                  f"    return {spec.nonfinite_input};", "}"]
    ok = config.status_codes[0].name
    state = [a.name for a in spec.inputs if a.kind != "params"]
    params = next(a.name for a in spec.inputs if a.kind == "params")
    call = ", ".join([f"&{PREPARED_ARG}", *state, *(a.name for a in spec.outputs)])
    return [*lines,
            f"{api.ctype} {PREPARED_ARG};",
            f"const {config.status_type} {status} = {api.prepare}({params}, &{PREPARED_ARG});",
            f"if ({status} != {ok}) {{",
            f"    return {status};",
            "}",
            f"return {api.function}_prepared({call});"]
