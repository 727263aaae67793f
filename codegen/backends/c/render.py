"""Render FunctionSpecs as C99: ``wmr_types.h`` (once) and ``<module>.h``/``<module>.c``.

Layout in C (all row-major, the same flattening as every other backend):

* ``"array"`` input: ``const wmr_real_t *name`` pointing at ``WMR_<FN>_<NAME>_SIZE``
  scalars; output: ``wmr_real_t *name``. A matrix is flat row-major: ``M[r*cols + c]``
  (``_ROWS``/``_COLS`` macros are emitted for matrices).
* ``"params"`` input: ``const wmr_params_t *name`` (or ``Argument.ctype``).
* ``"struct"`` input ``const <ctype> *name``, output ``<ctype> *name``. Struct fields are
  ``wmr_real_t f;`` for (1, 1), ``wmr_real_t f[N];`` for (N, 1)/(1, N) and
  ``wmr_real_t f[R][C];`` for matrices (C arrays are row-major, so ``&f[0][0]`` is the
  same flat row-major block as everywhere else).
* All struct types (params and struct arguments of every module) are defined once, in
  ``wmr_types.h``, rendered by :func:`render_types` from the specs of all modules.

Functions read every used input into a ``const`` local before the first output is written,
so outputs may alias inputs (in-place state updates are safe): a function that checks its
inputs reads them all first; the others read each just before its first use
(:class:`_LazyLoads`). Then CSE temporaries, then the stores.
"""

from __future__ import annotations

import hashlib
import keyword
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import sympy as sp

from codegen import template_util
from codegen.backend import FunctionIR, function_ir
from codegen.backends.c.config import CConfig
from codegen.backends.c.format import WIDTH, format_c
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
from codegen.prepare import PreparedForm, prepared_form
from codegen.printer_base import FUNCTIONS
from codegen.spec import Argument, Field, FunctionSpec

TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"

_C_KEYWORD_TEXT = (
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary"
)
_C_KEYWORDS = frozenset(_C_KEYWORD_TEXT.split())
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
        and name not in _C_KEYWORDS
        and name not in _MATH_H_NAMES
        and not keyword.iskeyword(name)
        and not name.startswith(("_", "wmr_", "WMR_"))
        and not name.endswith("_t")  # POSIX reserves *_t
    )


# Macros of C99's <complex.h>: a firmware that includes it beside our headers would see a
# field spelled so replaced (a parameter declares another C spelling, ParameterInfo.c_name).
_COMPLEX_H_NAMES = frozenset({"I", "complex", "imaginary"})


def _usable_field(name: str) -> bool:
    return (name.isidentifier() and name.isascii() and name not in _C_KEYWORDS
            and name not in _COMPLEX_H_NAMES)


@dataclass(frozen=True)
class _StructField:
    name: str
    dims: str  # "", "[3]" or "[2][2]"
    doc: str


@dataclass(frozen=True)
class _Struct:
    ctype: str
    doc: str
    fields: tuple[_StructField, ...]


def _dims(shape: tuple[int, int]) -> str:
    if is_scalar(shape):
        return ""
    if is_vector(shape):
        return f"[{shape[0] * shape[1]}]"
    return f"[{shape[0]}][{shape[1]}]"


def _ctype(arg: Argument, config: CConfig) -> str:
    ctype = arg.ctype or (config.params_ctype if arg.kind == "params" else "")
    if not ctype.startswith(config.prefix):
        raise ValueError(f"struct type {ctype!r} of {arg.name!r} must start with {config.prefix}")
    return ctype


def _field_doc(f: Field) -> str:
    return f.doc or ", ".join(str(s) for s in f.symbols)


def _structs(specs: Sequence[FunctionSpec], config: CConfig) -> list[_Struct]:
    """Struct types used by ``specs``: params types first, then others, each in order of
    first use; the same ctype must always have the same fields."""
    found: dict[str, _Struct] = {}
    args = [a for spec in specs for a in (*spec.inputs, *spec.outputs) if a.kind != "array"]
    args = [a for a in args if a.kind == "params"] + [a for a in args if a.kind == "struct"]
    for arg in args:
        ctype = _ctype(arg, config)
        bad = [f.name for f in arg.fields if not _usable_field(f.c_field)]
        if bad:
            raise ValueError(f"{ctype}: field names {bad} are not usable in C")
        struct = _Struct(
            ctype=ctype,
            doc=arg.doc,
            fields=tuple(
                _StructField(f.c_field, _dims(f.shape), _field_doc(f))
                for f in arg.fields
            ),
        )
        if ctype not in found:
            found[ctype] = struct
            continue
        old = found[ctype]
        if [(f.name, f.dims) for f in old.fields] != [(f.name, f.dims) for f in struct.fields]:
            raise ValueError(f"struct {ctype} is used with two different field lists")
        if not old.doc and struct.doc:
            found[ctype] = _Struct(ctype, struct.doc, old.fields)
    return list(found.values())


def _guard(name: str, config: CConfig) -> str:
    upper = name.upper().replace(".", "_")
    return upper if upper.startswith(config.macro_prefix) else config.macro_prefix + upper


def _comment_text(text: str) -> str:
    return text.replace("*/", "* /")


# fmax and fmin are printed as the WMR_FMAX/WMR_FMIN macros of wmr_types.h, not library calls
# (on a Cortex-M4, fmaxf is a call into newlib and __fpclassifyf; on x86-64 a libm call).
INLINE_MATH = ("fmax", "fmin")
# sin and cos in double are static inline functions of wmr_types.h (one argument reduction
# and two polynomials, shared by a sin and a cos of one angle), unless -DWMR_LIBM_TRIG:
# glibc's sincos is most of the forward dynamics' time. The same in float32 (libm's sinf/cosf
# beyond the bound): sinf and cosf were the float32 forward dynamics' excess over a
# hand-written one (1.08x -> 1.00x the trailer's).
GENERATED_TRIG = ("sin", "cos")
# Where the generated sin/cos are the generated reductions' (exact for |k| < 2^21: pi/2's
# first part has 31 significant bits, its second 32); twice the controller steps' input
# bound (controller_api.MAX_ABS_INPUT), so that a step's sincos_bounded never sees an
# argument beyond it: an input angle, or the difference of two (a trailer's yaw relative
# to the root's, ConstrainedSystem.root_frame_point).
TRIG_BOUND = "2.0e6"


def _size_macros(spec: FunctionSpec, config: CConfig) -> list[tuple[str, int]]:
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


def _param_decl(arg: Argument, is_input: bool, config: CConfig) -> str:
    const = "const " if is_input else ""
    ctype = config.real_type if arg.kind == "array" else _ctype(arg, config)
    return f"{const}{ctype} *{arg.name}"


def _param_doc(arg: Argument, is_input: bool, config: CConfig, spec: FunctionSpec) -> str:
    direction = "[in] " if is_input else "[out]"
    if arg.kind == "array":
        r, c = arg.shape
        macro = f"{config.macro_prefix}{spec.name.upper()}_{arg.name.upper()}_SIZE"
        layout = f"[{r * c}]" if is_vector(arg.shape) or is_scalar(arg.shape) else f"[{r}x{c}]"
        what = f"{layout} row-major ({macro})"
        if is_input:
            what += ": " + ", ".join(str(s) for s in arg.symbols)
    else:
        what = _ctype(arg, config)
    doc = f" -- {arg.doc}" if arg.doc else ""
    return _comment_text(f"@param{direction} {arg.name} {what}{doc}")


def _access(arg: Argument, f: Field | None, index: int) -> str:
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
class _Line:
    """One statement of a generated function's body (``module.c.jinja`` spells it)."""

    kind: str  # "void" (an unused argument), "decl" (a const local), "check", "store"
    target: str = ""  # void: the argument; decl: the local; store: the lvalue
    value: str = ""  # decl, store: the value; check: the condition that fails
    status: str = ""  # check: what it returns
    doc: str = ""  # check: its comment
    inner: str = ""  # check: a condition that, when the check fails, returns inner_status
    inner_status: str = ""
    inner_doc: str = ""


def _decl(name: str, value: str) -> _Line:
    return _Line("decl", name, value)


def _nonfinite_check(names: Sequence[str], status: str, config: CConfig) -> list[_Line]:
    return ([_Line("check", value=_any_nonfinite(names, config), status=status)]
            if names and status else [])


def _local_names(spec: FunctionSpec, slots: Sequence[InputSlot]) -> dict[sp.Symbol, str]:
    reserved = {a.name for a in (*spec.inputs, *spec.outputs)}
    if spec.prepared:
        reserved.add(PREPARED_ARG)
    return local_names(slots, reserved, _usable_c_name)


def _printer(names: Mapping[sp.Symbol, str], temps: Sequence[Temp], config: CConfig,
             spec: FunctionSpec) -> CPrinter:
    printer_names = dict(names)
    printer_names.update({s: str(s) for s, _ in temps})
    return CPrinter(config, printer_names, spec.bounded_trig)


def _guard_lines(
    spec: FunctionSpec, guards: Sequence[tuple[int, sp.Expr]], printer: CPrinter,
    config: CConfig,
) -> list[_Line]:
    """``if (!(condition > 0)) return status;`` per guard (index into spec.guards)."""
    return [
        _Line("check", value=f"!({printer.expr_code(e)} > {config.literal_macro}(0.0))",
              status=spec.guards[k].status, doc=_comment_text(spec.guards[k].doc))
        for k, e in guards
    ]


def _output_stores(
    spec: FunctionSpec, outputs: Sequence[Sequence[sp.Expr]], printer: CPrinter, config: CConfig
) -> list[tuple[str, str]]:
    stores: list[tuple[str, str]] = []
    for arg, exprs in zip(spec.outputs, outputs, strict=True):
        if arg.kind == "array":
            stores += [
                (_access(arg, None, i), printer.expr_code(e)) for i, e in enumerate(exprs)
            ]
        else:
            for f, chunk in split_fields(arg, exprs):
                stores += [
                    (_access(arg, f, i), printer.expr_code(e))
                    for i, e in enumerate(chunk)
                ]
    return stores


def _commit(
    spec: FunctionSpec, stores: list[tuple[str, str]], config: CConfig,
    late_inputs: Sequence[str] = (),
) -> list[_Line]:
    """The stores; for a checked function, into locals first, the finite-output check,
    then the stores: no output written on error. ``late_inputs`` are inputs not checked
    yet, whose non-finite values are known to make a result non-finite: checked only when
    a result is not finite, for the input status."""
    if not (spec.returns_status and spec.nonfinite_output):
        return [_Line("store", target, value) for target, value in stores]
    results = [f"r_{k}" for k in range(len(stores))]
    check = _with_late_check(_nonfinite_check(results, spec.nonfinite_output, config),
                             late_inputs, spec.nonfinite_input, config)
    return [
        *(_decl(r, value) for r, (_, value) in zip(results, stores, strict=True)),
        *check,
        *(_Line("store", target, r) for r, (target, _) in zip(results, stores, strict=True)),
    ]


def _unread_doc(
    slots: Sequence[InputSlot], used: frozenset[sp.Symbol], config: CConfig, what: str
) -> list[str]:
    """The ``@return`` lines of the non-finite input check over ``slots``."""
    line = f"if {what} it reads is NaN or infinite"
    unread = [_access(s.arg, s.field, s.index).replace("->", ".")
              for s in slots if s.symbol not in used]
    if unread:
        return [line, f"(it does not read, and ignores: {', '.join(unread)}),"]
    return [line + (" (it reads every input)," if what == "an input" else ",")]


class _LazyLoads:
    """Each input read into its ``const`` local just before the first expression that uses
    it, instead of all at the top: a law reading 50 inputs then holds only those its next
    temporaries need (on the Cortex-M4 the TDROC law's frame fell from 216 B to about
    100 B: every input was live at once and spilled). :meth:`rest` reads the ones left
    before the first store, so that outputs may still alias inputs."""

    def __init__(self, loads: Mapping[sp.Symbol, _Line]) -> None:
        self._pending = dict(loads)

    def __call__(self, exprs: Sequence[sp.Basic]) -> list[_Line]:
        need = {s for e in exprs for s in e.free_symbols}
        lines = [line for s, line in self._pending.items() if s in need]
        self._pending = {s: line for s, line in self._pending.items() if s not in need}
        return lines

    def rest(self) -> list[_Line]:
        lines = list(self._pending.values())
        self._pending = {}
        return lines


def _temp_lines(temps: Sequence[Temp], load_for: _LazyLoads, printer: CPrinter) -> list[_Line]:
    """Each temporary's declaration, after the reads of the inputs it is the first to use."""
    lines: list[_Line] = []
    for s, e in temps:
        lines += load_for([e])
        lines.append(_decl(str(s), printer.expr_code(e)))
    return lines


def _function_context(ir: FunctionIR, config: CConfig, module: str) -> dict[str, object]:
    spec = ir.spec
    slots = input_slots(spec)
    names = _local_names(spec, slots)
    form = ir.prepared
    n_out = len(spec.outputs)
    late_temps: Sequence[Temp] = ()
    late_guards: Sequence[tuple[int, sp.Expr]] = ()
    if form is None:
        used = ir.cse.used_symbols()
        temps: Sequence[Temp] = ir.cse.temps
        guard_values = ir.cse.outputs[n_out:]
        guards = list(enumerate(guard_values[0] if guard_values else ()))
        outputs = ir.cse.outputs[:n_out]
    else:  # the same evaluation as prepare + prepared: bit-identical results
        used = form.used_params() | form.used_state()
        temps, guards = form.param_temps, list(form.param_guards)
        late_temps, late_guards = form.state_temps, form.state_guards
        outputs = form.outputs
    if len(guards) + len(late_guards) != len(spec.guards):
        raise ValueError(f"{spec.name}: {len(spec.guards)} guards, conditions for "
                         f"{len(guards) + len(late_guards)}")
    printer = _printer(names, (*temps, *late_temps), config, spec)

    loads = {s.symbol: _decl(names[s.symbol], _access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used}
    body = [_Line("void", a.name) for a in spec.inputs
            if not any(s in used for s in a.all_symbols())]
    checked = spec.returns_status and bool(spec.nonfinite_input)
    load_for = _LazyLoads({} if checked else loads)
    if checked:  # the check reads every input: all loaded first
        body += loads.values()
        body += _nonfinite_check([line.target for line in loads.values()], spec.nonfinite_input,
                                 config)
    body += _temp_lines(temps, load_for, printer)
    body += load_for([e for _, e in guards])
    body += _guard_lines(spec, guards, printer, config)
    body += _temp_lines(late_temps, load_for, printer)
    body += load_for([e for _, e in late_guards])
    body += _guard_lines(spec, late_guards, printer, config)
    body += load_for.rest()  # every read before the first store: outputs may alias inputs
    body += _commit(spec, _output_stores(spec, outputs, printer, config), config)
    ops = op_count_from(printer.ops)

    name = f"{config.prefix}{spec.name}"
    params = [_param_decl(a, True, config) for a in spec.inputs]
    params += [_param_decl(a, False, config) for a in spec.outputs]
    doc = [_comment_text(line.rstrip()) for line in spec.doc.strip().splitlines()] or [name]
    if spec.equations:
        doc += ["", "Paper equations: " + ", ".join(spec.equations) + "."]
    doc += [""]
    doc += [_param_doc(a, True, config, spec) for a in spec.inputs]
    doc += [_param_doc(a, False, config, spec) for a in spec.outputs]
    if spec.returns_status:
        ok = config.status_codes[0].name
        doc.append(f"@return {ok} on success; on error no output is written:")
        if spec.nonfinite_input:
            first, *rest = _unread_doc(slots, used, config, "an input")
            doc.append(f"        {spec.nonfinite_input} {first}")
            doc += [f"        {line}" for line in rest]
        doc += [f"        {spec.guards[k].status} if not ({_comment_text(spec.guards[k].doc)}),"
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
        "size_macros": _size_macros(spec, config),
        "ops": ops.comment(),
        "body": body,
        "status_ok": config.status_codes[0].name if spec.returns_status else "",
    }


# ------------------------------------------------------------ prepare-parameters API


@dataclass(frozen=True)
class _Prepared:
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


def _prepared_api(ir: FunctionIR, module: str, config: CConfig) -> _Prepared:
    form = ir.prepared
    assert form is not None
    not_init = f"{config.macro_prefix}ERR_NOT_INITIALISED"
    if not_init not in {c.name for c in config.status_codes}:
        raise ValueError(f"{module}: a prepared function needs the status {not_init}")
    params = [str(s) for s in form.kept if s in form.params]
    n_temps = len(form.kept) - len(params)
    listed = ", ".join([*params, f"{n_temps} parameter-only subexpressions"] if n_temps
                       else params)
    return _Prepared(
        ctype=f"{module}_prepared_t",
        magic_macro=f"{module.upper()}_PREPARED_MAGIC",
        magic=prepared_magic(config),
        field=ir.spec.name,
        size=len(form.kept),
        doc=f"{listed}, for {config.prefix}{ir.spec.name}_prepared",
        prepare=f"{module}_prepare",
        function=f"{config.prefix}{ir.spec.name}",
    )


def _prepare_context(ir: FunctionIR, api: _Prepared, config: CConfig) -> dict[str, object]:
    """``<module>_prepare(p, prepared)``: the parameter checks and parameter-only
    temporaries of the prepared function, stored with the magic word on success."""
    spec, form = ir.spec, ir.prepared
    assert form is not None
    slots = input_slots(spec)
    names = _local_names(spec, slots)
    used = form.used_params()
    printer = _printer(names, form.param_temps, config, spec)
    param_args = [a for a in spec.inputs if a.kind == "params"]
    param_slots = [s for s in slots if s.symbol in form.params]
    loads = [(names[s.symbol], _access(s.arg, s.field, s.index))
             for s in param_slots if s.symbol in used]
    body = [_decl(n, v) for n, v in loads]
    body += _nonfinite_check([n for n, _ in loads], spec.nonfinite_input, config)
    body += [_decl(str(s), printer.expr_code(e)) for s, e in form.param_temps]
    guards = _guard_lines(spec, form.param_guards, printer, config)
    body += guards
    body.append(_Line("store", f"{PREPARED_ARG}->magic", api.magic_macro))
    body += [_Line("store", f"{PREPARED_ARG}->{api.field}[{k}]", names.get(s, str(s)))
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
        *[_param_doc(a, True, config, spec) for a in param_args],
        f"@param[out] {PREPARED_ARG} {api.ctype} -- written only on success",
        f"@return {ok} on success; on error *{PREPARED_ARG} is not written:",
    ]
    if spec.nonfinite_input:
        first, *rest = _unread_doc(param_slots, used, config, "a parameter")
        doc.append(f"        {spec.nonfinite_input} {first}")
        doc += [f"        {line}" for line in rest]
    doc += [f"        {line.status} if not ({line.doc})," for line in guards]
    doc[-1] = doc[-1].removesuffix(",") + "."
    doc += ["", ops.comment()]
    return {
        "name": api.prepare,
        "return_type": config.status_type,
        "params": [*(_param_decl(a, True, config) for a in param_args),
                   f"{api.ctype} *{PREPARED_ARG}"],
        "doc_lines": doc,
        "size_macros": [],
        "ops": ops.comment(),
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


def _with_late_check(lines: list[_Line], late: Sequence[str], status: str,
                     config: CConfig) -> list[_Line]:
    """``lines`` (checks) that, failing, first return ``status`` if a late input is not
    finite."""
    if not late:
        return lines
    return [replace(line, inner=_any_nonfinite(late, config), inner_status=status,
                    inner_doc="an input not checked yet, reaching the results through "
                    "+, -, * only")
            for line in lines]


def _prepared_context(ir: FunctionIR, api: _Prepared, config: CConfig) -> dict[str, object]:
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
    names = _local_names(spec, slots)
    used = form.used_state()
    printer = _printer(names, (*form.param_temps, *form.state_temps), config, spec)
    state_args = [a for a in spec.inputs if a.kind != "params"]
    state_slots = [s for s in slots if s.symbol not in form.params]
    not_init = f"{config.macro_prefix}ERR_NOT_INITIALISED"

    inputs = _state_inputs(form)
    calls = inputs.calls
    body = [_Line("void", a.name) for a in state_args
            if not any(s in used for s in a.all_symbols())]
    body.append(_Line("check", value=f"{PREPARED_ARG}->magic != {api.magic_macro}",
                      status=not_init))
    late_names: list[str] = []
    for part in (inputs.early, inputs.late):
        loads = [(names[s.symbol], _access(s.arg, s.field, s.index))
                 for s in state_slots if s.symbol in part]
        body += [_decl(n, v) for n, v in loads]
        if part is inputs.early or not inputs.lazy:
            body += _nonfinite_check([n for n, _ in loads], spec.nonfinite_input, config)
        else:
            late_names = [n for n, _ in loads]
        if part is inputs.early:
            body += [_decl(str(s), printer.expr_code(e)) for s, e in calls]
    load_for = _LazyLoads({s: _decl(names.get(s, str(s)), f"{PREPARED_ARG}->{api.field}[{k}]")
                           for k, s in enumerate(form.kept)})
    body += _temp_lines([(s, e) for s, e in form.state_temps if (s, e) not in calls],
                        load_for, printer)
    body += load_for([g for _, g in form.state_guards])
    guards = _guard_lines(spec, form.state_guards, printer, config)
    body += _with_late_check(guards, late_names, spec.nonfinite_input, config)
    body += load_for([e for exprs in form.outputs for e in exprs])
    body += _commit(spec, _output_stores(spec, form.outputs, printer, config), config,
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
        *[_param_doc(a, True, config, own) for a in state_args],
        *[_param_doc(a, False, config, own) for a in spec.outputs],
        f"@return {ok} on success; on error no output is written:",
        f"        {not_init} if {PREPARED_ARG} was not filled by {api.prepare},",
    ]
    if spec.nonfinite_input:
        first, *rest = _unread_doc(state_slots, used, config, "an input")
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
                   *(_param_decl(a, True, config) for a in state_args),
                   *(_param_decl(a, False, config) for a in spec.outputs)],
        "doc_lines": doc,
        "size_macros": _size_macros(own, config),
        "ops": ops.comment(),
        "body": body,
        "status_ok": ok,
    }


def _any_nonfinite(names: Sequence[str], config: CConfig) -> str:
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


CODE_ID_UNSET = "0x00000000u"  # <PREFIX>_CODE_ID until the backend has every file (stamp_code_id)


def stamp_code_id(files: dict[str, str], types_header: str, macro: str,
                  exclude: Sequence[str] = ()) -> str:
    """Set ``macro`` in ``types_header`` to the first 32 bits of a SHA-256 of ``files``
    (names and texts, the value still unset; ``exclude`` left out); returns the value."""
    digest = hashlib.sha256()
    for name in sorted(files):
        if name not in exclude:
            digest.update(name.encode() + b"\0" + files[name].encode() + b"\0")
    value = f"0x{digest.hexdigest()[:8]}u"
    unset = f"#define {macro} {CODE_ID_UNSET}"
    if files[types_header].count(unset) != 1:
        raise RuntimeError(f"{types_header}: expected one '{unset}' line to stamp")
    files[types_header] = files[types_header].replace(unset, f"#define {macro} {value}")
    return value


def _base_context(config: CConfig, source: str, template: str) -> dict[str, object]:
    return {
        "preamble": template_util.preamble_lines(source, TEMPLATE_DIR, template),
        "config": config,
    }


def norm_arities(texts: Iterable[str], config: CConfig) -> list[int]:
    """The sizes n of the ``<prefix>_norm<n>`` calls in ``texts`` (the printers write one
    for every square root of a sum of squares; ``render_types`` defines them)."""
    call = re.compile(rf"\b{re.escape(config.prefix)}norm(\d+)\(")
    return sorted({int(m.group(1)) for text in texts for m in call.finditer(text)})


def render_types(
    specs: Sequence[FunctionSpec], config: CConfig | None = None, *, source: str = "",
    norms: Sequence[int] = (),
) -> dict[str, str]:
    """``wmr_types.h``: scalar type, literal and math macros, status enum, every struct
    type used by ``specs`` (pass the specs of *all* modules so each struct is defined once)
    and the overflow-safe norms of the sizes ``norms``."""
    config = config or CConfig()
    template = "types.h.jinja"
    text = template_util.render(
        TEMPLATE_DIR,
        template,
        **_base_context(config, source, template),
        guard=_guard(config.types_header, config),
        macros=[(m.name.upper(), m.name, ", ".join("xyz"[: m.arity]))
                for m in config.math_macros if m.name not in INLINE_MATH],
        inline_math=[m.name for m in config.math_macros if m.name in INLINE_MATH],
        generated_trig=[m.name for m in config.math_macros if m.name in GENERATED_TRIG],
        trig_bound=TRIG_BOUND,
        norms=sorted(set(norms)),
        structs=_structs(specs, config),
        width=WIDTH,
        CODE_ID_UNSET=CODE_ID_UNSET,
    )
    return {config.types_header: format_c(text)}


def render(
    specs: Sequence[FunctionSpec],
    module: str,
    config: CConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """``<module>.h`` and ``<module>.c`` for ``specs`` (relative path -> text).

    ``source`` names what the specs were generated from (robot file, modeling module);
    it goes into each file's preamble. Struct types live in ``wmr_types.h``
    (:func:`render_types`).
    """
    return render_module([function_ir(s) for s in specs], module, config, source=source)


def render_module(
    functions: Sequence[FunctionIR],
    module: str,
    config: CConfig | None = None,
    *,
    source: str = "",
    wrappers: Mapping[str, Sequence[str]] | None = None,
    includes: Sequence[str] = (),
) -> dict[str, str]:
    """:func:`render` from the functions' shared form (no CSE here). ``wrappers``: the body
    (C statements) of each function so named, written instead of its own (the laws module's
    thin wrappers over the steps' shared kernels); ``includes``: headers its ``.c``
    includes after its own."""
    config = config or CConfig()
    if not module.isidentifier():
        raise ValueError(f"module name {module!r} is not an identifier")
    names = [f.name for f in functions]
    if len(set(names)) != len(names):
        raise ValueError(f"{module}: duplicate function names {names}")
    prepared = [f for f in functions if f.prepared is not None]
    api = None
    if prepared:
        if len(prepared) > 1:
            raise ValueError(f"{module}: one prepared function per module, not "
                             f"{[f.name for f in prepared]}")
        if not module.startswith(config.prefix):
            raise ValueError(f"{module}: a module with a prepared function must start with "
                             f"{config.prefix}")
        api = _prepared_api(prepared[0], module, config)
        taken = {f"{config.prefix}{n}" for n in names}
        clash = taken & {api.prepare, f"{api.function}_prepared"}
        if clash:
            raise ValueError(f"{module}: {sorted(clash)} is already a generated function")
    contexts = []
    for f in functions:
        ctx = _function_context(f, config, module)
        if wrappers and f.spec.name in wrappers:
            ctx["wrapper"] = list(wrappers[f.spec.name])
        contexts.append(ctx)
        if f.prepared is not None:
            assert api is not None
            contexts += [_prepare_context(f, api, config), _prepared_context(f, api, config)]
    files: dict[str, str] = {}
    for suffix, template in ((".h", "module.h.jinja"), (".c", "module.c.jinja")):
        files[module + suffix] = format_c(
            template_util.render(
                TEMPLATE_DIR,
                template,
                **_base_context(config, source, template),
                module=module,
                guard=_guard(module + "_H", config),
                header=module + ".h",
                functions=contexts,
                prepared=api,
                includes=list(includes),
            )
        )
    return files


def render_all(
    modules: Mapping[str, Sequence[FunctionSpec]],
    config: CConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """``wmr_types.h`` for all modules plus each module's ``.h``/``.c``."""
    return render_all_ir(
        {name: [function_ir(s) for s in specs] for name, specs in modules.items()},
        config,
        source=source,
    )


def render_all_ir(
    modules: Mapping[str, Sequence[FunctionIR]],
    config: CConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """:func:`render_all` from the functions' shared form (no CSE here). The types header
    is rendered last: it defines the norms the modules call."""
    config = config or CConfig()
    all_specs = [f.spec for functions in modules.values() for f in functions]
    files: dict[str, str] = {}
    for module in sorted(modules):
        files.update(render_module(modules[module], module, config, source=source))
    files.update(render_types(all_specs, config, source=source,
                              norms=norm_arities(files.values(), config)))
    return files


def cdef(
    specs: Sequence[FunctionSpec], config: CConfig | None = None, *, float32: bool = False
) -> str:
    """Declarations of the types, size constants and functions of ``specs`` for
    ``cffi.FFI.cdef`` (``wmr_real_t`` is ``float`` if ``float32``, else ``double``; only
    integer ``#define``s, which cffi reads as constants)."""
    config = config or CConfig()
    functions = [
        {
            "name": f"{config.prefix}{spec.name}",
            "size_macros": _size_macros(spec, config),
            "return_type": config.status_type if spec.returns_status else "void",
            "params": [_param_decl(a, True, config) for a in spec.inputs]
            + [_param_decl(a, False, config) for a in spec.outputs],
        }
        for spec in specs
    ]
    return template_util.render(
        TEMPLATE_DIR,
        "cdef.jinja",
        config=config,
        real="float" if float32 else "double",
        structs=_structs(specs, config),
        functions=functions,
    )


# ------------------------------------------------------------ a step's kept kernels


@dataclass(frozen=True)
class KeptKernel:
    """A kernel a controller step calls, split at its parameters (:mod:`codegen.prepare`):
    ``keep`` evaluates its parameter-only subexpressions once (the controller's ``_init``
    stores them in the state, ``size`` values), ``call`` the per-step rest reading them."""

    name: str  # the spec's name
    size: int
    keep: dict[str, object]  # function contexts, as _function_context's
    call: dict[str, object]
    fixed: tuple[str, ...] = ()  # inputs _keep takes after the parameters, not the step


def kept_kernel(ir: FunctionIR, config: CConfig, name: str, kept_arg: str = "kept",
                fixed_inputs: frozenset[str] = frozenset()) -> KeptKernel | None:
    """``ir`` (a kernel without status or guards, with a ``"params"`` input) as
    ``<name>_keep(p, fixed inputs..., kept)`` and ``<name>(kept, other inputs...,
    outputs...)``, or None if nothing but parameters would be kept (then there is nothing
    to evaluate once). The inputs named in ``fixed_inputs`` (values the caller derives from
    its configuration alone) are split with the parameters: ``_keep`` takes them."""
    spec = ir.spec
    if spec.returns_status or spec.guards or not any(a.kind == "params" for a in spec.inputs):
        return None
    form = prepared_form(ir.cse, replace(spec, returns_status=True), fixed_inputs)
    if not form.param_temps:
        return None
    slots = input_slots(spec)
    names = _local_names(spec, slots)
    printer = _printer(names, (*form.param_temps, *form.state_temps), config, spec)
    # keep: the parameters read, the parameter-only temporaries, the kept values stored
    param_args = [a for a in spec.inputs if a.kind == "params" or a.name in fixed_inputs]
    used_params = form.used_params()
    body = [_Line("void", a.name) for a in param_args  # (an `_mhat` kernel's p)
            if not any(s in used_params for s in a.all_symbols())]
    body += [_decl(names[s.symbol], _access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used_params]
    body += [_decl(str(s), printer.expr_code(e)) for s, e in form.param_temps]
    body += [_Line("store", f"{kept_arg}[{k}]", names.get(s, str(s)))
             for k, s in enumerate(form.kept)]
    keep_ops = op_count_from(printer.ops)
    keep: dict[str, object] = {
        "name": f"{name}_keep", "origin": f"the parameter-only part of {config.prefix}{spec.name}",
        "return_type": "void",
        "params": [*(_param_decl(a, True, config) for a in param_args),
                   f"{config.real_type} {kept_arg}[{len(form.kept)}]"],
        "ops": keep_ops.comment(), "body": body,
    }
    # call: the per-step rest, each input and kept value read before its first use
    printer = _printer(names, (*form.param_temps, *form.state_temps), config, spec)
    state_args = [a for a in spec.inputs if a.kind != "params" and a.name not in fixed_inputs]
    used = form.used_state()
    loads = {s.symbol: _decl(names[s.symbol], _access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used}
    loads.update({s: _decl(names.get(s, str(s)), f"{kept_arg}[{k}]")
                  for k, s in enumerate(form.kept)})
    body = [_Line("void", a.name) for a in state_args
            if not any(s in used for s in a.all_symbols())]
    load_for = _LazyLoads(loads)
    body += _temp_lines(form.state_temps, load_for, printer)
    body += load_for([e for exprs in form.outputs for e in exprs])
    body += load_for.rest()
    body += _commit(spec, _output_stores(spec, form.outputs, printer, config), config)
    call: dict[str, object] = {
        "name": name, "origin": f"the per-step part of {config.prefix}{spec.name}",
        "return_type": "void",
        "params": [f"const {config.real_type} {kept_arg}[{len(form.kept)}]",
                   *(_param_decl(a, True, config) for a in state_args),
                   *(_param_decl(a, False, config) for a in spec.outputs)],
        "ops": op_count_from(printer.ops).comment(), "body": body,
    }
    moved = tuple(a.name for a in spec.inputs if a.name in fixed_inputs)
    return KeptKernel(spec.name, len(form.kept), keep, call, moved)
