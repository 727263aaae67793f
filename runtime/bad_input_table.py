"""Every bad input tried on the generated C controllers, and what each one did.

``python -m runtime.bad_input_table`` runs all cases on the double build of
``generated/c`` (through cffi) and writes ``docs/BAD_INPUT.md``; ``--check`` exits 1 if
the committed file differs. ``tests/test_firmware_bad_input.py`` runs the same cases,
asserts each expectation and that the committed document equals :func:`render`'s output,
so the table cannot drift from the code.

A case runs on every controller it applies to, in both formulations. Each run: two
controllers with the same configuration take the same ``WARMUP`` valid steps; one then
gets the bad input (τ pre-filled with a sentinel). Recorded: the status, whether the
state's bytes and τ are unchanged, for a bad configuration also ``_init`` (on a
pattern-filled state) and ``_check_config``, and whether the next valid step (status,
τ and every state field) equals the twin's, which never saw the bad input.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime import cbuild

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "BAD_INPUT.md"
CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")
FORMULATIONS = {"paper": 0, "minimal": 1}
INPUT_NAMES = ("q", "qdot", "q_des", "qdot_des", "qddot_des")
WARMUP = 5
SENTINEL = (111.0, -222.0)
# Which controllers have which configuration fields.
SWITCHING = ("tdroc", "roc", "asmc")
TDE = ("tdc", "tdroc")
DRISHTI = {"m": 36.0, "I": 5.72, "K": 0.34, "Iw": 0.07, "r": 0.096, "b": 0.414, "d": 0.12}
BASE: dict[str, Any] = {
    "k1": (4.0, 5.0, 6.0, 7.0, 8.0),
    "k2": (3.0, 3.5, 4.0, 4.5, 5.0),
    "q_pos": 1.5,
    "q_vel": 0.8,
    "h": 0.01,
    "tau_max": 200.0,
    "accel_estimator": 2,
    "rate_window": 0.005,
    "hold_gain": 0,
    "held_gain": 0.0,
    "eps": 0.05,
    "n": 4,
    "a": 0.8,
    "alpha": 0.3,
    "phi": 2.0,
    "gamma": 2.0,
    "gain0": 0.5,
}
SATURATION_LIMIT = 0.5


@dataclass(frozen=True)
class Case:
    """One bad input. ``row`` groups cases into one line of the table."""

    row: str
    kind: str  # input | config | state | null | init-null | saturate
    expected: str
    applies: tuple[str, ...] = CONTROLLERS
    inputs: tuple[int, int, float] | None = None  # (which input, index, value)
    mutate: Callable[[Any], None] | None = None  # changes a copy of the configuration
    fill: bytes | None = None  # state cases: bytes the state is filled with (None: magic only)
    null_arg: int | None = None  # null cases: which argument of step is NULL
    id: str = ""


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
    extra: dict[str, Any] = field(default_factory=dict)


def _set(name: str, value: Any) -> Callable[[Any], None]:
    def mutate(cfg: Any) -> None:
        setattr(cfg, name, value)

    return mutate


def _set_item(name: str, index: int, value: float) -> Callable[[Any], None]:
    def mutate(cfg: Any) -> None:
        getattr(cfg, name)[index] = value

    return mutate


def _nominal(**changes: float) -> Callable[[Any], None]:
    def mutate(cfg: Any) -> None:
        cbuild.fill_params(cfg.nominal, changes)

    return mutate


def max_window(lib: cbuild.CLibrary) -> int:
    """WMR_MAX_WINDOW, read from the C state (omega has WMR_MAX_WINDOW + 1 rows)."""
    fields = dict(lib.ffi.typeof("wmr_tdroc_state_t").fields)
    return int(fields["omega"].type.length) - 1


def cases(max_win: int) -> list[Case]:
    """Every bad input, in the order of the table."""
    out: list[Case] = []
    for which, label in enumerate(INPUT_NAMES):
        status = "WMR_ERR_BAD_MEASUREMENT" if which < 2 else "WMR_ERR_BAD_REFERENCE"
        bad_values = (
            ("NaN", math.nan),
            ("+Inf", math.inf),
            ("-Inf", -math.inf),
            ("1e9", 1e9),
            ("-1e9", -1e9),
        )
        for text, value in bad_values:
            for index in range(5):
                out.append(
                    Case(
                        f"`{label}[i]` = {text}",
                        "input",
                        status,
                        inputs=(which, index, value),
                        id=f"{label}[{index}]={text}",
                    )
                )
    k2m = DRISHTI["K"] ** 2 / DRISHTI["m"]
    config: list[tuple[str, str, Callable[[Any], None], tuple[str, ...]]] = [
        ("`eps` = 0", "WMR_ERR_BAD_EPS", _set("eps", 0.0), SWITCHING),
        ("`eps` = -0.1", "WMR_ERR_BAD_EPS", _set("eps", -0.1), SWITCHING),
        ("`eps` = NaN", "WMR_ERR_BAD_EPS", _set("eps", math.nan), SWITCHING),
        ("`n` = 1", "WMR_ERR_BAD_WINDOW", _set("n", 1), ("tdroc",)),
        (
            f"`n` = WMR_MAX_WINDOW + 1 = {max_win + 1}",
            "WMR_ERR_BAD_WINDOW",
            _set("n", max_win + 1),
            ("tdroc",),
        ),
        ("`a` = 0", "WMR_ERR_BAD_DISCOUNT", _set("a", 0.0), ("tdroc",)),
        ("`a` = 1.5", "WMR_ERR_BAD_DISCOUNT", _set("a", 1.5), ("tdroc",)),
        ("`a` = NaN", "WMR_ERR_BAD_DISCOUNT", _set("a", math.nan), ("tdroc",)),
        ("`h` = 0", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", 0.0), CONTROLLERS),
        ("`h` = -0.01", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", -0.01), CONTROLLERS),
        ("`h` = NaN", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", math.nan), CONTROLLERS),
        ("`h` = +Inf", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", math.inf), CONTROLLERS),
        ("`k1[1]` = 0", "WMR_ERR_BAD_GAINS", _set_item("k1", 1, 0.0), CONTROLLERS),
        ("`k1[3]` = -4", "WMR_ERR_BAD_GAINS", _set_item("k1", 3, -4.0), CONTROLLERS),
        ("`k2[4]` = -5", "WMR_ERR_BAD_GAINS", _set_item("k2", 4, -5.0), CONTROLLERS),
        ("`k2[0]` = NaN", "WMR_ERR_BAD_GAINS", _set_item("k2", 0, math.nan), CONTROLLERS),
        ("Q: `q_pos` = 0", "WMR_ERR_BAD_GAINS", _set("q_pos", 0.0), CONTROLLERS),
        ("Q: `q_vel` = -1", "WMR_ERR_BAD_GAINS", _set("q_vel", -1.0), CONTROLLERS),
        ("nominal `m` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(m=0.0), CONTROLLERS),
        ("nominal `m` = -36", "WMR_ERR_BAD_NOMINAL", _nominal(m=-36.0), CONTROLLERS),
        ("nominal `K` = NaN", "WMR_ERR_BAD_NOMINAL", _nominal(K=math.nan), CONTROLLERS),
        (
            "nominal `I` = K²/m (M-hat singular)",
            "WMR_ERR_BAD_NOMINAL",
            _nominal(I=k2m),
            CONTROLLERS,
        ),
        (
            "nominal `I` = K²/(2m) (M-hat not positive definite)",
            "WMR_ERR_BAD_NOMINAL",
            _nominal(I=0.5 * k2m),
            CONTROLLERS,
        ),
        ("nominal `Iw` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(Iw=0.0), CONTROLLERS),
        ("nominal `b` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(b=0.0), CONTROLLERS),
        ("nominal `r` = +Inf", "WMR_ERR_BAD_NOMINAL", _nominal(r=math.inf), CONTROLLERS),
        ("`tau_max` = 0", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", 0.0), CONTROLLERS),
        ("`tau_max` = -5", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", -5.0), CONTROLLERS),
        ("`tau_max` = NaN", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", math.nan), CONTROLLERS),
        ("`tau_max` = +Inf", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", math.inf), CONTROLLERS),
        ("`formulation` = 2", "WMR_ERR_BAD_FORMULATION", _set("formulation", 2), CONTROLLERS),
        ("`formulation` = -1", "WMR_ERR_BAD_FORMULATION", _set("formulation", -1), CONTROLLERS),
        ("`accel_estimator` = -1", "WMR_ERR_BAD_ESTIMATOR", _set("accel_estimator", -1), TDE),
        ("`accel_estimator` = 3", "WMR_ERR_BAD_ESTIMATOR", _set("accel_estimator", 3), TDE),
        ("`rate_window` = -0.001", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", -0.001), TDE),
        ("`rate_window` > h", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", 0.02), TDE),
        ("`rate_window` = NaN", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", math.nan), TDE),
        ("TDROC `hold_gain` = 2", "WMR_ERR_BAD_HELD_GAIN", _set("hold_gain", 2), ("tdroc",)),
        ("TDROC `held_gain` = -1", "WMR_ERR_BAD_HELD_GAIN", _set("held_gain", -1.0), ("tdroc",)),
        (
            "TDROC `held_gain` = NaN",
            "WMR_ERR_BAD_HELD_GAIN",
            _set("held_gain", math.nan),
            ("tdroc",),
        ),
        ("ROC `alpha` = 1", "WMR_ERR_BAD_BOUNDS", _set("alpha", 1.0), ("roc",)),
        ("ROC `alpha` = -0.1", "WMR_ERR_BAD_BOUNDS", _set("alpha", -0.1), ("roc",)),
        ("ROC `phi` = -1", "WMR_ERR_BAD_BOUNDS", _set("phi", -1.0), ("roc",)),
        ("ROC `phi` = NaN", "WMR_ERR_BAD_BOUNDS", _set("phi", math.nan), ("roc",)),
        ("ASMC `gamma` = -1", "WMR_ERR_BAD_BOUNDS", _set("gamma", -1.0), ("asmc",)),
        ("ASMC `gain0` = -1", "WMR_ERR_BAD_BOUNDS", _set("gain0", -1.0), ("asmc",)),
    ]
    for row, status, mutate, applies in config:
        out.append(Case(row, "config", status, applies, mutate=mutate, id=row))
    for row, fill in (
        ("state never initialised (zero-filled)", b"\x00"),
        ("state never initialised (filled with 0x5a)", b"\x5a"),
        ("initialised state with `magic` overwritten", None),
    ):
        out.append(Case(row, "state", "WMR_ERR_NOT_INITIALISED", fill=fill, id=row))
    step_args = ("state", "config", *INPUT_NAMES, "tau")
    for index, arg in enumerate(step_args):
        out.append(
            Case(
                f"`{arg}` = NULL in `_step`",
                "null",
                "WMR_ERR_NULL_POINTER",
                null_arg=index,
                id=f"step:{arg}=NULL",
            )
        )
    for index, arg in enumerate(("state", "config")):
        out.append(
            Case(
                f"`{arg}` = NULL in `_init`",
                "init-null",
                "WMR_ERR_NULL_POINTER",
                null_arg=index,
                id=f"init:{arg}=NULL",
            )
        )
    out.append(
        Case("`config` = NULL in `_check_config`", "init-null", "WMR_ERR_NULL_POINTER", id="check")
    )
    out.append(
        Case(
            f"torque beyond `tau_max` = {SATURATION_LIMIT}",
            "saturate",
            "WMR_WARN_SATURATED",
            id="saturate",
        )
    )
    return out


# --------------------------------------------------------------------------- running
def status_names(lib: cbuild.CLibrary) -> dict[int, str]:
    """value → name of ``wmr_status_t``, read from the C declarations."""
    return dict(lib.ffi.typeof("wmr_status_t").elements)


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
    """A controller instance through cffi: caller-owned state, init, step."""

    def __init__(self, lib: cbuild.CLibrary, name: str, cfg: Any) -> None:
        self.lib, self.name, self.cfg = lib, name, cfg
        self.state = lib.ffi.new(f"wmr_{name}_state_t *")
        status = getattr(lib.lib, f"wmr_{name}_init")(self.state, cfg)
        if status != 0:
            raise RuntimeError(f"{name}: init failed with {status}")

    def step(
        self, inputs: Iterable[list[float]], cfg: Any = None, tau: Any = None
    ) -> tuple[int, list[float]]:
        ffi = self.lib.ffi
        tau = ffi.new("wmr_real_t[2]") if tau is None else tau
        arrays = [ffi.new("wmr_real_t[5]", list(v)) for v in inputs]
        fn = getattr(self.lib.lib, f"wmr_{self.name}_step")
        status = fn(self.state, self.cfg if cfg is None else cfg, *arrays, tau)
        return int(status), [float(tau[0]), float(tau[1])]

    def raw(self) -> bytes:
        return bytes(self.lib.ffi.buffer(self.state))

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
    step_fn = getattr(clib, f"wmr_{name}_step")
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

    bad, twin = Controller(lib, name, cfg), Controller(lib, name, cfg)
    for inputs in seq[:WARMUP]:
        bad.step(inputs)
        twin.step(inputs)
    good = seq[WARMUP]

    if case.kind == "init-null":
        before = bad.raw()
        if case.null_arg == 0:
            status = int(init_fn(ffi.NULL, cfg))
        elif case.null_arg == 1:
            status = int(init_fn(bad.state, ffi.NULL))
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
        status, tau_after = bad.step(good, tau=tau)
        return outcome(
            status, state_unchanged=bad.raw() == before, tau_unchanged=tau_after == list(SENTINEL)
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

    before = bad.raw()
    tau = ffi.new("wmr_real_t[2]", list(SENTINEL))
    if case.kind == "null":
        args = [bad.state, step_cfg, *[ffi.new("wmr_real_t[5]", v) for v in step_inputs], tau]
        assert case.null_arg is not None
        args[case.null_arg] = ffi.NULL
        status = int(step_fn(*args))
        tau_unchanged: bool | None = (
            None if case.null_arg == len(args) - 1 else list(tau) == list(SENTINEL)
        )
    else:
        status, tau_after = bad.step(step_inputs, cfg=step_cfg, tau=tau)
        tau_unchanged = tau_after == list(SENTINEL)
    return outcome(
        status,
        state_unchanged=bad.raw() == before,
        tau_unchanged=tau_unchanged,
        init_status=init_status,
        init_untouched=init_untouched,
        check_status=check_status,
        twin_equal=_twin_equal(bad, twin, good),
    )


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
        if not o.state_unchanged:
            bad.append(f"{where}: state bytes changed")
        if o.tau_unchanged is False:
            bad.append(f"{where}: tau changed")
        if c.kind == "config":
            if o.init_status != code or o.check_status != code:
                bad.append(f"{where}: init {o.init_status}, check_config {o.check_status}")
            if not o.init_untouched:
                bad.append(f"{where}: init with a bad config wrote the state")
        if o.twin_equal is False:
            bad.append(f"{where}: next valid step differs from the twin's")
    return bad


# --------------------------------------------------------------------------- document
def _controllers_label(names: Iterable[str]) -> str:
    names = list(dict.fromkeys(names))
    return "all four" if len(names) == len(CONTROLLERS) else ", ".join(n.upper() for n in names)


def _yes(flags: list[bool | None]) -> str:
    known = [f for f in flags if f is not None]
    if not known:
        return "n/a"
    return "yes" if all(known) else f"**no** ({known.count(False)} of {len(known)})"


def render(outcomes: list[Outcome], names: dict[int, str], alpha_rows: list[list[str]]) -> str:
    """docs/BAD_INPUT.md from the outcomes (and the TDE-condition rows)."""
    rows: dict[str, list[Outcome]] = {}
    for o in outcomes:
        rows.setdefault(o.case.row, []).append(o)
    lines = [
        "# Bad input to the generated controllers",
        "",
        "Generated by `python -m runtime.bad_input_table` from the double build of",
        "`generated/c` (do not edit: `tests/test_firmware_bad_input.py` fails if this file",
        "differs from the script's output).",
        "",
        "Each row ran on the listed controllers in both formulations (paper, minimal); input",
        "rows also on each of the 5 entries of the vector. Before the bad call, the controller",
        f"took {WARMUP} valid steps (Drishti's nominal model, K1 = diag(4..8),",
        "K2 = diag(3..5), Q = diag(1.5, 0.8), h = 0.01 s, tau_max = 200 N m, eps = 0.05,",
        "n = 4, a = 0.8, alpha = 0.3, phi = 2, gamma = 2, gain0 = 0.5); tau held a sentinel.",
        "",
        "* **status**: what `wmr_<ctrl>_step` returned, name (value), every run;",
        "* **state, tau untouched**: the state's bytes (`ffi.buffer`) and tau are unchanged;",
        "* **init/check**: for a bad configuration, `wmr_<ctrl>_init` (on a state filled with",
        "  0xab) and `wmr_<ctrl>_check_config` return the same code and init writes nothing;",
        "* **next step = twin**: the next valid step (status, tau, every state field) equals",
        "  that of a second controller that never saw the bad input.",
        "",
        "| bad input | controllers | runs | status | state, tau untouched | init/check | "
        "next step = twin |",
        "|---|---|---|---|---|---|---|",
    ]
    for row, group in rows.items():
        statuses = sorted({o.status for o in group}, key=lambda s: -s)
        status = " / ".join(f"`{names.get(s, '?')}` ({s})" for s in statuses)
        kind = group[0].case.kind
        if kind == "saturate":
            untouched = "clipped to ±tau_max, step committed"
            twin = "n/a"
        else:
            flags: list[bool | None] = [o.state_unchanged for o in group]
            flags += [o.tau_unchanged for o in group]
            untouched = _yes(flags)
            twin = _yes([o.twin_equal for o in group])
        if kind == "config":
            init_check = _yes(
                [o.init_status == o.status == o.check_status and o.init_untouched for o in group]
            )
        else:
            init_check = "n/a"
        ctrls = _controllers_label(o.controller for o in group)
        lines.append(
            f"| {row} | {ctrls} | {len(group)} | {status} | {untouched} | {init_check} | {twin} |"
        )
    lines += [
        "",
        "Inputs are checked before anything is computed: a measurement (q, qdot) or a",
        "reference (q_des, qdot_des, qddot_des) that is NaN, infinite or larger than 1e6 in",
        "magnitude is rejected (`WMR_ERR_BAD_MEASUREMENT` / `WMR_ERR_BAD_REFERENCE`); the",
        "configuration is re-validated on every step, so a configuration corrupted after",
        "`_init` is caught too. A step works on a copy of the state and commits it only on",
        "success.",
        "",
        "## The time-delay estimation condition over a parameter box",
        "",
        "`runtime.nominal_check.check_nominal(nominal, box)` computes",
        "alpha = max ||M^-1 M-hat - I||_2 over true robots whose m, I, K and Iw are each within",
        "±box of Drishti's (a 3-level grid of the box × 9 headings) and raises `ValueError` when",
        "alpha >= 1, the condition (17) needs. `checked_controller_config` applies it when a",
        "TDC/TDROC configuration is built. A nominal model that is too light keeps alpha",
        "below 1 (the estimate still converges, more slowly); one that is too heavy fails.",
        "",
        "| nominal model | box | alpha (paper) | alpha (minimal) | check_nominal |",
        "|---|---|---|---|---|",
        *("| " + " | ".join(r) + " |" for r in alpha_rows),
        "",
    ]
    return "\n".join(lines)


NOMINAL_VARIANTS: tuple[tuple[str, dict[str, float]], ...] = (
    ("Drishti (exact)", {}),
    ("m, I, K × 1.3", {"m": 1.3, "I": 1.3, "K": 1.3}),
    ("m, I, K × 1.5", {"m": 1.5, "I": 1.5, "K": 1.5}),
    ("m, I, K × 3 (3× too heavy)", {"m": 3.0, "I": 3.0, "K": 3.0}),
    ("m, I, K × 0.5", {"m": 0.5, "I": 0.5, "K": 0.5}),
    ("m, I, K × 0.2", {"m": 0.2, "I": 0.2, "K": 0.2}),
)


def alpha_rows(box: float = 0.3) -> list[list[str]]:
    """The TDE-condition table: α for scaled nominal models against Drishti ± box."""
    from runtime.nominal_check import check_nominal, tde_alpha

    rows = []
    for label, scale in NOMINAL_VARIANTS:
        nominal = {k: v * scale.get(k, 1.0) for k, v in DRISHTI.items()}
        alphas = [
            tde_alpha(nominal, box, true_params=DRISHTI, formulation=f)[0] for f in FORMULATIONS
        ]
        try:
            for f in FORMULATIONS:
                check_nominal(nominal, box, true_params=DRISHTI, formulation=f)
            verdict = "accepted"
        except ValueError:
            verdict = "`ValueError`"
        rows.append([label, f"±{box:.0%}", *(f"{a:.3f}" for a in alphas), verdict])
    return rows


def document(lib: cbuild.CLibrary | None = None) -> str:
    lib = cbuild.build(False) if lib is None else lib
    return render(run_all(lib), status_names(lib), alpha_rows())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DOC)
    parser.add_argument("--check", action="store_true", help="exit 1 if --out is stale")
    args = parser.parse_args(argv)
    lib = cbuild.build(False)
    outcomes = run_all(lib)
    problems = failures(outcomes, lib)
    for p in problems:
        print(p, file=sys.stderr)
    text = render(outcomes, status_names(lib), alpha_rows())
    if args.check:
        same = args.out.exists() and args.out.read_text() == text
        print(f"{args.out}: {'up to date' if same else 'STALE'}")
        return 0 if same and not problems else 1
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"wrote {args.out} ({len(outcomes)} runs, {len(problems)} unexpected)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
