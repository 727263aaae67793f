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

Functions read every used input into a ``const`` local first, so outputs may alias inputs
(in-place state updates are safe), then evaluate CSE temporaries, then store outputs.
"""

from __future__ import annotations

import keyword
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from codegen import template_util
from codegen.backend import FunctionIR, function_ir
from codegen.backends.c.config import CConfig
from codegen.backends.c.format import WIDTH, format_c
from codegen.backends.c.printer import CPrinter
from codegen.cse import op_count_from
from codegen.layout import (
    argument_size,
    input_slots,
    is_scalar,
    is_vector,
    local_names,
    split_fields,
)
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


def _usable_field(name: str) -> bool:
    return name.isidentifier() and name.isascii() and name not in _C_KEYWORDS


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
        bad = [f.name for f in arg.fields if not _usable_field(config.c_field(f.name))]
        if bad:
            raise ValueError(f"{ctype}: field names {bad} are not usable in C")
        struct = _Struct(
            ctype=ctype,
            doc=arg.doc,
            fields=tuple(
                _StructField(config.c_field(f.name), _dims(f.shape), _field_doc(f))
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


# fmax and fmin are printed as static inline functions of wmr_types.h, not library calls
# (on a Cortex-M4, fmaxf is a call into newlib and __fpclassifyf; on x86-64 a libm call).
INLINE_MATH = ("fmax", "fmin")


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


def _access(arg: Argument, f: Field | None, index: int, config: CConfig) -> str:
    """C lvalue/rvalue of element ``index`` (row-major) of an array or struct field."""
    if f is None:
        return f"{arg.name}[{index}]"
    base = f"{arg.name}->{config.c_field(f.name)}"
    if is_scalar(f.shape):
        return base
    if is_vector(f.shape):
        return f"{base}[{index}]"
    return f"{base}[{index // f.shape[1]}][{index % f.shape[1]}]"


def _function_context(ir: FunctionIR, config: CConfig) -> dict[str, object]:
    spec, result = ir.spec, ir.cse
    slots = input_slots(spec)
    reserved = {a.name for a in (*spec.inputs, *spec.outputs)}
    names = local_names(slots, reserved, _usable_c_name)
    used = result.used_symbols()
    printer_names = dict(names)
    printer_names.update({s: str(s) for s, _ in result.temps})
    printer = CPrinter(config, printer_names)

    loads = [
        (names[s.symbol], _access(s.arg, s.field, s.index, config))
        for s in slots
        if s.symbol in used
    ]
    unused = [a.name for a in spec.inputs if not any(s in used for s in a.all_symbols())]
    temps = [(str(s), printer.expr_code(e)) for s, e in result.temps]
    stores: list[tuple[str, str]] = []
    guard_values = result.outputs[len(spec.outputs):]
    guards = [
        (printer.expr_code(e), g.status, _comment_text(g.doc))
        for g, e in zip(spec.guards, guard_values[0] if guard_values else (), strict=True)
    ]
    for arg, exprs in zip(spec.outputs, result.outputs[: len(spec.outputs)], strict=True):
        if arg.kind == "array":
            stores += [
                (_access(arg, None, i, config), printer.expr_code(e)) for i, e in enumerate(exprs)
            ]
        else:
            for f, chunk in split_fields(arg, exprs):
                stores += [
                    (_access(arg, f, i, config), printer.expr_code(e))
                    for i, e in enumerate(chunk)
                ]
    ops = op_count_from(printer.ops)
    checked = spec.returns_status and bool(spec.nonfinite_output)
    if checked:  # compute into locals, check, then store: no output written on error
        results = [(f"r_{k}", value) for k, (_, value) in enumerate(stores)]
        stores = [(target, f"r_{k}") for k, (target, _) in enumerate(stores)]
    else:
        results = []

    name = f"{config.prefix}{spec.name}"
    ret = config.status_type if spec.returns_status else "void"
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
            doc.append(f"        {spec.nonfinite_input} if an input it reads is NaN or infinite")
            unread = [_access(s.arg, s.field, s.index, config).replace("->", ".")
                      for s in slots if s.symbol not in used]
            if unread:
                doc.append(f"        (it does not read, and ignores: {', '.join(unread)}),")
            else:
                doc[-1] += " (it reads every input),"
        doc += [f"        {g.status} if not ({_comment_text(g.doc)})," for g in spec.guards]
        if spec.nonfinite_output:
            doc.append(f"        {spec.nonfinite_output} if a result is not finite.")
    doc += ["", ops.comment()]
    return {
        "name": name,
        "return_type": ret,
        "params": params,
        "doc_lines": doc,
        "size_macros": _size_macros(spec, config),
        "ops": ops.comment(),
        "unused": unused,
        "loads": loads,
        "temps": temps,
        "stores": stores,
        "status_ok": config.status_codes[0].name if spec.returns_status else "",
        "input_check": (
            _any_nonfinite([n for n, _ in loads])
            if spec.returns_status and spec.nonfinite_input and loads else ""
        ),
        "nonfinite_input": spec.nonfinite_input,
        "guards": guards,
        "results": results,
        "output_check": _any_nonfinite([n for n, _ in results]) if results else "",
        "nonfinite_output": spec.nonfinite_output,
    }


def _any_nonfinite(names: Sequence[str]) -> str:
    """One branch-free test that is true when any of ``names`` is NaN or infinite.

    x - x is 0 for a finite x and NaN for NaN or ±Inf, and a sum of zeros and NaNs is NaN
    exactly when one term is: the same answer as one ``isfinite`` per value, without a
    compare and branch per value (and without keeping every value live across them).
    The sum is balanced, so its chain of dependent additions is log2(n) long.
    """
    def tree(terms: list[str]) -> str:  # a balanced sum: a short dependency chain
        if len(terms) == 1:
            return terms[0]
        half = (len(terms) + 1) // 2
        return f"({tree(terms[:half])} + {tree(terms[half:])})"

    return "isnan" + tree([f"({n} - {n})" for n in names]) + " != 0"  # MISRA 14.4


def _base_context(config: CConfig, source: str, template: str) -> dict[str, object]:
    return {
        "preamble": template_util.preamble_lines(source, TEMPLATE_DIR, template),
        "config": config,
    }


def render_types(
    specs: Sequence[FunctionSpec], config: CConfig | None = None, *, source: str = ""
) -> dict[str, str]:
    """``wmr_types.h``: scalar type, literal and math macros, status enum, and every struct
    type used by ``specs`` (pass the specs of *all* modules so each struct is defined once)."""
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
        structs=_structs(specs, config),
        width=WIDTH,
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
) -> dict[str, str]:
    """:func:`render` from the functions' shared form (no CSE here)."""
    config = config or CConfig()
    if not module.isidentifier():
        raise ValueError(f"module name {module!r} is not an identifier")
    names = [f.name for f in functions]
    if len(set(names)) != len(names):
        raise ValueError(f"{module}: duplicate function names {names}")
    contexts = [_function_context(f, config) for f in functions]
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
    """:func:`render_all` from the functions' shared form (no CSE here)."""
    config = config or CConfig()
    all_specs = [f.spec for functions in modules.values() for f in functions]
    files = render_types(all_specs, config, source=source)
    for module in sorted(modules):
        files.update(render_module(modules[module], module, config, source=source))
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
