"""Running one bad-input case on one controller and formulation through cffi (the double
build), with a twin controller that never sees the bad input, and checking each outcome
against the case's documented expectation.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from runtime.bindings import cbuild
from runtime.bindings.controller import Controller as CController
from runtime.bindings.generated import controllers as mirror
from runtime.tooling.bad_input.cases import (
    BASE,
    CONTROLLER_FORMULATIONS,
    CONTROLLERS,
    DRISHTI,
    FORMULATIONS,
    SATURATION_LIMIT,
    SENTINEL,
    WARMUP,
    ZERO_ERROR_STEPS,
    Case,
    cases,
    max_window,
)


@dataclass(frozen=True)
class Outcome:
    case: Case
    controller: str
    formulation: str
    status: int
    state_unchanged: bool
    tau_unchanged: bool | None  # None: tau was NULL
    init_status: int | None = None
    init_untouched: bool | None = None
    check_status: int | None = None
    twin_equal: bool | None = None  # None: no twin comparison for this kind
    detail: tuple[str, int] | None = None  # (field name, index) from _step_detail
    extra: dict[str, Any] = field(default_factory=dict)


def status_names(lib: cbuild.CLibrary) -> dict[int, str]:
    """value → name of ``wmr_status_t``, read from the C declarations."""
    return dict(lib.ffi.typeof("wmr_status_t").elements)


def field_names(lib: cbuild.CLibrary) -> dict[int, str]:
    """value → name of ``wmr_field_t``, read from the C declarations."""
    return dict(lib.ffi.typeof("wmr_field_t").elements)


def status_values(lib: cbuild.CLibrary) -> dict[str, int]:
    return {v: k for k, v in status_names(lib).items()}


def base_config(lib: cbuild.CLibrary, name: str, formulation: str, **changes: Any) -> Any:
    """``wmr_<name>_config_t`` for Drishti's nominal model and :data:`BASE` gains."""
    ffi = lib.ffi
    ctype = f"wmr_{name}_config_t"
    cfg = ffi.new(f"{ctype} *")
    cfg.nominal = cbuild.params_struct(lib, DRISHTI)[0]
    cfg.formulation = FORMULATIONS[formulation]
    values = {**BASE, **changes}
    for fname, _ in ffi.typeof(ctype).fields:
        if fname in ("nominal", "formulation"):
            continue
        value = values[fname]
        setattr(cfg, fname, list(value) if isinstance(value, tuple) else value)
    return cfg


def copy_config(lib: cbuild.CLibrary, name: str, cfg: Any) -> Any:
    ffi = lib.ffi
    out = ffi.new(f"wmr_{name}_config_t *")
    ffi.memmove(out, cfg, ffi.sizeof(out[0]))
    return out


def smooth_sequence(steps: int, h: float, seed: int = 3) -> list[tuple[list[float], ...]]:
    """(q, qdot, q_des, qdot_des, qddot_des) per step: a smooth motion and a reference a
    small smooth offset from it."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.05, 0.3, 5)
    w = rng.uniform(0.5, 2.0, 5)
    drift = np.array([0.3, 0.1, 0.05, 2.0, 1.5])
    seq = []
    for k in range(steps):
        t = k * h
        q = drift * t + amp * np.sin(w * t)
        qd = drift + amp * w * np.cos(w * t)
        e = 0.05 * np.sin(w * t + 1.0)
        ed = 0.05 * w * np.cos(w * t + 1.0)
        edd = -0.05 * w**2 * np.sin(w * t + 1.0)
        seq.append(tuple(list(map(float, v)) for v in (q, qd, q + e, qd + ed, edd)))
    return seq


class Controller:
    """A controller instance of the bad-input cases (Drishti's ``wmr_`` code): the bindings'
    wrapper (:class:`runtime.bindings.controller.Controller`), initialised at once, whose
    step takes the five inputs, returns (status, τ) and may write τ elsewhere."""

    def __init__(self, lib: cbuild.CLibrary, name: str, cfg: Any) -> None:
        self.lib, self.name, self.cfg = lib, name, cfg
        self.c = CController(lib, "wmr", name, cfg, 5, 2)
        self.state = self.c.state
        status = self.c.init()
        if status != 0:
            raise RuntimeError(f"{name}: init failed with {status}")

    def step(
        self, inputs: Iterable[list[float]], cfg: Any = None, tau: Any = None,
        detail: Any = None,
    ) -> tuple[int, list[float]]:
        """One step; with ``detail`` (a ``wmr_error_detail_t *``) through ``_step_detail``."""
        out = self.c.tau if tau is None else tau
        status = self.c.step([list(v) for v in inputs], cfg, detail, out)
        return status, [float(out[0]), float(out[1])]

    def raw(self) -> bytes:
        return self.c.raw()

    def fields(self) -> Any:
        return to_python(self.lib.ffi, self.state[0])


def to_python(ffi: Any, value: Any) -> Any:
    """A cffi struct/array as nested dicts and lists (padding bytes ignored)."""
    if not isinstance(value, ffi.CData):
        return value
    t = ffi.typeof(value)
    if t.kind == "array":
        return [to_python(ffi, v) for v in value]
    if t.kind == "struct":
        return {f: to_python(ffi, getattr(value, f)) for f, _ in t.fields}
    raise TypeError(t)


def _pattern_state(lib: cbuild.CLibrary, name: str, byte: bytes) -> Any:
    ffi = lib.ffi
    state = ffi.new(f"wmr_{name}_state_t *")
    ffi.memmove(state, byte * ffi.sizeof(state[0]), ffi.sizeof(state[0]))
    return state


def run_case(lib: cbuild.CLibrary, name: str, formulation: str, case: Case) -> Outcome:
    """Run one case on one controller and formulation; see the module docstring."""
    ffi, clib = lib.ffi, lib.lib
    step_fn = getattr(clib, f"wmr_{name}_step_detail")
    reset_fn = getattr(clib, f"wmr_{name}_reset")
    fields = field_names(lib)
    detail = ffi.new("wmr_error_detail_t *", {"status": 99, "field": 99, "index": 99})

    def detail_of(status: int) -> tuple[str, int] | None:
        """The detail written, if it agrees with the status returned (else None)."""
        if int(detail.status) != status:
            return None
        return fields.get(int(detail.field), "?"), int(detail.index)

    init_fn = getattr(clib, f"wmr_{name}_init")
    check_fn = getattr(clib, f"wmr_{name}_check_config")
    cfg = base_config(lib, name, formulation)
    seq = smooth_sequence(WARMUP + 1, float(BASE["h"]))

    def outcome(status: int, **kw: Any) -> Outcome:
        return Outcome(case, name, formulation, status, **kw)

    if case.kind == "saturate":
        big = ([0.0] * 5, [0.0] * 5, [0.8] * 5, [1.0] * 5, [2.0] * 5)
        free = Controller(lib, name, base_config(lib, name, formulation, tau_max=1e5))
        clipped = Controller(lib, name, base_config(lib, name, formulation, tau_max=0.5))
        s_free, tau_free = free.step(big)
        status, tau = clipped.step(big)
        expect = [min(max(x, -SATURATION_LIMIT), SATURATION_LIMIT) for x in tau_free]
        ok = (
            s_free == 0
            and max(abs(x) for x in tau_free) > SATURATION_LIMIT
            and tau == expect
            and list(clipped.state.tau) == tau
            and clipped.state.steps == 1
        )
        return outcome(
            status, state_unchanged=False, tau_unchanged=False, extra={"clipped_correctly": ok}
        )

    if case.kind == "zero-error":
        return _zero_error(lib, name, formulation, case)

    bad, twin = Controller(lib, name, cfg), Controller(lib, name, cfg)
    for inputs in seq[:WARMUP]:
        bad.step(inputs)
        twin.step(inputs)
    good = seq[WARMUP]

    if case.kind == "reset":
        fresh = Controller(lib, name, cfg)
        status = int(reset_fn(bad.state))
        return outcome(
            status,
            state_unchanged=False,
            tau_unchanged=None,
            twin_equal=_twin_equal(bad, fresh, good),
            extra={"reset_equals_init": bad.fields() == fresh.fields()},
        )

    if case.kind == "init-null":
        before = bad.raw()
        if case.null_arg == 0:
            status = int(init_fn(ffi.NULL, cfg))
        elif case.null_arg == 1:
            status = int(init_fn(bad.state, ffi.NULL))
        elif case.null_arg == 2:
            status = int(reset_fn(ffi.NULL))
        else:
            status = int(check_fn(ffi.NULL))
        return outcome(
            status,
            state_unchanged=bad.raw() == before,
            tau_unchanged=None,
            twin_equal=_twin_equal(bad, twin, good),
        )

    if case.kind == "state":
        if case.fill is None:
            bad.state.magic = bad.state.magic ^ 0x1
        else:
            ffi.memmove(bad.state, case.fill * ffi.sizeof(bad.state[0]), ffi.sizeof(bad.state[0]))
        before = bad.raw()
        tau = ffi.new("wmr_real_t[2]", list(SENTINEL))
        status, tau_after = bad.step(good, tau=tau, detail=detail)
        return outcome(
            status, state_unchanged=bad.raw() == before, tau_unchanged=tau_after == list(SENTINEL),
            detail=detail_of(status),
        )

    if case.kind == "corrupt":
        assert case.flip is not None
        path, bit = case.flip
        at = ffi.offsetof(f"wmr_{name}_state_t", *path) + bit // 8  # a little-endian host
        raw = ffi.cast("unsigned char *", bad.state)
        raw[at] ^= 1 << (bit % 8)
        before = bad.raw()
        tau = ffi.new("wmr_real_t[2]", list(SENTINEL))
        status, tau_after = bad.step(good, tau=tau, detail=detail)
        unchanged = bad.raw() == before
        raw[at] ^= 1 << (bit % 8)  # restored: the refused step must have written nothing
        return outcome(
            status, state_unchanged=unchanged, tau_unchanged=tau_after == list(SENTINEL),
            twin_equal=_twin_equal(bad, twin, good), detail=detail_of(status),
        )

    step_cfg = cfg
    init_status = init_untouched = check_status = None
    step_inputs = [list(v) for v in good]
    if case.kind == "input":
        assert case.inputs is not None
        which, index, value = case.inputs
        step_inputs[which][index] = value
    elif case.kind == "config":
        assert case.mutate is not None
        step_cfg = copy_config(lib, name, cfg)
        case.mutate(step_cfg)
        fresh = _pattern_state(lib, name, b"\xab")
        pattern = bytes(ffi.buffer(fresh))
        init_status = int(init_fn(fresh, step_cfg))
        init_untouched = bytes(ffi.buffer(fresh)) == pattern
        check_status = int(check_fn(step_cfg))
    elif case.kind == "changed":
        assert case.mutate is not None
        step_cfg = copy_config(lib, name, cfg)
        case.mutate(step_cfg)
        fresh = _pattern_state(lib, name, b"\xab")
        init_status = int(init_fn(fresh, step_cfg))  # valid: _init takes it
        init_untouched = init_status == 0
        check_status = int(check_fn(step_cfg))

    before = bad.raw()
    tau = ffi.new("wmr_real_t[2]", list(SENTINEL))
    if case.kind == "null":
        args = [bad.state, step_cfg, *[ffi.new("wmr_real_t[5]", v) for v in step_inputs], tau]
        assert case.null_arg is not None
        args[case.null_arg] = ffi.NULL
        status = int(step_fn(*args, detail))
        tau_unchanged: bool | None = (
            None if case.null_arg == len(args) - 1 else list(tau) == list(SENTINEL)
        )
    else:
        status, tau_after = bad.step(step_inputs, cfg=step_cfg, tau=tau, detail=detail)
        tau_unchanged = tau_after == list(SENTINEL)
    return outcome(
        status,
        state_unchanged=bad.raw() == before,
        tau_unchanged=tau_unchanged,
        init_status=init_status,
        init_untouched=init_untouched,
        check_status=check_status,
        twin_equal=_twin_equal(bad, twin, good),
        detail=detail_of(status),
    )


GAIN_MIN = float(mirror.GAIN_MIN)  # WMR_GAIN_MIN (a real macro: cffi does not read it)


def _zero_error(lib: cbuild.CLibrary, name: str, formulation: str, case: Case) -> Outcome:
    """A measured motion equal to its reference (e = 0, edot = 0 exactly) for
    ZERO_ERROR_STEPS steps at the smallest eps, a switching gain > 0 throughout: every step
    must succeed (with k / eps * 0 it returned NONFINITE_OUTPUT, and kept doing so)."""
    changes: dict[str, Any] = {"eps": GAIN_MIN, "hold_gain": 1, "held_gain": 1.0}
    ctl = Controller(lib, name, base_config(lib, name, formulation, **changes))
    statuses = []
    for q, qdot, _, _, qddot in smooth_sequence(ZERO_ERROR_STEPS, float(BASE["h"])):
        status, tau = ctl.step((q, qdot, q, qdot, qddot))
        statuses.append(status if all(x == x for x in tau) else -99)
    worst = min(statuses, key=lambda s: (s >= 0, s))
    return Outcome(case, name, formulation, worst, state_unchanged=False, tau_unchanged=False,
                   extra={"steps_ok": sum(s >= 0 for s in statuses),
                          "gain": float(ctl.state.gain)})


def _twin_equal(bad: Controller, twin: Controller, good: tuple[list[float], ...]) -> bool:
    s_bad, tau_bad = bad.step(good)
    s_twin, tau_twin = twin.step(good)
    return s_bad == s_twin and s_bad >= 0 and tau_bad == tau_twin and bad.fields() == twin.fields()


def run_all(lib: cbuild.CLibrary | None = None) -> list[Outcome]:
    lib = cbuild.build(False) if lib is None else lib
    return [
        run_case(lib, name, form, case)
        for case in cases(max_window(lib))
        for name in CONTROLLERS
        if name in case.applies
        for form in FORMULATIONS
        if form in CONTROLLER_FORMULATIONS[name]
    ]


def failures(outcomes: list[Outcome], lib: cbuild.CLibrary) -> list[str]:
    """Every expectation an outcome misses (empty: all as documented)."""
    values = status_values(lib)
    bad = []
    for o in outcomes:
        c = o.case
        where = f"{o.controller}/{o.formulation} {c.id}"
        code = values[c.expected]
        if o.status != code:
            bad.append(f"{where}: status {o.status}, expected {c.expected} ({code})")
        if c.kind == "saturate":
            if not o.extra.get("clipped_correctly"):
                bad.append(f"{where}: torque not clipped to the limit")
            continue
        if c.kind == "zero-error":
            if o.extra.get("steps_ok") != ZERO_ERROR_STEPS:
                bad.append(f"{where}: {o.extra.get('steps_ok')} of {ZERO_ERROR_STEPS} "
                           "zero-error steps succeeded")
            continue
        if c.kind == "reset":
            if not o.extra.get("reset_equals_init") or not o.twin_equal:
                bad.append(f"{where}: _reset is not the state _init leaves")
            continue
        if c.kind in ("input", "config", "changed", "state", "corrupt", "null") \
                and o.detail is None:
            bad.append(f"{where}: _step_detail did not report the status it returned")
        if c.kind == "input" and c.inputs is not None and o.detail is not None \
                and o.detail[1] != c.inputs[1]:
                bad.append(f"{where}: detail index {o.detail[1]}, expected {c.inputs[1]}")
        if not o.state_unchanged:
            bad.append(f"{where}: state bytes changed")
        if o.tau_unchanged is False:
            bad.append(f"{where}: tau changed")
        if c.kind == "changed" and (o.init_status != 0 or o.check_status != 0):
            bad.append(f"{where}: the changed config is valid, init/check must accept it")
        if c.kind == "config":
            if o.init_status != code or o.check_status != code:
                bad.append(f"{where}: init {o.init_status}, check_config {o.check_status}")
            if not o.init_untouched:
                bad.append(f"{where}: init with a bad config wrote the state")
        if o.twin_equal is False:
            bad.append(f"{where}: next valid step differs from the twin's")
    return bad
