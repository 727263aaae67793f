"""Which files the C backend writes, and with which context: the types header
(``<prefix>_types.h``: scalar type, math macros, status codes, every struct type once, the
norms the lowered code calls), one ``<module>.h``/``<module>.c`` pair per module, and the
cffi declarations (:func:`cdef`). Every file's template is rendered once, from contexts
computed before it (:mod:`.lowering`, :mod:`.prepared`): nothing rendered is read back.

Struct fields are ``wmr_real_t f;`` for (1, 1), ``wmr_real_t f[N];`` for (N, 1)/(1, N)
and ``wmr_real_t f[R][C];`` for matrices (C arrays are row-major, so ``&f[0][0]`` is the
same flat row-major block as everywhere else). All struct types (params and struct
arguments of every module) are defined once, in ``wmr_types.h``, rendered by
:func:`render_types` from the specs of all modules.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from codegen import template_util
from codegen.backend import FunctionIR, function_ir
from codegen.backends.c import trig_table
from codegen.backends.c.config import CConfig
from codegen.backends.c.format import WIDTH, format_c
from codegen.backends.c.lowering import (
    C_KEYWORDS,
    comment_text,
    context_norms,
    function_context,
    param_decl,
    size_macros,
    struct_ctype,
)
from codegen.backends.c.prepared import (
    PreparedApi,
    prepare_context,
    prepared_api,
    prepared_context,
    prepared_wrapper,
)
from codegen.certify.header import certificate_doc
from codegen.cse import count_ops
from codegen.layout import is_scalar, is_vector
from codegen.shared import SharedCall
from codegen.spec import Field, FunctionSpec

TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"

_COMPLEX_H_NAMES = frozenset({"I", "complex", "imaginary"})


def _usable_field(name: str) -> bool:
    return (name.isidentifier() and name.isascii() and name not in C_KEYWORDS
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


def _field_doc(f: Field) -> str:
    return f.doc or ", ".join(str(s) for s in f.symbols)


def _structs(specs: Sequence[FunctionSpec], config: CConfig) -> list[_Struct]:
    """Struct types used by ``specs``: params types first, then others, each in order of
    first use; the same ctype must always have the same fields."""
    found: dict[str, _Struct] = {}
    args = [a for spec in specs for a in (*spec.inputs, *spec.outputs) if a.kind != "array"]
    args = [a for a in args if a.kind == "params"] + [a for a in args if a.kind == "struct"]
    for arg in args:
        ctype = struct_ctype(arg, config)
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
        **trig_table.context(),
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


@dataclass(frozen=True)
class ModuleContext:
    """A module's functions lowered (:mod:`.lowering`, :mod:`.prepared`), before any file
    is written: ``functions`` the templates' contexts, ``api`` its prepare API if any,
    ``norms`` the ``<prefix>norm<n>`` its written bodies call."""

    module: str
    functions: tuple[dict[str, object], ...]
    api: PreparedApi | None
    norms: frozenset[int]
    # the static functions of the ``.c`` its functions call (``codegen.shared`` groups)
    helpers: tuple[dict[str, object], ...] = ()


def module_context(
    functions: Sequence[FunctionIR],
    module: str,
    config: CConfig,
    wrappers: Mapping[str, Sequence[str]] | None = None,
) -> ModuleContext:
    """``module``'s functions lowered. ``wrappers``: the body (C statements) of each
    function so named, written instead of its own (the laws module's thin wrappers over
    the steps' shared kernels: its own norms are then the kernels')."""
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
        api = prepared_api(prepared[0], module, config)
        taken = {f"{config.prefix}{n}" for n in names}
        clash = taken & {api.prepare, f"{api.function}_prepared"}
        if clash:
            raise ValueError(f"{module}: {sorted(clash)} is already a generated function")
    helpers: dict[str, dict[str, object]] = {}
    for f in functions:
        if f.shared is not None and f.shared.quantities.spec.name not in helpers:
            helpers[f.shared.quantities.spec.name] = helper_context(f.shared, config)
    contexts = []
    for f in functions:
        ctx = function_context(f, config, module)
        late_helper = ctx.pop("late_helper", None)
        if isinstance(late_helper, dict):  # one copy of its late input test
            helpers[str(late_helper["name"])] = late_helper
        ctx["doc_lines"] = [*ctx["doc_lines"],  # type: ignore[misc]
                            *certificate_doc(f.name, ctx["body"], config.prefix.rstrip("_"))]
        if wrappers and f.spec.name in wrappers:
            ctx["wrapper"] = list(wrappers[f.spec.name])
            ctx["norms"] = []
        contexts.append(ctx)
        if f.prepared is not None:
            assert api is not None
            if f.spec.calls_prepared:
                ctx["wrapper"] = prepared_wrapper(f, api, config)
            contexts += [prepare_context(f, api, config), prepared_context(f, api, config)]
    clash = {f"{config.prefix}{n}" for n in names} & {str(h["name"]) for h in helpers.values()}
    if clash:
        raise ValueError(f"{module}: {sorted(clash)} is already a generated function")
    return ModuleContext(module, tuple(contexts), api,
                         context_norms([*contexts, *helpers.values()]),
                         tuple(helpers.values()))


def helper_context(call: SharedCall, config: CConfig) -> dict[str, object]:
    """The static helper of ``call``'s group: what its callers read, evaluated once
    (their own bodies hold the same arithmetic as hidden lines, :func:`.lowering.shared_lines`)."""
    helper = call.quantities
    ir = FunctionIR(helper.spec, helper.cse, helper.cse, count_ops(helper.cse))
    ctx = function_context(ir, config, "")
    ctx["summary"] = comment_text(helper.spec.doc)
    return ctx


def module_files(ctx: ModuleContext, config: CConfig, *, source: str = "",
                 includes: Sequence[str] = ()) -> dict[str, str]:
    """``<module>.h`` and ``<module>.c`` of a lowered module, each rendered once;
    ``includes``: headers its ``.c`` includes after its own."""
    files: dict[str, str] = {}
    for suffix, template in ((".h", "module.h.jinja"), (".c", "module.c.jinja")):
        files[ctx.module + suffix] = format_c(
            template_util.render(
                TEMPLATE_DIR,
                template,
                **_base_context(config, source, template),
                module=ctx.module,
                guard=_guard(ctx.module + "_H", config),
                header=ctx.module + ".h",
                functions=list(ctx.functions),
                helpers=list(ctx.helpers),
                prepared=ctx.api,
                includes=list(includes),
            )
        )
    return files


def render_module(
    functions: Sequence[FunctionIR],
    module: str,
    config: CConfig | None = None,
    *,
    source: str = "",
) -> dict[str, str]:
    """:func:`render` from the functions' shared form (no CSE here)."""
    config = config or CConfig()
    return module_files(module_context(functions, module, config), config, source=source)


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
    defines the norms the lowered modules call."""
    config = config or CConfig()
    all_specs = [f.spec for functions in modules.values() for f in functions]
    contexts = [module_context(modules[m], m, config) for m in sorted(modules)]
    files: dict[str, str] = {}
    for ctx in contexts:
        files.update(module_files(ctx, config, source=source))
    norms = frozenset().union(*(ctx.norms for ctx in contexts))
    files.update(render_types(all_specs, config, source=source, norms=sorted(norms)))
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
            "size_macros": size_macros(spec, config),
            "return_type": config.status_type if spec.returns_status else "void",
            "params": [param_decl(a, True, config) for a in spec.inputs]
            + [param_decl(a, False, config) for a in spec.outputs],
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

