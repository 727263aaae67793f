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
    render_types,
    stamp_code_id,
)
from codegen.controller_api import (
    CONTROLLERS,
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


def step_kernels(text: str, kp: str, functions: Sequence[FunctionIR], module: str,
                 config: CConfig, frozen: str, unguarded: frozenset[str] = frozenset()
                 ) -> tuple[str, list[KeptKernel]]:
    """Static copies, named ``<kp><kernel>``, of the kernels of ``module`` that ``text``
    (a controller's C) calls under those names, in the module's order: the step then calls
    functions of its own file, which the compiler inlines and schedules with the step.

    A kernel with parameter-only subexpressions is split at its parameters
    (:func:`~codegen.backends.c.render.kept_kernel`): ``<kp><kernel>_keep``, which the
    controller's ``_init`` calls to keep those values in the state, and ``<kp><kernel>``,
    the per-step rest reading them (``_keep`` is compiled only without ``frozen``, the
    define of a build whose state, kept values included, is compiled in, except that of a
    kernel in ``unguarded``, which the configuration check calls too). Returns the C and
    the kept kernels."""
    called = set(re.findall(rf"\b{re.escape(kp)}(\w+)\(", text))
    by_name = {f.spec.name: f for f in functions}
    unknown = called - set(by_name)
    if unknown:
        raise ValueError(f"{module}: the step calls {sorted(unknown)}, not kernels of it")
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
                contexts.append({**split.keep, "unless": frozen})
            else:
                split = replace(split, keep={**split.keep, "name": same})
            kept.append(split)
            contexts.append({**split.call, "unless": ""})
            continue
        ctx = _function_context(f, config, module)
        ctx["origin"] = f"a copy of {ctx['name']}"
        ctx["name"] = f"{kp}{f.spec.name}"
        ctx["unless"] = ""
        contexts.append(ctx)
    always = {str(k.keep["name"]) for k in kept if k.name in unguarded}
    contexts = [{**c, "unless": ""} if c["name"] in always else c for c in contexts]
    if not contexts:
        return "", kept
    return template_util.render(TEMPLATE_DIR, "step_kernels.c.jinja", functions=contexts,
                                laws=module, config=config), kept


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
                nominal_bounds=nominal_bounds(target), **c_common_context(),
            )
        laws = next(m for m in target.modules if m.name == f"{pre}_laws")
        for info in CONTROLLERS:
            kp = f"{pre}_{info.name}_k_"  # the step's private copies of its kernels
            context = dict(layout=layout, c=info, max_abs_input=MAX_ABS_INPUT,
                           step_kernel_prefix=kp,
                           **c_controller_context(info, param_fields, layout, target.model))
            # Rendered once to see which kernels the step calls, then with their copies
            # (and the state with the values the split ones keep).
            first = _template("controller.c.jinja", law, step_kernels="", kept_kernels=[],
                              span_kept=[], span_needed=True, **context)
            # a robot whose ||Mhat(q)^-1|| depends on q: the configuration check evaluates
            # the step's copy (at q = 0), not the laws module's, so only one is linked
            text, kept = step_kernels(first, kp, laws.functions, laws.name, config,
                                      f"{pre.upper()}_{info.name.upper()}_FROZEN",
                                      frozenset({"minimal_minv_norm"} if layout.minv_needs_q
                                                else ()))
            kept_ctx = [{"name": k.name, "size": k.size, "keep": k.keep["name"],
                         "fixed": list(k.fixed)} for k in kept]
            # the step's span is needed only by a (17) kernel that did not keep 1/span
            span_kept = [k.name for k in kept if "span" in k.fixed]
            tde_called = set(re.findall(rf"\b{re.escape(kp)}(\w+_tde(?:_trig)?)\(", first))
            context.update(span_kept=span_kept, span_needed=bool(tde_called - set(span_kept)))
            files[f"{pre}_{info.name}.h"] = _template("controller.h.jinja", law,
                                                      kept_kernels=kept_ctx, **context)
            files[f"{pre}_{info.name}.c"] = _template(
                "controller.c.jinja", law, step_kernels=text, kept_kernels=kept_ctx, **context)
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
