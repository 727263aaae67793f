"""Lowering: a function's shared form (:class:`~codegen.backend.FunctionIR`) as C99
statements, the job of this module alone (which files hold them is :mod:`.files`'s).

Layout in C (all row-major, the same flattening as every other backend):

* ``"array"`` input: ``const wmr_real_t *name`` pointing at ``WMR_<FN>_<NAME>_SIZE``
  scalars; output: ``wmr_real_t *name``. A matrix is flat row-major: ``M[r*cols + c]``
  (``_ROWS``/``_COLS`` macros are emitted for matrices).
* ``"params"`` input: ``const wmr_params_t *name`` (or ``Argument.ctype``).
* ``"struct"`` input ``const <ctype> *name``, output ``<ctype> *name``; the struct types
  themselves are the types header's (:mod:`.files`).

Functions read every used input into a ``const`` local before the first output is written,
so outputs may alias inputs (in-place state updates are safe): a function that checks its
inputs reads them all first; the others read each just before its first use
(:class:`LazyLoads`). Then CSE temporaries, then the stores.

Each function's context (what ``module.c.jinja`` and ``step_kernels.c.jinja`` spell) also
says which ``<prefix>norm<n>`` its printer wrote (``"norms"``): the types header defines
those, and nothing reads the C back to find them.
"""

from __future__ import annotations

import keyword
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.config import CConfig
from codegen.backends.c.deferred import is_input_call, late_inputs
from codegen.backends.c.printer import CPrinter
from codegen.cse import op_count_from
from codegen.layout import (
    InputSlot,
    argument_size,
    input_slots,
    is_scalar,
    is_vector,
    local_names,
    split_fields,
)
from codegen.shared import SharedCall
from codegen.spec import Argument, Field, FunctionSpec

_C_KEYWORD_TEXT = (
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary"
)
C_KEYWORDS = frozenset(_C_KEYWORD_TEXT.split())
# Everything <math.h> may declare: a local with one of these names would trip -Wshadow.
_MATH_H_TEXT = (
    "acos acosh asin asinh atan atan2 atanh cbrt ceil copysign cos cosh erf erfc exp exp2 "
    "expm1 fabs fdim floor fma fmax fmin fmod frexp hypot ilogb ldexp lgamma llrint llround "
    "log log10 log1p log2 logb lrint lround modf nan nearbyint nextafter nexttoward pow "
    "remainder remquo rint round scalbln scalbn signbit sin sinh sqrt tan tanh tgamma trunc "
    "isfinite isinf isnan isnormal fpclassify isgreater isless j0 j1 jn y0 y1 yn gamma "
    "signgam errno math_errhandling float_t double_t HUGE_VAL INFINITY NAN"
)
_MATH_H_NAMES = frozenset(_MATH_H_TEXT.split())


def _usable_c_name(name: str) -> bool:
    return (
        name.isidentifier()
        and name.isascii()
        and name not in C_KEYWORDS
        and name not in _MATH_H_NAMES
        and not keyword.iskeyword(name)
        and not name.startswith(("_", "wmr_", "WMR_"))
        and not name.endswith("_t")  # POSIX reserves *_t
    )


# Macros of C99's <complex.h>: a firmware that includes it beside our headers would see a


def struct_ctype(arg: Argument, config: CConfig) -> str:
    ctype = arg.ctype or (config.params_ctype if arg.kind == "params" else "")
    if not ctype.startswith(config.prefix):
        raise ValueError(f"struct type {ctype!r} of {arg.name!r} must start with {config.prefix}")
    return ctype


def comment_text(text: str) -> str:
    return text.replace("*/", "* /")


def size_macros(spec: FunctionSpec, config: CConfig) -> list[tuple[str, int]]:
    macros: list[tuple[str, int]] = []
    for arg in (*spec.inputs, *spec.outputs):
        if arg.kind != "array":
            continue
        stem = f"{config.macro_prefix}{spec.name.upper()}_{arg.name.upper()}"
        macros.append((f"{stem}_SIZE", argument_size(arg)))
        if not is_scalar(arg.shape) and not is_vector(arg.shape):
            macros += [(f"{stem}_ROWS", arg.shape[0]), (f"{stem}_COLS", arg.shape[1])]
    names = [m for m, _ in macros]
    if len(set(names)) != len(names):
        raise ValueError(f"{spec.name}: argument names collide in size macros: {names}")
    return macros


def param_decl(arg: Argument, is_input: bool, config: CConfig) -> str:
    const = "const " if is_input else ""
    ctype = config.real_type if arg.kind == "array" else struct_ctype(arg, config)
    return f"{const}{ctype} *{arg.name}"


def param_doc(arg: Argument, is_input: bool, config: CConfig, spec: FunctionSpec) -> str:
    direction = "[in] " if is_input else "[out]"
    if arg.kind == "array":
        r, c = arg.shape
        macro = f"{config.macro_prefix}{spec.name.upper()}_{arg.name.upper()}_SIZE"
        layout = f"[{r * c}]" if is_vector(arg.shape) or is_scalar(arg.shape) else f"[{r}x{c}]"
        what = f"{layout} row-major ({macro})"
        if is_input:
            what += ": " + ", ".join(str(s) for s in arg.symbols)
    else:
        what = struct_ctype(arg, config)
    doc = f" -- {arg.doc}" if arg.doc else ""
    return comment_text(f"@param{direction} {arg.name} {what}{doc}")


def access(arg: Argument, f: Field | None, index: int) -> str:
    """C lvalue/rvalue of element ``index`` (row-major) of an array or struct field."""
    if f is None:
        return f"{arg.name}[{index}]"
    base = f"{arg.name}->{f.c_field}"
    if is_scalar(f.shape):
        return base
    if is_vector(f.shape):
        return f"{base}[{index}]"
    return f"{base}[{index // f.shape[1]}][{index % f.shape[1]}]"


Temp = tuple[sp.Symbol, sp.Expr]
PREPARED_ARG = "prepared"  # the prepared struct's argument name in _prepare and _prepared


@dataclass(frozen=True)
class Line:
    """One statement of a generated function's body (``module.c.jinja`` spells it)."""

    kind: str  # "void" (an unused argument), "decl" (a const local), "check", "store"
    target: str = ""  # void: the argument; decl: the local; store: the lvalue
    value: str = ""  # decl, store: the value; check: the condition that fails
    status: str = ""  # check: what it returns
    doc: str = ""  # check: its comment
    inner: str = ""  # check: a condition that, when the check fails, returns inner_status
    inner_status: str = ""
    inner_doc: str = ""
    # decl of a function calling its group's helper (``codegen.shared``): ``hidden``, a
    # helper's temporary, evaluated in the helper; ``printed``, what the decl reads instead
    # of ``value`` (the helper's result). ``value`` is always the arithmetic the line
    # stands for: the body is the straight-line evaluation a call executes (the float32
    # certifier reads it so), the template prints the call.
    # (Out of the repr, which the certificate's hash reads: they change where a value is
    # printed, not the value; a function without a helper hashes as it always did.)
    hidden: bool = field(default=False, repr=False)
    printed: str = field(default="", repr=False)


def decl(name: str, value: str) -> Line:
    return Line("decl", name, value)


def nonfinite_check(names: Sequence[str], status: str, config: CConfig) -> list[Line]:
    return ([Line("check", value=any_nonfinite(names, config), status=status)]
            if names and status else [])


def c_local_names(spec: FunctionSpec, slots: Sequence[InputSlot]) -> dict[sp.Symbol, str]:
    reserved = {a.name for a in (*spec.inputs, *spec.outputs)}
    if spec.prepared:
        reserved.add(PREPARED_ARG)
    return local_names(slots, reserved, _usable_c_name)


def printer_for(names: Mapping[sp.Symbol, str], temps: Sequence[Temp], config: CConfig,
             spec: FunctionSpec) -> CPrinter:
    printer_names = dict(names)
    printer_names.update({s: str(s) for s, _ in temps})
    return CPrinter(config, printer_names, spec.bounded_trig)


def guard_lines(
    spec: FunctionSpec, guards: Sequence[tuple[int, sp.Expr]], printer: CPrinter,
    config: CConfig,
) -> list[Line]:
    """``if (!(condition > 0)) return status;`` per guard (index into spec.guards)."""
    return [
        Line("check", value=f"!({printer.expr_code(e)} > {config.literal_macro}(0.0))",
              status=spec.guards[k].status, doc=comment_text(spec.guards[k].doc))
        for k, e in guards
    ]


def output_stores(
    spec: FunctionSpec, outputs: Sequence[Sequence[sp.Expr]], printer: CPrinter, config: CConfig
) -> list[tuple[str, str]]:
    stores: list[tuple[str, str]] = []
    for arg, exprs in zip(spec.outputs, outputs, strict=True):
        if arg.kind == "array":
            stores += [
                (access(arg, None, i), printer.expr_code(e)) for i, e in enumerate(exprs)
            ]
        else:
            for f, chunk in split_fields(arg, exprs):
                stores += [
                    (access(arg, f, i), printer.expr_code(e))
                    for i, e in enumerate(chunk)
                ]
    return stores


def commit(
    spec: FunctionSpec, stores: list[tuple[str, str]], config: CConfig,
    late_inputs: Sequence[str] = (), late_doc: str = "", summed: bool = False,
    late_test: str = "",
) -> list[Line]:
    """The stores; for a checked function, into locals first, the finite-output check,
    then the stores: no output written on error. ``late_inputs`` are inputs not checked
    yet, whose non-finite values are known to make a result non-finite: checked only when
    a result is not finite, for the input status (``late_doc`` says why that is enough;
    ``late_test``, the condition that tests them, if not theirs inline).
    ``summed``: the check tests the results' sum first (:func:`summed_nonfinite`)."""
    if not (spec.returns_status and spec.nonfinite_output):
        return [Line("store", target, value) for target, value in stores]
    results = [f"r_{k}" for k in range(len(stores))]
    check = nonfinite_check(results, spec.nonfinite_output, config)
    if summed and len(results) > 2:
        check = [replace(line, value=summed_nonfinite(results, config)) for line in check]
    check = with_late_check(check, late_inputs, spec.nonfinite_input, config, late_doc,
                            late_test)
    return [
        *(decl(r, value) for r, (_, value) in zip(results, stores, strict=True)),
        *check,
        *(Line("store", target, r) for r, (target, _) in zip(results, stores, strict=True)),
    ]


def unread_doc(
    slots: Sequence[InputSlot], used: frozenset[sp.Symbol], config: CConfig, what: str
) -> list[str]:
    """The ``@return`` lines of the non-finite input check over ``slots``."""
    line = f"if {what} it reads is NaN or infinite"
    unread = [access(s.arg, s.field, s.index).replace("->", ".")
              for s in slots if s.symbol not in used]
    if unread:
        return [line, f"(it does not read, and ignores: {', '.join(unread)}),"]
    return [line + (" (it reads every input)," if what == "an input" else ",")]


class LazyLoads:
    """Each input read into its ``const`` local just before the first expression that uses
    it, instead of all at the top: a law reading 50 inputs then holds only those its next
    temporaries need (on the Cortex-M4 the TDROC law's frame fell from 216 B to about
    100 B: every input was live at once and spilled). :meth:`rest` reads the ones left
    before the first store, so that outputs may still alias inputs."""

    def __init__(self, loads: Mapping[sp.Symbol, Line]) -> None:
        self._pending = dict(loads)

    def __call__(self, exprs: Sequence[sp.Basic]) -> list[Line]:
        need = {s for e in exprs for s in e.free_symbols}
        lines = [line for s, line in self._pending.items() if s in need]
        self._pending = {s: line for s, line in self._pending.items() if s not in need}
        return lines

    def rest(self) -> list[Line]:
        lines = list(self._pending.values())
        self._pending = {}
        return lines


def temp_lines(temps: Sequence[Temp], load_for: LazyLoads, printer: CPrinter) -> list[Line]:
    """Each temporary's declaration, after the reads of the inputs it is the first to use."""
    lines: list[Line] = []
    for s, e in temps:
        lines += load_for([e])
        lines.append(decl(str(s), printer.expr_code(e)))
    return lines


# Why a function's late inputs (:mod:`.deferred`) may wait for a failed check.
LATE_DOC = "an input not checked yet, reaching a result through +, -, *, sin, cos only"
SHARED_LOCAL = "_shared"  # a caller's array of its group's helper results


def shared_temps(call: SharedCall) -> tuple[list[Temp], list[Temp]]:
    """The helper's temporaries (renamed ``_h<k>``, apart from the caller's ``_t<k>``) and
    its results (shared symbol, value), as the caller's evaluation holds them."""
    helper = call.quantities
    rename = {t: sp.Symbol(f"_h{k}") for k, (t, _) in enumerate(helper.cse.temps)}
    temps = [(rename[t], e.xreplace(rename)) for t, e in helper.cse.temps]
    results = [e.xreplace(rename) for e in helper.cse.outputs[0]]
    return temps, list(zip(helper.symbols, results, strict=True))


def shared_lines(call: SharedCall, temps: Sequence[Temp], results: Sequence[Temp],
                 printer: CPrinter, reads: set[sp.Symbol], config: CConfig) -> list[Line]:
    """The call of ``call``'s helper as lines (``Line.printed``, ``Line.hidden``): the
    call, then the helper's temporaries (hidden: evaluated in the helper) and its results,
    each read from the caller's array where the rest of the function reads it
    (``reads``), hidden elsewhere."""
    helper = call.quantities
    args = ", ".join([*(a.name for a in helper.spec.inputs), SHARED_LOCAL])
    lines = [Line("call", f"{SHARED_LOCAL}[{len(results)}]",
                  f"{config.prefix}{helper.spec.name}({args})")]
    lines += [Line("decl", str(t), printer.expr_code(e), hidden=True) for t, e in temps]
    lines += [Line("decl", str(q), printer.expr_code(e), hidden=q not in reads,
                   printed=f"{SHARED_LOCAL}[{k}]") for k, (q, e) in enumerate(results)]
    return lines


def function_context(ir: FunctionIR, config: CConfig, module: str) -> dict[str, object]:
    spec = ir.spec
    slots = input_slots(spec)
    names = c_local_names(spec, slots)
    form = ir.prepared
    n_out = len(spec.outputs)
    late_temps: Sequence[Temp] = ()
    late_guards: Sequence[tuple[int, sp.Expr]] = ()
    call = ir.shared if form is None else None
    if form is None:
        result = ir.cse if call is None else call.cse
        inputs = set(spec.input_symbols())
        used = frozenset(s for s in result.used_symbols() if s in inputs)
        temps: Sequence[Temp] = result.temps
        guard_values = result.outputs[n_out:]
        guards = list(enumerate(guard_values[0] if guard_values else ()))
        outputs = result.outputs[:n_out]
    else:  # the same evaluation as prepare + prepared: bit-identical results
        used = form.used_params() | form.used_state()
        temps, guards = form.param_temps, list(form.param_guards)
        late_temps, late_guards = form.state_temps, form.state_guards
        outputs = form.outputs
    if len(guards) + len(late_guards) != len(spec.guards):
        raise ValueError(f"{spec.name}: {len(spec.guards)} guards, conditions for "
                         f"{len(guards) + len(late_guards)}")
    checked = spec.returns_status and bool(spec.nonfinite_input)
    call_lines: list[Line] = []
    passed: set[str] = set()  # inputs handed to the helper
    check_only: set[sp.Symbol] = set()  # inputs the helper alone reads, loaded to be checked
    helper: tuple[list[Temp], list[Temp]] = ([], [])
    if call is not None:
        helper = shared_temps(call)
        passed = {a.name for a in call.quantities.spec.inputs}
        if checked:  # what the helper reads is checked with the rest of the inputs
            check_only = set(call.quantities.cse.used_symbols()) - used
            used = used | check_only
    printer = printer_for(names, (*helper[0], *helper[1], *temps, *late_temps), config, spec)
    if call is not None:
        reads = {s for _, e in temps for s in e.free_symbols}
        reads |= {s for exprs in result.outputs for e in exprs for s in e.free_symbols}
        call_lines = shared_lines(call, *helper, printer, reads, config)

    loads = {s.symbol: decl(names[s.symbol], access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used}
    body = [Line("void", a.name) for a in spec.inputs
            if not any(s in used for s in a.all_symbols()) and a.name not in passed]
    load_for = LazyLoads({} if checked else loads)
    late: frozenset[sp.Symbol] = frozenset()
    calls: list[Temp] = []
    # Late input checks where the function's speed is measured against CasADi's (the one
    # with a prepared twin, which defers its own): each failing check gets a copy of the
    # late test, code that the other checked functions (and trailer2's budget) do without.
    if checked and form is not None and spec.nonfinite_output and not spec.calls_prepared:
        late = late_inputs(used, (*temps, *late_temps), [e for ex in outputs for e in ex])
    if late:  # the library calls of inputs as soon as their inputs are read: then little
        # is held across their out-of-range branch (libm's sin and cos) but the pointers
        calls = [(t, e) for t, e in (*temps, *late_temps) if is_input_call(e, used)]
        temps = [te for te in temps if te not in calls]
        late_temps = [te for te in late_temps if te not in calls]
    late_names = [line.target for s, line in loads.items() if s in late]
    late_helper = late_check_helper(spec, [s for s in slots if s.symbol in late], names,
                                    config) if late else {}
    late_test = str(late_helper.get("call", ""))
    if checked:  # the check reads every input: all loaded first, in the inputs' order
        # (the float32 certificate's subdivision takes them in this order)
        read: set[sp.Symbol] = set()
        for s, line in loads.items():
            read.add(s)
            body.append(line)
            ready = [(t, e) for t, e in calls if e.free_symbols <= read]
            body += [decl(str(t), printer.expr_code(e)) for t, e in ready]
            calls = [te for te in calls if te not in ready]
        body += nonfinite_check([line.target for s, line in loads.items() if s not in late],
                                 spec.nonfinite_input, config)
        body += [Line("void", names[s]) for s in sorted(check_only, key=str)]
    if call is not None:  # what the helper reads, before its (hidden) arithmetic
        helper_reads = call.quantities.cse.used_symbols()
        body += load_for(sorted(helper_reads & used, key=str))
        body += [replace(decl(names[s.symbol], access(s.arg, s.field, s.index)), hidden=True)
                 for s in slots if s.symbol in helper_reads - used]
    body += call_lines
    body += temp_lines(temps, load_for, printer)
    body += load_for([e for _, e in guards])
    body += with_late_check(guard_lines(spec, guards, printer, config), late_names,
                            spec.nonfinite_input, config, LATE_DOC, late_test)
    body += temp_lines(late_temps, load_for, printer)
    body += load_for([e for _, e in late_guards])
    body += with_late_check(guard_lines(spec, late_guards, printer, config), late_names,
                            spec.nonfinite_input, config, LATE_DOC, late_test)
    body += load_for.rest()  # every read before the first store: outputs may alias inputs
    body += commit(spec, output_stores(spec, outputs, printer, config), config, late_names,
                   LATE_DOC, summed=bool(late), late_test=late_test)
    ops = op_count_from(printer.ops)

    name = f"{config.prefix}{spec.name}"
    params = [param_decl(a, True, config) for a in spec.inputs]
    params += [param_decl(a, False, config) for a in spec.outputs]
    doc = [comment_text(line.rstrip()) for line in spec.doc.strip().splitlines()] or [name]
    if spec.equations:
        doc += ["", "Paper equations: " + ", ".join(spec.equations) + "."]
    doc += [""]
    doc += [param_doc(a, True, config, spec) for a in spec.inputs]
    doc += [param_doc(a, False, config, spec) for a in spec.outputs]
    if spec.returns_status:
        ok = config.status_codes[0].name
        doc.append(f"@return {ok} on success; on error no output is written:")
        if spec.nonfinite_input:
            first, *rest = unread_doc(slots, used, config, "an input")
            doc.append(f"        {spec.nonfinite_input} {first}")
            doc += [f"        {line}" for line in rest]
        doc += [f"        {spec.guards[k].status} if not ({comment_text(spec.guards[k].doc)}),"
                for k, _ in (*guards, *late_guards)]
        if spec.nonfinite_output:
            doc.append(f"        {spec.nonfinite_output} if a result is not finite.")
    if form is not None:
        doc += ["", f"With fixed parameters, {module}_prepare once and {name}_prepared",
                "per call give the same results, bit for bit."]
    doc += ["", ops.comment()]
    return {
        "name": name,
        "return_type": config.status_type if spec.returns_status else "void",
        "params": params,
        "doc_lines": doc,
        "size_macros": size_macros(spec, config),
        "ops": ops.comment(),
        "norms": sorted(printer.norms),
        "body": body,
        "status_ok": config.status_codes[0].name if spec.returns_status else "",
        **({"late_helper": late_helper} if late_helper else {}),
    }


def with_late_check(lines: list[Line], late: Sequence[str], status: str,
                     config: CConfig, doc: str = "", test: str = "") -> list[Line]:
    """``lines`` (checks) that, failing, first return ``status`` if a late input is not
    finite (``doc``: why these inputs may wait; ``test``: the condition, if not
    :func:`any_nonfinite` of ``late``)."""
    if not late:
        return lines
    return [replace(line, inner=test or any_nonfinite(late, config), inner_status=status,
                    inner_doc=doc or "an input not checked yet, reaching the results "
                    "through +, -, * only")
            for line in lines]


def late_check_helper(spec: FunctionSpec, late: Sequence[InputSlot],
                      names: Mapping[sp.Symbol, str], config: CConfig) -> dict[str, object]:
    """The static helper that tests ``spec``'s late inputs (``"call"``: the condition its
    failing checks test, true when one is NaN or infinite): one copy of the test, read
    from the arguments, where each failing check would otherwise hold its own (inlined
    by gcc and clang but when optimising for size, as the shared helpers are: on the
    Cortex-M4, -Os, ``wmr_forward_dynamics`` took 844 B with five copies inline, 554 B
    and a helper of 142 B in float32)."""
    ok = config.status_codes[0].name
    args = [a for a in spec.inputs if any(s.arg is a for s in late)]
    name = f"{config.prefix}{spec.name}_late_inputs"
    loads = [decl(names[s.symbol], access(s.arg, s.field, s.index)) for s in late]
    return {
        "name": name,
        "summary": comment_text(f"{spec.nonfinite_input} if an input that "
                                f"{config.prefix}{spec.name} checks late is NaN or "
                                f"infinite, else {ok}."),
        "return_type": config.status_type,
        "params": [param_decl(a, True, config) for a in args],
        "ops": "",
        "norms": [],
        "body": [*loads, *nonfinite_check([line.target for line in loads],
                                          spec.nonfinite_input, config)],
        "status_ok": ok,
        "call": f"{name}({', '.join(a.name for a in args)}) != {ok}",
    }


def summed_nonfinite(names: Sequence[str], config: CConfig) -> str:
    """True when any of ``names`` is NaN or infinite, testing their sum first (a pairwise
    sum, whose depth is the log of the count): a NaN or infinite term makes the sum NaN or
    infinite, so a finite sum clears all of them with one test instead of one per value;
    a sum that is not finite (also when finite terms overflow it) leads to the test of
    each value (:func:`any_nonfinite`), which decides. On x86-64 (gcc -O2) it took 11 of
    ``wmr_forward_dynamics``'s instructions off the path that succeeds (callgrind)."""
    terms = list(names)
    while len(terms) > 1:
        pairs = [f"({a} + {b})" for a, b in zip(terms[::2], terms[1::2], strict=False)]
        terms = pairs + (terms[-1:] if len(terms) % 2 else [])
    total = terms[0][1:-1] if terms[0].startswith("(") else terms[0]
    return f"({any_nonfinite([total], config)}) && ({any_nonfinite(names, config)})"


def any_nonfinite(names: Sequence[str], config: CConfig) -> str:
    """One branch-free test that is true when any of ``names`` is NaN or infinite.

    Integer operations on the bits (``<prefix>exp_carry`` of the types header: the
    exponent field plus one, whose top bit is set exactly for NaN and ±Inf), OR-ed and
    tested once: the same answer as one ``isfinite`` per value, without a compare and
    branch per value, and on the integer units, which the arithmetic around it leaves idle
    (the former floating-point form, a balanced sum of ``x - x``, took two floating-point
    operations per value; with both of ``wmr_forward_dynamics``'s checks in bits it went
    from 22.9 to 21.0 ns on x86-64, gcc -O2). The cost is code size on a core whose
    integer and FP registers are apart: on the Cortex-M4 (-Os, float32) a value takes a
    move, AND, ADD and ORR, and ``wmr_forward_dynamics`` grew from 582 to 624 B.
    """
    carries = " | ".join(f"{config.prefix}exp_carry({n})" for n in names)
    return f"(({carries}) & {config.macro_prefix}EXP_CARRY_TOP) != 0u"  # MISRA 14.4


def context_norms(contexts: Iterable[Mapping[str, object]]) -> frozenset[int]:
    """The norm sizes the lowered functions ``contexts`` call (their ``"norms"``)."""
    found: set[int] = set()
    for ctx in contexts:
        norms = ctx["norms"]
        assert isinstance(norms, list)
        found.update(norms)
    return frozenset(found)
