"""The C99 backend as the driver sees it: every C file of a robot, from its target.

``c/``: ``<prefix>_types.h``, one ``.h``/``.c`` pair per module, the controllers
(``<prefix>_controller.{h,c}`` and ``<prefix>_<controller>.{h,c}`` from the layout),
``<prefix>_robot.h`` (the robot file's numbers) and ``example_main.c``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import replace
from functools import cache

import sympy as sp

from codegen import template_util
from codegen.backend import FunctionIR, RobotTarget
from codegen.backends.c.config import CConfig
from codegen.backends.c.format import format_c
from codegen.backends.c.printer import CPrinter
from codegen.backends.c.render import (
    TEMPLATE_DIR,
    KeptKernel,
    _function_context,
    kept_kernel,
    norm_arities,
    render_all_ir,
    render_module,
    render_types,
    stamp_code_id,
)
from codegen.controller_api import (
    MAX_ABS_INPUT,
    c_common_context,
    c_controller_context,
    defines,
    nominal_range,
    status_codes,
)
from codegen.controller_layout import ControllerLayout
from codegen.robot_functions import (
    guard_mass_matrix,
    leading_minors,
    minor_doc,
    positive_parameters,
    staged_forms,
)


@cache
def config_for(layout: ControllerLayout) -> CConfig:
    """The C names for a robot: ``<prefix>_real_t``, ``<PREFIX>_LIT``, its status codes and
    integer constants."""
    p, big = layout.prefix, layout.PREFIX
    return CConfig(
        prefix=f"{p}_", types_header=f"{p}_types.h", real_type=f"{p}_real_t",
        status_type=f"{p}_status_t", params_ctype=f"{p}_params_t",
        float32_define=f"{big}_FLOAT32", literal_macro=f"{big}_LIT",
        status_codes=status_codes(layout), defines=defines(layout),
    )


def default_config() -> CConfig:
    """The default robot's C config (``wmr_`` names), for tools built around it."""
    from codegen.generate import layout_for
    from modeling.robot_file import load_robot_model

    return config_for(layout_for(load_robot_model(None)[0]))


def nominal_conditions(target: RobotTarget, config: CConfig) -> list[tuple[str, str]]:
    """The robot's own conditions on nominal parameters as (C expression over ``p->``, doc)."""
    names = {p.symbol: f"p->{p.c_field}" for p in target.model.params}
    printer = CPrinter(config, names)
    return [(printer.expr_code(c.expr), c.doc) for c in target.model.nominal_conditions]


def nominal_guards(target: RobotTarget, config: CConfig) -> dict[str, list[tuple[str, str]]]:
    """The forward dynamics' guards on the parameters, written out for the controllers'
    nominal check (so validating a configuration does not link the forward dynamics):
    ``positive`` (C condition, doc) per positive parameter; ``mbar`` the entries of SᵀMS at
    q = 0 (row-major C expressions, doc empty); ``minors`` its leading minors over those
    entries (``mbar[k]``), positive exactly when SᵀMS is positive definite (Sylvester)."""
    model = target.model
    at_zero = {q: sp.S.Zero for q in model.q}
    if model.staged:  # the closed form at q = 0 only (small: sin 0, cos 0 fold away)
        stage = staged_forms(model)
        mbar = stage.mbar.applyfunc(lambda e: stage.stage.expand(e, at_zero))
    else:
        mbar = guard_mass_matrix(model).subs(at_zero)
    n = mbar.rows
    entry = sp.Matrix(n, n, lambda i, j: sp.Symbol(f"mbar_{i * n + j}", real=True))
    on_entries = CPrinter(config, {e: f"mbar[{k}]" for k, e in enumerate(entry)})
    minors = [(on_entries.expr_code(m), minor_doc(k + 1, n))
              for k, m in enumerate(leading_minors(entry))]
    temps, (shared,) = sp.cse([mbar], symbols=sp.numbered_symbols("mbar_t"))
    names = {p.symbol: f"p->{p.c_field}" for p in model.params}
    names.update({t: f"t{k}" for k, (t, _) in enumerate(temps)})
    printer = CPrinter(config, names)
    return {
        "positive": [(printer.expr_code(s), doc) for s, doc in positive_parameters(model)],
        "temps": [(names[t], printer.expr_code(e)) for t, e in temps],
        "mbar": [(printer.expr_code(e), "") for e in shared],
        "minors": minors,
    }


def nominal_bounds(target: RobotTarget) -> list[tuple[str, str, str]]:
    """(C field, lowest, highest) accepted value per nominal parameter
    (``controller_api.nominal_range``)."""
    model = target.model
    out = []
    for p in model.params:
        low, high = nominal_range(target.robot.lumped[p.key], p.key in model.positive)
        out.append((p.c_field, repr(low), repr(high)))
    return out


def payload_dependent(target: RobotTarget) -> list[str]:
    """C fields of the parameters a payload changes (the example's heavier plant)."""
    model = target.model
    return [p.c_field for p in model.params
            if model.payload_relations.get(p.symbol, p.symbol) != p.symbol]


def c_string(text: str) -> str:
    """A C string literal of ``text``: quotes, backslashes, non-printable and non-ASCII
    bytes (of its UTF-8) escaped in octal, so any robot name gives a valid header."""
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 0x20 <= byte < 0x7F and ch != "?":  # '?' could start a trigraph
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _template(name: str, source: str, **context: object) -> str:
    text = template_util.render(
        TEMPLATE_DIR,
        name,
        preamble=template_util.preamble_lines(source, TEMPLATE_DIR, name),
        **context,
    )
    return format_c(text)


# Kernel inputs a controller step derives from its configuration alone, so split with the
# parameters: (17)'s span (h or 2h), whose reciprocal _init then keeps (no division a step).
# The controller's _init passes &fresh.tde_<name>, which it computes before the kept values.
STEP_FIXED_INPUTS = frozenset({"span"})


def called_kernels(text: str, kp: str) -> set[str]:
    """The kernel names ``text`` (C) calls or defines as ``<kp><name>(``."""
    return set(re.findall(rf"\b{re.escape(kp)}(\w+)\(", text))


def step_kernels(text: str, kp: str, functions: Sequence[FunctionIR], module: str,
                 config: CConfig) -> tuple[str, list[KeptKernel]]:
    """The kernels of ``module`` that ``text`` (the controllers' C) calls as ``<kp><kernel>``,
    in the module's order, each once as a ``static inline`` function for the shared header
    every controller includes: its step then calls functions of its own translation unit,
    which the compiler inlines and schedules with the step.

    A kernel with parameter-only subexpressions is split at its parameters
    (:func:`~codegen.backends.c.render.kept_kernel`): ``<kp><kernel>_keep``, which a
    controller's ``_init`` calls to keep those values in the state, and ``<kp><kernel>``,
    the per-step rest reading them (a frozen build never calls ``_keep``: static inline, it
    is not compiled then). Returns the C and the kept kernels."""
    called = called_kernels(text, kp)
    by_name = {f.spec.name: f for f in functions}
    unknown = called - set(by_name)
    if unknown:
        raise ValueError(f"{module}: the steps call {sorted(unknown)}, not kernels of it")
    contexts: list[dict[str, object]] = []
    kept: list[KeptKernel] = []
    keeps: dict[tuple[object, ...], str] = {}  # a _keep's parameters and body -> its name
    for f in functions:
        if f.spec.name not in called:
            continue
        if f.spec.returns_status:
            raise ValueError(f"{module}: step kernel {f.spec.name} returns a status")
        split = kept_kernel(f, config, f"{kp}{f.spec.name}", fixed_inputs=STEP_FIXED_INPUTS)
        if split is not None:
            # Two kernels that keep the same values (the minimal form's M-bar in the TDE
            # and in the law) share one _keep: else the compiler merges the copies into an
            # alias that the stack analysis cannot see.
            same = keeps.get(_keep_key(split.keep))
            if same is None:
                keeps[_keep_key(split.keep)] = str(split.keep["name"])
                contexts.append({**split.keep, "unless": ""})
            else:
                split = replace(split, keep={**split.keep, "name": same})
            kept.append(split)
            contexts.append({**split.call, "unless": ""})
            continue
        ctx = _function_context(f, config, module)
        ctx["origin"] = f"the body of {ctx['name']}"
        ctx["name"] = f"{kp}{f.spec.name}"
        ctx["unless"] = ""
        contexts.append(ctx)
    if not contexts:
        return "", kept
    return template_util.render(TEMPLATE_DIR, "step_kernels.c.jinja", functions=contexts,
                                laws=module, config=config), kept


def law_wrappers(functions: Sequence[FunctionIR], kernels: str, kp: str,
                 kept: Sequence[KeptKernel], config: CConfig) -> dict[str, list[str]]:
    """The body of each laws function the steps call as ``<kp><kernel>`` (``kernels``, the
    shared header's C): a call of that kernel, or, split, its ``_keep`` into a local then the
    per-step part (the steps' rounding: e.g. 1/span kept, then a product)."""
    defined = called_kernels(kernels, kp)
    split = {k.name: k for k in kept}
    out: dict[str, list[str]] = {}
    for f in functions:
        spec = f.spec
        if spec.name not in defined:
            continue
        outputs = [a.name for a in spec.outputs]
        k = split.get(spec.name)
        if k is None:
            args = [a.name for a in spec.inputs] + outputs
            out[spec.name] = [f"{kp}{spec.name}({', '.join(args)});"]
            continue
        fixed = [a.name for a in spec.inputs if a.kind == "params" or a.name in k.fixed]
        rest = [a.name for a in spec.inputs if a.kind != "params" and a.name not in k.fixed]
        out[spec.name] = [f"{config.real_type} kept[{k.size}];",
                          f"{k.keep['name']}({', '.join([*fixed, 'kept'])});",
                          f"{kp}{spec.name}({', '.join(['kept', *rest, *outputs])});"]
    return out


def _keep_key(ctx: dict[str, object]) -> tuple[object, ...]:
    """What a ``_keep`` function computes (its parameters and statements), not its name."""
    params = ctx["params"]
    body = ctx["body"]
    assert isinstance(params, list) and isinstance(body, list)
    return (*params, *body)


class CBackend:
    """C99 over ``<prefix>_real_t`` (double, or float with ``-D<PREFIX>_FLOAT32``)."""

    name = "c"
    folder = "c"

    def render(self, target: RobotTarget) -> dict[str, str]:
        layout = target.layout
        config = config_for(layout)
        pre = layout.prefix
        law = target.law_source
        source = f"{target.model_source}, {law}"
        files = render_all_ir({m.name: m.functions for m in target.modules}, config,
                              source=source)
        param_fields = [p.c_field for p in target.model.params]
        for suffix in ("h", "c"):
            files[f"{pre}_controller.{suffix}"] = _template(
                f"controller_common.{suffix}.jinja", law, layout=layout,
                param_fields=param_fields, max_abs_input=MAX_ABS_INPUT,
                nominal_conditions=nominal_conditions(target, config),
                nominal_guards=nominal_guards(target, config),
                nominal_bounds=nominal_bounds(target), **c_common_context(target.controllers),
            )
        laws = next(m for m in target.modules if m.name == f"{pre}_laws")
        kp = f"{pre}_k_"  # the steps' kernels, written once in <prefix>_kernels.h
        kernels_h = f"{pre}_kernels.h"
        contexts: dict[str, dict[str, object]] = {}
        firsts: dict[str, str] = {}
        for info in target.controllers:
            contexts[info.name] = dict(
                layout=layout, c=info, max_abs_input=MAX_ABS_INPUT, step_kernel_prefix=kp,
                **c_controller_context(info, param_fields, layout, target.model))
            # Rendered once to see which kernels the step calls, then with them (and the
            # state with the values the split ones keep).
            firsts[info.name] = _template("controller.c.jinja", law, step_kernels="",
                                          kept_kernels=[], span_kept=[], span_needed=True,
                                          **contexts[info.name])
        # a robot whose ||Mhat(q)^-1|| depends on q: the configuration check evaluates the
        # step's kernel (at q = 0), not the laws module's function
        text, kept = step_kernels("".join(firsts.values()), kp, laws.functions, laws.name,
                                  config)
        files[kernels_h] = _template(
            "kernels.h.jinja", law, guard=f"{pre.upper()}_KERNELS_H", kernels=text,
            laws=laws.name, prefix=pre, types_header=config.types_header)
        # the laws module's functions of the same kernels: thin wrappers over them
        files.update(render_module(
            laws.functions, laws.name, config, source=source, includes=[kernels_h],
            wrappers=law_wrappers(laws.functions, text, kp, kept, config)))
        for info in target.controllers:
            context = contexts[info.name]
            first = firsts[info.name]
            called = called_kernels(first, kp)
            mine = [k for k in kept if k.name in called]
            kept_ctx = [{"name": k.name, "size": k.size, "keep": k.keep["name"],
                         "fixed": list(k.fixed)} for k in mine]
            # the step's span is needed only by a (17) kernel that did not keep 1/span
            span_kept = [k.name for k in mine if "span" in k.fixed]
            tde_called = {k for k in called if k.endswith(("_tde", "_tde_trig"))}
            context.update(span_kept=span_kept, span_needed=bool(tde_called - set(span_kept)))
            files[f"{pre}_{info.name}.h"] = _template("controller.h.jinja", law,
                                                      kept_kernels=kept_ctx, **context)
            files[f"{pre}_{info.name}.c"] = _template(
                "controller.c.jinja", law,
                step_kernels=f'#include "{kernels_h}"' if called else "",
                kept_kernels=kept_ctx, **context)
        robot = target.robot
        fields = [(p.c_field, repr(robot.lumped[p.key])) for p in target.model.params]
        files[f"{pre}_robot.h"] = _template(
            "robot.h.jinja", robot.source, layout=layout, fields=fields,
            robot_name=robot.name.replace("*/", "* /"), robot_name_literal=c_string(robot.name),
        )
        # (the example's preamble has always named the driver as its source)
        files["example_main.c"] = _template(
            "example_main.c.jinja", "codegen/generate.py", layout=layout,
            param_fields=param_fields, heavier=payload_dependent(target),
        )
        # Again, with the norms the controllers call as well (u_discarded).
        files.update(render_types([f.spec for m in target.modules for f in m.functions], config,
                                  source=source, norms=norm_arities(files.values(), config)))
        stamp_code_id(files, config.types_header, f"{config.macro_prefix}CODE_ID",
                      exclude=("example_main.c",))
        return files


BACKEND = CBackend()
