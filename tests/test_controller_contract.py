"""The C controllers' contract beyond bad input (issue 13): no accepted input latches
failure, the step counter lasts the robot's life, configuration changes are refused with
their own status, ``_reset`` restores the state ``_init`` leaves, the error detail names
the field and entry (C and the Python mirror alike), and inputs a model function does not
read are ignored as its header says.

Latching: from any state reached by accepted inputs (hypothesis draws configurations at
and near every plausibility bound and inputs up to the 1e6 input bound), the first valid
step (the bad-input table's configuration and a smooth motion) must succeed:
``RECOVERY_STEPS`` = 1. Double and float32 builds, both formulations.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from runtime import cbuild
from runtime.generated_modules import controllers as pyctl
from runtime.tooling.bad_input.cases import BASE, CONTROLLERS, DRISHTI, FORMULATIONS
from runtime.tooling.bad_input.runner import (
    Controller,
    base_config,
    copy_config,
    field_names,
    smooth_sequence,
    status_values,
)

RECOVERY_STEPS = 1  # a valid step succeeds within this many steps of any accepted history
GAIN_MAX = pyctl.GAIN_MAX
EXAMPLES = 60 if shutil.which("gcc") else 0


@pytest.fixture(scope="module", params=["double", "float32"])
def lib(request: pytest.FixtureRequest) -> cbuild.CLibrary:
    return cbuild.build(request.param == "float32")


def _status(lib: cbuild.CLibrary, name: str) -> int:
    return status_values(lib)[name]


# Accepted but extreme values: at and just inside every bound.
edge_gain = st.sampled_from([1e-3, 1.0, 1e3, 1e5, GAIN_MAX])
edge_h = st.sampled_from([pyctl.H_MIN, 1e-4, 0.01, 0.5, pyctl.H_MAX])
edge_tau = st.sampled_from([1e-3, 1.0, 1e4, pyctl.TORQUE_LIMIT_MAX])
edge_input = st.one_of(
    st.sampled_from([0.0, 1e6, -1e6, 1e-30, 999_999.0]), st.floats(-1e6, 1e6, allow_nan=False)
)
inputs_strategy = st.lists(st.lists(edge_input, min_size=5, max_size=5), min_size=5, max_size=5)


def _nominal_strategy() -> st.SearchStrategy[dict[str, float]]:
    """Nominal parameters from the robot file's up to its bounds (many are rejected by the
    model's guards; the test only continues with accepted ones)."""
    return st.fixed_dictionaries(
        {
            k: st.one_of(
                st.just(v),
                st.just(math.copysign(pyctl.NOMINAL_BOUNDS[k], v)),
                st.floats(-pyctl.NOMINAL_BOUNDS[k], pyctl.NOMINAL_BOUNDS[k]),
            )
            for k, v in DRISHTI.items()
        }
    )


@st.composite
def extreme_config(draw: st.DrawFn) -> dict[str, Any]:
    return {
        "k1": tuple(draw(edge_gain) for _ in range(5)),
        "k2": tuple(draw(edge_gain) for _ in range(5)),
        "q_pos": draw(edge_gain),
        "q_vel": draw(edge_gain),
        "h": draw(edge_h),
        "tau_max": draw(edge_tau),
        "eps": draw(edge_gain),
        "phi": draw(st.sampled_from([0.0, GAIN_MAX])),
        "alpha": draw(st.sampled_from([0.0, 0.999999])),
        "gamma": draw(st.sampled_from([0.0, GAIN_MAX])),
        "gain0": draw(st.sampled_from([0.0, GAIN_MAX])),
        "a": draw(st.sampled_from([1e-6, 1.0])),
        "nominal": draw(_nominal_strategy()),
    }


def _config(lib: cbuild.CLibrary, name: str, form: str, values: dict[str, Any]) -> Any:
    nominal = values.pop("nominal")
    present = dict(lib.ffi.typeof(f"wmr_{name}_config_t").fields)
    cfg = base_config(lib, name, form, **{k: v for k, v in values.items() if k in present})
    cbuild.fill_params(cfg.nominal, nominal)
    if hasattr(cfg, "rate_window"):
        cfg.rate_window = min(float(cfg.rate_window), float(cfg.h))
    return cfg


def _run_adversarial(lib: cbuild.CLibrary, ctl: Controller, cfg: Any,
                     steps: list[list[list[float]]]) -> int:
    """Accepted steps on ``cfg`` (the controller's own config); returns how many succeeded."""
    ok = 0
    for inputs in steps:
        status, _ = ctl.step(inputs, cfg=cfg)
        ok += status >= 0
    return ok


def _recovers(lib: cbuild.CLibrary, name: str, form: str, state_bytes: bytes) -> int:
    """Re-initialise-free recovery: copy the reached state's history into a controller on
    the valid configuration and count the steps until one succeeds (at most 10)."""
    valid = Controller(lib, name, base_config(lib, name, form))
    ffi = lib.ffi
    # Keep the valid configuration's fingerprint, P and ||Mhat^-1||; take the rest.
    keep = {f: ffi.buffer(ffi.addressof(valid.state[0], f))[:]
            for f in ("magic", "config_fp", "p12", "p22", "minv_norm", "gain0")
            if f in dict(ffi.typeof(valid.state[0]).fields)}
    ffi.memmove(valid.state, state_bytes, len(state_bytes))
    for f, raw in keep.items():
        ffi.memmove(ffi.addressof(valid.state[0], f), raw, len(raw))
    for k, inputs in enumerate(smooth_sequence(10, float(BASE["h"])), start=1):
        status, tau = valid.step(inputs)
        if status >= 0:
            assert all(math.isfinite(x) for x in tau)
            return k
    return 11


@pytest.mark.parametrize("name", CONTROLLERS)
@pytest.mark.parametrize("form", FORMULATIONS)
def test_no_accepted_input_latches(lib: cbuild.CLibrary, name: str, form: str) -> None:
    """From any state reached by accepted inputs (extreme configurations and inputs), a
    valid step succeeds within RECOVERY_STEPS; the adaptive gains stay <= GAIN_MAX."""

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(values=extreme_config(), steps=st.lists(inputs_strategy, min_size=1, max_size=6))
    def prop(values: dict[str, Any], steps: list[list[list[float]]]) -> None:
        cfg = _config(lib, name, form, dict(values))
        if int(getattr(lib.lib, f"wmr_{name}_check_config")(cfg)) != 0:
            return  # not accepted: nothing to latch
        ctl = Controller(lib, name, cfg)
        _run_adversarial(lib, ctl, cfg, steps)
        if name in ("asmc", "tdroc"):  # adaptive (ROC's rho is computed afresh each step)
            assert float(ctl.state.gain) <= GAIN_MAX
        assert _recovers(lib, name, form, ctl.raw()) <= RECOVERY_STEPS

    prop()


def test_issue_examples_are_refused_and_do_not_latch() -> None:
    """The issue's two: ASMC given h = 1.8e306 once; nominal Iw = 1e25 on the third float32
    TDROC step. Both are refused now, with the field named, and the next valid step equals
    that of a twin that never saw them."""
    for float32, name, field, change in (
        (False, "asmc", "WMR_FIELD_H", lambda c: setattr(c, "h", 1.8e306)),
        (True, "tdroc", "WMR_FIELD_NOMINAL", lambda c: setattr(c.nominal, "Iw", 1e25)),
    ):
        lib = cbuild.build(float32)
        seq = smooth_sequence(8, float(BASE["h"]))
        cfg = base_config(lib, name, "paper")
        bad, twin = Controller(lib, name, cfg), Controller(lib, name, cfg)
        for inputs in seq[:2]:
            bad.step(inputs)
            twin.step(inputs)
        absurd = copy_config(lib, name, cfg)
        change(absurd)
        detail = lib.ffi.new("wmr_error_detail_t *")
        status, _ = bad.step(seq[2], cfg=absurd, detail=detail)
        assert status < 0 and field_names(lib)[int(detail.field)] == field
        for inputs in seq[3:]:
            assert bad.step(inputs) == twin.step(inputs)
            assert bad.raw() == twin.raw()


def test_adaptive_gain_is_capped(lib: cbuild.CLibrary) -> None:
    """ASMC at the largest accepted gamma and h with a large sliding variable: the gain
    stops at GAIN_MAX instead of growing until the law overflows."""
    cfg = base_config(lib, "asmc", "minimal", gamma=GAIN_MAX, h=1.0, tau_max=1e6)
    ctl = Controller(lib, "asmc", cfg)
    far = ([0.0] * 5, [0.0] * 5, [1e3] * 5, [1e3] * 5, [0.0] * 5)
    for _ in range(5):
        status, _ = ctl.step(far)
        assert status >= 0
    assert float(ctl.state.gain) == GAIN_MAX
    assert ctl.step(smooth_sequence(1, 0.01)[0])[0] >= 0


@pytest.mark.parametrize("name", CONTROLLERS)
def test_step_counter_saturates(lib: cbuild.CLibrary, name: str) -> None:
    """From STEPS_MAX - 1 the counter reaches STEPS_MAX and stays; the steps equal those
    of a twin whose counter is small (behaviour depends on steps >= 2 only)."""
    cfg = base_config(lib, name, "paper")
    seq = smooth_sequence(8, float(BASE["h"]))
    old, young = Controller(lib, name, cfg), Controller(lib, name, cfg)
    for inputs in seq[:3]:
        old.step(inputs)
        young.step(inputs)
    old.state.steps = pyctl.STEPS_MAX - 1
    for k, inputs in enumerate(seq[3:]):
        assert old.step(inputs) == young.step(inputs)
        assert int(old.state.steps) == pyctl.STEPS_MAX
        assert int(young.state.steps) == 4 + k
        assert old.fields() | {"steps": 0} == young.fields() | {"steps": 0}


UBSAN_MAIN = r"""
#include <stdio.h>
#include "wmr_tdroc.h"
int main(void)
{
    wmr_tdroc_config_t c = {0};
    wmr_tdroc_state_t s;
    wmr_real_t q[5] = {0}, qd[5] = {0}, r[5] = {0.1, 0.1, 0.1, 0.1, 0.1}, rd[5] = {0}, tau[2];
    int i, k;
    c.nominal.m = 36; c.nominal.Iz = 5.72; c.nominal.K = 0.34; c.nominal.Iw = 0.07;
    c.nominal.r = 0.096; c.nominal.b = 0.414; c.nominal.d = 0.12;
    for (i = 0; i < 5; ++i) { c.k1[i] = 4; c.k2[i] = 3; }
    c.q_pos = 1; c.q_vel = 1; c.h = 0.001; c.tau_max = 50; c.eps = 0.1; c.n = 4; c.a = 0.9;
    if (wmr_tdroc_init(&s, &c) != WMR_OK) return 2;
    s.steps = WMR_STEPS_MAX - 2u;
    for (k = 0; k < 5; ++k) {
        if (wmr_tdroc_step(&s, &c, q, qd, r, rd, rd, tau) < 0) return 3;
    }
    printf("%lu\n", (unsigned long)s.steps);
    return s.steps == WMR_STEPS_MAX ? 0 : 4;
}
"""


def test_step_counter_under_ubsan(tmp_path: Path) -> None:
    """The counter at its maximum under -fsanitize=undefined (signed overflow was UB)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not found")
    src = tmp_path / "main.c"
    src.write_text(UBSAN_MAIN)
    exe = tmp_path / "ubsan"
    cmd = cbuild.gcc_command(
        [*sorted(cbuild.GENERATED_C.glob("wmr_*.c")), src], exe, kind="executable",
        flags=("-std=c99", "-O1", "-fsanitize=undefined", "-fno-sanitize-recover=all"),
        include_dirs=(cbuild.GENERATED_C,), libs=("-lm",),
    )
    try:
        cbuild.run_compiler([cmd])
    except cbuild.BuildError as exc:
        pytest.skip(f"no UBSan here: {exc.output[-200:]}")
    proc = subprocess.run([str(exe)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "runtime error" not in proc.stderr
    assert proc.stdout.strip() == str(pyctl.STEPS_MAX)


CHANGES: tuple[tuple[str, Any], ...] = (
    ("k1[0]", lambda c: c.k1.__setitem__(0, 4.5)),
    ("q_pos", lambda c: setattr(c, "q_pos", 1.6)),
    ("h", lambda c: setattr(c, "h", 0.02)),
    ("tau_max", lambda c: setattr(c, "tau_max", 150.0)),
    ("nominal.m", lambda c: setattr(c.nominal, "m", 40.0)),
    ("formulation", lambda c: setattr(c, "formulation", 1 - c.formulation)),
)


@pytest.mark.parametrize("name", CONTROLLERS)
@pytest.mark.parametrize(("label", "change"), CHANGES, ids=[c[0] for c in CHANGES])
def test_config_change_is_refused(lib: cbuild.CLibrary, name: str, label: str,
                                  change: Any) -> None:
    """A valid configuration that differs from _init's: WMR_ERR_CONFIG_CHANGED with the
    CONFIG field, state and tau untouched; the same in the Python mirror; _init adopts it."""
    cfg = base_config(lib, name, "paper")
    ctl = Controller(lib, name, cfg)
    seq = smooth_sequence(3, float(BASE["h"]))
    ctl.step(seq[0])
    changed = copy_config(lib, name, cfg)
    change(changed)
    assert int(getattr(lib.lib, f"wmr_{name}_check_config")(changed)) == 0
    before = ctl.raw()
    detail = lib.ffi.new("wmr_error_detail_t *")
    tau = lib.ffi.new("wmr_real_t[2]", [7.0, -7.0])
    status, out = ctl.step(seq[1], cfg=changed, tau=tau, detail=detail)
    assert status == _status(lib, "WMR_ERR_CONFIG_CHANGED")
    assert field_names(lib)[int(detail.field)] == "WMR_FIELD_CONFIG"
    assert ctl.raw() == before and out == [7.0, -7.0]
    assert ctl.step(seq[1])[0] >= 0  # the original configuration still works
    assert Controller(lib, name, changed).step(seq[1])[0] >= 0  # _init adopts the change
    if not lib.float32:  # the mirror: same status, same fingerprint as C
        py = pyctl.__dict__[name.upper()](_py_config(cfg))
        assert py.config_fp == int(Controller(lib, name, cfg).state.config_fp)
        with pytest.raises(pyctl.ControllerError) as err:
            py.step(*seq[1], config=_py_config(changed))
        assert err.value.status == "WMR_ERR_CONFIG_CHANGED" and err.value.field == "CONFIG"


def _py_config(cfg: Any) -> Any:
    """The Python mirror's Config from a C configuration struct."""
    kwargs: dict[str, Any] = {}
    for f in pyctl.Config.__dataclass_fields__:
        if f == "nominal":
            kwargs[f] = {k: float(getattr(cfg.nominal, pyctl.C_FIELD_NAMES.get(k, k)))
                         for k in pyctl.PARAM_KEYS}
        elif hasattr(cfg, f):
            v = getattr(cfg, f)
            kwargs[f] = [float(x) for x in v] if f in ("k1", "k2") else v
    return pyctl.Config(**kwargs)


@pytest.mark.parametrize("name", CONTROLLERS)
def test_reset_restores_the_init_state(lib: cbuild.CLibrary, name: str) -> None:
    cfg = base_config(lib, name, "paper")
    ctl, fresh = Controller(lib, name, cfg), Controller(lib, name, cfg)
    seq = smooth_sequence(6, float(BASE["h"]))
    for inputs in seq:
        ctl.step(inputs)
    assert ctl.fields() != fresh.fields()
    assert int(getattr(lib.lib, f"wmr_{name}_reset")(ctl.state)) == 0
    assert ctl.fields() == fresh.fields()  # field by field (padding is indeterminate)
    ctl.state.magic = 0
    assert int(getattr(lib.lib, f"wmr_{name}_reset")(ctl.state)) == _status(
        lib, "WMR_ERR_NOT_INITIALISED")
    if not lib.float32:
        py, py_fresh = (pyctl.__dict__[name.upper()](_py_config(cfg)) for _ in range(2))
        for inputs in seq:
            py.step(*inputs)
        py.reset()
        assert repr(py.state()) == repr(py_fresh.state())


DETAIL_CASES: tuple[tuple[str, Any, str, int], ...] = (
    ("k2[3]=-1", lambda c: c.k2.__setitem__(3, -1.0), "K2", 3),
    ("k1[1]=2e6", lambda c: c.k1.__setitem__(1, 2e6), "K1", 1),
    ("h=2", lambda c: setattr(c, "h", 2.0), "H", -1),
    ("tau_max=nan", lambda c: setattr(c, "tau_max", math.nan), "TAU_MAX", -1),
    ("Iw=1e25", lambda c: setattr(c.nominal, "Iw", 1e25), "NOMINAL", 3),
    ("b=0", lambda c: setattr(c.nominal, "b", 0.0), "NOMINAL", -1),
    ("eps=0", lambda c: setattr(c, "eps", 0.0), "EPS", -1),
)


@pytest.mark.parametrize(("label", "change", "field", "index"), DETAIL_CASES,
                         ids=[c[0] for c in DETAIL_CASES])
def test_error_detail_c_equals_python(label: str, change: Any, field: str, index: int) -> None:
    lib = cbuild.build(False)
    cfg = base_config(lib, "tdroc", "paper")
    bad = copy_config(lib, "tdroc", cfg)
    change(bad)
    detail = lib.ffi.new("wmr_error_detail_t *")
    status = int(lib.lib.wmr_tdroc_check_config_detail(bad, detail))
    assert (int(detail.status), field_names(lib)[int(detail.field)], int(detail.index)) == (
        status, f"WMR_FIELD_{field}", index)
    with pytest.raises(pyctl.ControllerError) as err:
        pyctl.TDROC(_py_config(bad))
    assert err.value.detail == (status, pyctl.FIELDS[field], index)
    # Inputs: the entry made bad, in C and Python.
    ctl = Controller(lib, "tdroc", cfg)
    inputs = [list(v) for v in smooth_sequence(1, 0.01)[0]]
    inputs[3][2] = math.inf
    ctl.step(inputs, detail=detail)
    assert (field_names(lib)[int(detail.field)], int(detail.index)) == ("WMR_FIELD_QDOT_DES", 2)
    with pytest.raises(pyctl.ControllerError) as err:
        pyctl.TDROC(_py_config(cfg)).step(*inputs)
    assert (err.value.field, err.value.index) == ("QDOT_DES", 2)


def test_unread_inputs_are_ignored_as_documented() -> None:
    """wmr_forward_dynamics reads q[2] only among q: NaN elsewhere in q is ignored (its
    header says so); NaN in q[2] is WMR_ERR_NONFINITE_INPUT."""
    header = (cbuild.GENERATED_C / "wmr_model.h").read_text()
    doc = header[: header.index("wmr_status_t wmr_forward_dynamics(")]
    doc = doc[doc.rindex("/**"):]
    assert "it does not read, and ignores: q[0], q[1], q[3], q[4]" in doc
    lib = cbuild.build(False)
    ffi = lib.ffi
    p = cbuild.params_struct(lib, DRISHTI)
    out = ffi.new("wmr_real_t[5]")

    def call(q: list[float]) -> int:
        qdot = ffi.new("wmr_real_t[5]", [0.1] * 5)
        return int(lib.lib.wmr_forward_dynamics(p, ffi.new("wmr_real_t[5]", q), qdot,
                                                ffi.new("wmr_real_t[2]", [1.0, 1.0]), out))

    assert call([math.nan, math.nan, 0.3, math.nan, math.nan]) == 0
    assert call([0.0, 0.0, math.nan, 0.0, 0.0]) == _status(lib, "WMR_ERR_NONFINITE_INPUT")


# clang -Weverything, minus two documented exclusions (docs/STATIC_CHECKS.md): -Wpadded (the
# compiler pads the configuration structs; informational, the layout is the caller's ABI)
# and -Wdeclaration-after-statement (a C90-compatibility warning: the code is C99).
CLANG_EXCLUSIONS = ("-Wno-padded", "-Wno-declaration-after-statement")


@pytest.mark.parametrize("float32", [False, True], ids=["double", "float32"])
def test_clang_weverything(float32: bool) -> None:
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang not installed (apt-get install clang)")
    cmd = [clang, "-std=c99", "-Weverything", "-Werror", *CLANG_EXCLUSIONS, "-fsyntax-only",
           *(["-DWMR_FLOAT32"] if float32 else []),
           *map(str, sorted(cbuild.GENERATED_C.glob("wmr_*.c")))]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr[-3000:]
