"""The C99 backend as the driver sees it: every C file of a robot, from its target.

``c/``: ``<prefix>_types.h``, one ``.h``/``.c`` pair per module, the controllers
(``<prefix>_controller.{h,c}`` and ``<prefix>_<controller>.{h,c}`` from the layout),
``<prefix>_kernels.h`` (the steps' kernels), ``<prefix>_robot.h`` (the robot file's
numbers) and ``example_main.c``.

This module wires the backend's jobs, each its own module: :mod:`.lowering` (a function's
IR as C statements), :mod:`.prepared` (the prepare-parameters API), :mod:`.kernels` (which
kernels each controller step calls, from its declaration, and which are split at their
parameters), :mod:`.files` (the module files and the types header); the controllers' own
contexts (their nominal checks) are written here. Everything is decided before any
template is rendered, and each template is rendered once per file it writes.
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from codegen import template_util
from codegen.backend import RobotTarget
from codegen.backends.c.certify.gate import certified_gate_context
from codegen.backends.c.config import CConfig
from codegen.backends.c.files import (
    TEMPLATE_DIR,
    module_context,
    module_files,
    render_types,
    stamp_code_id,
)
from codegen.backends.c.format import format_c
from codegen.backends.c.kernels import law_wrappers, step_kernels, step_norms
from codegen.backends.c.printer import CPrinter
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


class CBackend:
    """C99 over ``<prefix>_real_t`` (double, or float with ``-D<PREFIX>_FLOAT32``)."""

    name = "c"
    folder = "c"

    def render(self, target: RobotTarget) -> dict[str, str]:
        """Every C file of ``target``, each template rendered once per file it writes: the
        steps' kernels from the controllers' declarations (:mod:`.kernels`), then the
        modules (the laws module's kernels as wrappers over them), the controllers, and
        last the types header with every norm the lowered code and the steps call."""
        layout = target.layout
        config = config_for(layout)
        pre = layout.prefix
        law = target.law_source
        source = f"{target.model_source}, {law}"
        laws = next(m for m in target.modules if m.name == f"{pre}_laws")
        kp = f"{pre}_k_"  # the steps' kernels, written once in <prefix>_kernels.h
        kernels_h = f"{pre}_kernels.h"
        kernels = step_kernels(target.controllers, layout, laws.functions, laws.name, kp, config)
        modules = [
            module_context(m.functions, m.name, config,
                           law_wrappers(m.functions, kernels, kp, config) if m is laws else None)
            for m in sorted(target.modules, key=lambda m: m.name)
        ]
        files: dict[str, str] = {}
        for ctx in modules:
            # the laws module's functions of the steps' kernels: thin wrappers over them
            files.update(module_files(ctx, config, source=source,
                                      includes=[kernels_h] if ctx.module == laws.name else []))
        param_fields = [p.c_field for p in target.model.params]
        for suffix in ("h", "c"):
            files[f"{pre}_controller.{suffix}"] = _template(
                f"controller_common.{suffix}.jinja", law, layout=layout,
                param_fields=param_fields, max_abs_input=MAX_ABS_INPUT,
                nominal_conditions=nominal_conditions(target, config),
                nominal_guards=nominal_guards(target, config),
                nominal_bounds=nominal_bounds(target), **c_common_context(target.controllers),
                minimal_reads_q_prev=kernels.reads("minimal_tde", "q_prev"),
            )
        text = template_util.render(TEMPLATE_DIR, "step_kernels.c.jinja",
                                    functions=list(kernels.contexts), laws=laws.name,
                                    config=config, inline=f"{pre.upper()}_KERNEL_INLINE"
                                    ) if kernels.contexts else ""
        files[kernels_h] = _template(
            "kernels.h.jinja", law, guard=f"{pre.upper()}_KERNELS_H", kernels=text,
            laws=laws.name, prefix=pre, types_header=config.types_header)
        norms = set(kernels.norms).union(*(ctx.norms for ctx in modules))
        for info in target.controllers:
            context = dict(
                layout=layout, c=info, max_abs_input=MAX_ABS_INPUT, step_kernel_prefix=kp,
                **c_controller_context(info, param_fields, layout, target.model),
                **kernels.controller_context(info.name, kernels_h),
                gate=certified_gate_context(info, pre),
                minimal_reads_q_prev=kernels.reads("minimal_tde", "q_prev"))
            step = context.pop("step_kernels")
            files[f"{pre}_{info.name}.h"] = _template("controller.h.jinja", law, **context)
            files[f"{pre}_{info.name}.c"] = _template("controller.c.jinja", law,
                                                      step_kernels=step, **context)
            norms |= step_norms(info, layout)
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
        files.update(render_types([f.spec for m in target.modules for f in m.functions], config,
                                  source=source, norms=sorted(norms)))
        stamp_code_id(files, config.types_header, f"{config.macro_prefix}CODE_ID",
                      exclude=("example_main.c",))
        return files


BACKEND = CBackend()
