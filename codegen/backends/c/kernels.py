"""The controller steps' kernels: which kernels of the laws module each step calls, which
of them are split at their parameters (``_keep``, evaluated by a controller's ``_init``,
and the per-step rest), and the laws module's thin wrappers over them.

Which kernels a step calls follows from the controller's declaration (the registry entry:
its estimate, its gain window, its ``_trig`` law) and the robot's layout (its formulations,
the angles and M-hat its kernels take), the same facts ``controller.c.jinja`` branches on:
computed here once (:func:`step_calls`), never found by reading a rendered step.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

from codegen.backend import FunctionIR
from codegen.backends.c.config import CConfig
from codegen.backends.c.lowering import (
    LazyLoads,
    Line,
    access,
    c_local_names,
    commit,
    context_norms,
    decl,
    function_context,
    output_stores,
    param_decl,
    printer_for,
    temp_lines,
)
from codegen.controller_layout import ControllerLayout
from codegen.cse import op_count_from
from codegen.layout import input_slots
from codegen.prepare import prepared_form
from modeling.controllers import ControllerSpec

# Kernel inputs a controller step derives from its configuration alone, so split with the
# parameters: (17)'s span (h or 2h), whose reciprocal _init then keeps (no division a step).
# The controller's _init passes &fresh.tde_<name>, which it computes before the kept values.
STEP_FIXED_INPUTS = frozenset({"span"})


@dataclass(frozen=True)
class StepFeatures:
    """What of a controller's declaration decides its step's kernels: the one place this
    module reads the registry entry (``tde``: the estimate (17); ``window``: TDROC's gain
    (25) over a window; ``trig``: the law's ``_trig``/``_mhat`` variants; ``formulations``:
    those it has)."""

    name: str
    tde: bool
    window: bool
    trig: bool
    formulations: tuple[str, ...]

    @classmethod
    def of(cls, info: ControllerSpec) -> StepFeatures:
        return cls(info.name, bool(info.tde), bool(info.window), bool(info.trig),
                   tuple(info.formulations))

    def law_forms(self, layout: ControllerLayout) -> tuple[str, ...]:
        """The formulations its step's law is written for (``controller.c.jinja``'s
        ``paper_form``)."""
        return ("paper", "minimal") if layout.paper and "paper" in self.formulations \
            else ("minimal",)


def _robot_forms(layout: ControllerLayout) -> tuple[str, ...]:
    return ("paper", "minimal") if layout.paper else ("minimal",)


def step_calls(info: ControllerSpec, layout: ControllerLayout) -> frozenset[str]:
    """The laws module's kernels (spec names) the step of ``info`` calls for ``layout``:
    (17)'s estimate per formulation (on the M-hat kept, the sin/cos kept, or q(t-h)),
    M-hat(q) once a step, (25)'s difference norm, ||Mhat(q)^-1|| and weighted gain, and
    the law (its ``_trig``/``_mhat`` variant where there is one)."""
    f = StepFeatures.of(info)
    calls: set[str] = set()
    if f.tde:
        for form in _robot_forms(layout):
            variant = ("_mhat" if layout.mhat_of(form)
                       else "_trig" if layout.trig_of(form) else "")
            calls.add(f"{form}_tde{variant}")
    if f.trig and layout.mhat_of("minimal"):
        calls.add("minimal_mhat")
    if f.window:
        calls |= {f"{form}_omega_difference" for form in _robot_forms(layout)}
        if layout.minv_needs_q:
            calls.add("minimal_minv_norm_mhat" if layout.mhat_of("minimal")
                      else "minimal_minv_norm")
        calls.add("tdroc_weighted_gain")
    for form in f.law_forms(layout):
        variant = ("_trig" if f.trig and layout.trig_of(form)
                   else "_mhat" if f.trig and layout.mhat_of(form) else "")
        calls.add(f"{form}_{f.name}_law{variant}")
    return frozenset(calls)


def step_norms(info: ControllerSpec, layout: ControllerLayout) -> frozenset[int]:
    """The ``<prefix>norm<n>`` the step itself calls: ||u's dropped rows|| (``u_discarded``)
    of a paper-formulation step whose tau = B^T u drops more than one row."""
    dropped = len(layout.unactuated)
    paper = "paper" in StepFeatures.of(info).law_forms(layout)
    return frozenset({dropped}) if paper and dropped > 1 else frozenset()


@dataclass(frozen=True)
class KeptKernel:
    """A kernel a controller step calls, split at its parameters (:mod:`codegen.prepare`):
    ``keep`` evaluates its parameter-only subexpressions once (the controller's ``_init``
    stores them in the state, ``size`` values), ``call`` the per-step rest reading them."""

    name: str  # the spec's name
    size: int
    keep: dict[str, object]  # function contexts, as function_context's
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
    names = c_local_names(spec, slots)
    printer = printer_for(names, (*form.param_temps, *form.state_temps), config, spec)
    # keep: the parameters read, the parameter-only temporaries, the kept values stored
    param_args = [a for a in spec.inputs if a.kind == "params" or a.name in fixed_inputs]
    used_params = form.used_params()
    body = [Line("void", a.name) for a in param_args  # (an `_mhat` kernel's p)
            if not any(s in used_params for s in a.all_symbols())]
    body += [decl(names[s.symbol], access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used_params]
    body += [decl(str(s), printer.expr_code(e)) for s, e in form.param_temps]
    body += [Line("store", f"{kept_arg}[{k}]", names.get(s, str(s)))
             for k, s in enumerate(form.kept)]
    keep_ops = op_count_from(printer.ops)
    keep: dict[str, object] = {
        "name": f"{name}_keep", "origin": f"the parameter-only part of {config.prefix}{spec.name}",
        "return_type": "void",
        "params": [*(param_decl(a, True, config) for a in param_args),
                   f"{config.real_type} {kept_arg}[{len(form.kept)}]"],
        "ops": keep_ops.comment(), "body": body, "norms": sorted(printer.norms),
    }
    # call: the per-step rest, each input and kept value read before its first use
    printer = printer_for(names, (*form.param_temps, *form.state_temps), config, spec)
    state_args = [a for a in spec.inputs if a.kind != "params" and a.name not in fixed_inputs]
    used = form.used_state()
    loads = {s.symbol: decl(names[s.symbol], access(s.arg, s.field, s.index))
             for s in slots if s.symbol in used}
    loads.update({s: decl(names.get(s, str(s)), f"{kept_arg}[{k}]")
                  for k, s in enumerate(form.kept)})
    body = [Line("void", a.name) for a in state_args
            if not any(s in used for s in a.all_symbols())]
    load_for = LazyLoads(loads)
    body += temp_lines(form.state_temps, load_for, printer)
    body += load_for([e for exprs in form.outputs for e in exprs])
    body += load_for.rest()
    body += commit(spec, output_stores(spec, form.outputs, printer, config), config)
    call: dict[str, object] = {
        "name": name, "origin": f"the per-step part of {config.prefix}{spec.name}",
        "return_type": "void",
        "params": [f"const {config.real_type} {kept_arg}[{len(form.kept)}]",
                   *(param_decl(a, True, config) for a in state_args),
                   *(param_decl(a, False, config) for a in spec.outputs)],
        "ops": op_count_from(printer.ops).comment(), "body": body,
        "norms": sorted(printer.norms),
    }
    moved = tuple(a.name for a in spec.inputs if a.name in fixed_inputs)
    return KeptKernel(spec.name, len(form.kept), keep, call, moved)


@dataclass(frozen=True)
class StepKernels:
    """The kernels the controller steps call (``calls``: each controller's), lowered for
    the shared header in the laws module's order (``contexts``, ``step_kernels.c.jinja``'s
    functions), the split ones (``kept``) and the norms their bodies call."""

    calls: Mapping[str, frozenset[str]]
    contexts: tuple[dict[str, object], ...]
    kept: tuple[KeptKernel, ...]
    norms: frozenset[int]
    # kernel (spec name) -> the inputs its per-step body does not read (the `(void)` ones)
    unread: Mapping[str, frozenset[str]] = field(default_factory=dict)

    def reads(self, kernel: str, arg: str) -> bool:
        """Whether a step's ``kernel`` reads its input ``arg`` (False: no step calls it)."""
        return kernel in self.called and arg not in self.unread.get(kernel, frozenset())

    @property
    def called(self) -> frozenset[str]:
        """Every kernel some step calls."""
        return frozenset().union(*self.calls.values())

    def controller_context(self, controller: str, kernels_h: str) -> dict[str, object]:
        """What ``controller.{h,c}.jinja`` need of the kernels of ``controller``'s step: the
        shared header's include, its kept kernels (state and ``_init``), and whether its
        (17) still takes the span (a kernel that did not keep 1/span)."""
        called = self.calls[controller]
        mine = [k for k in self.kept if k.name in called]
        span_kept = [k.name for k in mine if "span" in k.fixed]
        tde_called = {k for k in called if k.endswith(("_tde", "_tde_trig"))}
        return {
            "step_kernels": f'#include "{kernels_h}"' if called else "",
            "kept_kernels": [{"name": k.name, "size": k.size, "keep": k.keep["name"],
                              "fixed": list(k.fixed)} for k in mine],
            "span_kept": span_kept,
            "span_needed": bool(tde_called - set(span_kept)),
        }


def step_kernels(controllers: Iterable[ControllerSpec], layout: ControllerLayout,
                 functions: Sequence[FunctionIR], module: str, kp: str,
                 config: CConfig) -> StepKernels:
    """The kernels of ``module`` that the steps of ``controllers`` call as ``<kp><kernel>``,
    in the module's order, each once as a ``static inline`` function for the shared header
    every controller includes: its step then calls functions of its own translation unit,
    which the compiler inlines and schedules with the step.

    A kernel with parameter-only subexpressions is split at its parameters
    (:func:`kept_kernel`): ``<kp><kernel>_keep``, which a controller's ``_init`` calls to
    keep those values in the state, and ``<kp><kernel>``, the per-step rest reading them
    (a frozen build never calls ``_keep``: static inline, it is not compiled then)."""
    calls = {info.name: step_calls(info, layout) for info in controllers}
    called = frozenset().union(*calls.values())
    by_name = {f.spec.name: f for f in functions}
    unknown = called - set(by_name)
    if unknown:
        raise ValueError(f"{module}: the steps call {sorted(unknown)}, not kernels of it")
    contexts: list[dict[str, object]] = []
    kept: list[KeptKernel] = []
    unread: dict[str, frozenset[str]] = {}
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
            unread[f.spec.name] = _unread(split.call)
            continue
        ctx = function_context(f, config, module)
        unread[f.spec.name] = _unread(ctx)
        ctx["origin"] = f"the body of {ctx['name']}"
        ctx["name"] = f"{kp}{f.spec.name}"
        ctx["unless"] = ""
        contexts.append(ctx)
    return StepKernels(calls, tuple(contexts), tuple(kept), context_norms(contexts), unread)


def _unread(ctx: dict[str, object]) -> frozenset[str]:
    """The inputs a lowered body does not read (its ``(void)`` lines)."""
    body = ctx["body"]
    assert isinstance(body, list)
    return frozenset(line.target for line in body if isinstance(line, Line) and line.kind == "void")


def law_wrappers(functions: Sequence[FunctionIR], kernels: StepKernels, kp: str,
                 config: CConfig) -> dict[str, list[str]]:
    """The body of each laws function the steps call as ``<kp><kernel>``: a call of that
    kernel, or, split, its ``_keep`` into a local then the per-step part (the steps'
    rounding: e.g. 1/span kept, then a product)."""
    split = {k.name: k for k in kernels.kept}
    out: dict[str, list[str]] = {}
    for f in functions:
        spec = f.spec
        if spec.name not in kernels.called:
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
