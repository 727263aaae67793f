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
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from runtime.bindings import cbuild
from runtime.bindings.generated import controllers as pyctl
from runtime.tooling.bad_input.cases import (
    BASE,
    CONTROLLER_FIELDS,
    CONTROLLER_FORMULATIONS,
    CONTROLLERS,
    DRISHTI,
    FORMULATIONS,
)
from runtime.tooling.bad_input.runner import (
    Controller,
    base_config,
    copy_config,
    field_names,
    smooth_sequence,
    status_values,
)

RECOVERY_STEPS = 1  # a valid step succeeds within this many steps of any accepted history
# Every (controller, formulation) the registry generates.
FORMS = [(n, f) for n in CONTROLLERS for f in FORMULATIONS if f in CONTROLLER_FORMULATIONS[n]]


def own_form(name: str) -> str:
    """The paper formulation where ``name`` has it, else its own."""
    return "paper" if "paper" in CONTROLLER_FORMULATIONS[name] else CONTROLLER_FORMULATIONS[name][0]
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
    # Keep the valid configuration (the copy _init kept), P and ||Mhat^-1||; take the rest.
    keep = {f: ffi.buffer(ffi.addressof(valid.state[0], f))[:]
            for f in ("magic", "config", "p12", "p22", "minv_norm", "gain0")
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


@pytest.mark.parametrize(("name", "form"), FORMS)
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
        cfg = base_config(lib, name, own_form(name))
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
    cfg = base_config(lib, name, own_form(name))
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
    ("kp", lambda c: setattr(c, "kp", 3.0)),
    ("k1[0]", lambda c: c.k1.__setitem__(0, 4.5)),
    ("q_pos", lambda c: setattr(c, "q_pos", 1.6)),
    ("h", lambda c: setattr(c, "h", 0.02)),
    ("tau_max", lambda c: setattr(c, "tau_max", 150.0)),
    ("nominal.m", lambda c: setattr(c.nominal, "m", 40.0)),
    ("formulation", lambda c: setattr(c, "formulation", 1 - c.formulation)),
)


CHANGE_CASES = [
    pytest.param(name, label, change, id=f"{name}-{label}")
    for name in CONTROLLERS for label, change in CHANGES
    # the field changed exists, and a valid other formulation does
    if re.split(r"[\[.]", label)[0] in {*CONTROLLER_FIELDS[name], "nominal"}
    and (label != "formulation" or len(CONTROLLER_FORMULATIONS[name]) > 1)
]


@pytest.mark.parametrize(("name", "label", "change"), CHANGE_CASES)
def test_config_change_is_refused(lib: cbuild.CLibrary, name: str, label: str,
                                  change: Any) -> None:
    """A valid configuration that differs from _init's: WMR_ERR_CONFIG_CHANGED with the
    CONFIG field, state and tau untouched; the same in the Python mirror; _init adopts it."""
    cfg = base_config(lib, name, own_form(name))
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
    if not lib.float32:  # the mirror: same status; it keeps what the C's copy holds
        py = pyctl.__dict__[name.upper()](_py_config(cfg))
        kept = Controller(lib, name, cfg).state.config
        assert py.config_bits == py.value_bits(_py_config(kept))
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
    cfg = base_config(lib, name, own_form(name))
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
    ("b=0", lambda c: setattr(c.nominal, "b", 0.0), "NOMINAL", 5),  # below b / 1000
    ("I=K^2/m", lambda c: setattr(c.nominal, "Iz", 0.34**2 / 36.0), "NOMINAL", -1),  # guards
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


# ----- issue 25: a changed configuration is caught whatever bits change -----

BITFLIP_DRIVER = r"""
#include <string.h>
#include "wmr_NAME.h"
#include "bitflip_NAME.h"

/* Flip bit b of the configuration's value bytes (value k spans offsets[k], sizes[k]). */
static void flip(unsigned char *cfg, const int *offsets, const int *sizes, int nvalues, long b)
{
    int k;
    for (k = 0; k < nvalues; ++k) {
        if (b < 8L * sizes[k]) {
            cfg[offsets[k] + b / 8] ^= (unsigned char)(1u << (b % 8));
            return;
        }
        b -= 8L * sizes[k];
    }
}

/* Every one-bit and every two-bit change of *config's values, each given to a step of a
   copy of *state: returns how many the step accepted or that changed the state or tau. */
long bitflip_NAME(const wmr_NAME_state_t *state, const wmr_NAME_config_t *config,
                  const int *offsets, const int *sizes, int nvalues, const wmr_real_t *inputs,
                  long *tried)
{
    long bits = 0, i, j, missed = 0;
    int k;
    for (k = 0; k < nvalues; ++k) {
        bits += 8L * sizes[k];
    }
    *tried = 0;
    for (i = 0; i < bits; ++i) {
        for (j = i; j < bits; ++j) {  /* j == i: the one-bit change */
            wmr_NAME_config_t cfg = *config;
            wmr_NAME_state_t s = *state;
            wmr_real_t tau[2] = {7.0, -7.0};
            wmr_status_t status;
            flip((unsigned char *)&cfg, offsets, sizes, nvalues, i);
            if (j != i) {
                flip((unsigned char *)&cfg, offsets, sizes, nvalues, j);
            }
            status = wmr_NAME_step(&s, &cfg, inputs, inputs + 5, inputs + 10, inputs + 15,
                                   inputs + 20, tau);
            ++*tried;
            if (status >= 0 || memcmp(&s, state, sizeof s) != 0 || tau[0] != 7.0
                || tau[1] != -7.0) {
                ++missed;
            }
        }
    }
    return missed;
}
"""


def _value_layout(lib: cbuild.CLibrary, name: str) -> tuple[list[int], list[int]]:
    """(offset, size) of every value of the configuration struct (never its padding)."""
    ffi = lib.ffi
    offsets, sizes = [], []

    def walk(ctype: Any, base: int) -> None:
        if ctype.kind == "struct":
            for _, f in ctype.fields:
                walk(f.type, base + f.offset)
        elif ctype.kind == "array":
            for i in range(ctype.length):
                walk(ctype.item, base + i * ffi.sizeof(ctype.item))
        else:
            offsets.append(base)
            sizes.append(ffi.sizeof(ctype))

    walk(ffi.typeof(f"wmr_{name}_config_t"), 0)
    return offsets, sizes


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not found")
@pytest.mark.parametrize("float32", [False, True], ids=["double", "float32"])
@pytest.mark.parametrize("name", CONTROLLERS)
def test_every_one_and_two_bit_change_is_refused(tmp_path: Path, name: str,
                                                 float32: bool) -> None:
    """Every one-bit and every two-bit change of every value of an initialised controller's
    configuration (sign flips included: any two of them cancelled in the old 32-bit
    fingerprint) is refused by the next step (the field's error or CONFIG_CHANGED), state
    and tau untouched. Both formulations; millions of steps, so in C."""
    src, hdr = tmp_path / f"bitflip_{name}.c", tmp_path / f"bitflip_{name}.h"
    src.write_text(BITFLIP_DRIVER.replace("NAME", name))
    hdr.write_text(
        f"long bitflip_{name}(const wmr_{name}_state_t *state, const wmr_{name}_config_t *"
        "config, const int *offsets, const int *sizes, int nvalues, const wmr_real_t *inputs,"
        " long *tried);\n")
    lib = cbuild.build(float32, extra_sources=(src,), extra_headers=(hdr,))
    offsets, sizes = _value_layout(lib, name)
    seq = smooth_sequence(4, float(BASE["h"]))
    for form in CONTROLLER_FORMULATIONS[name]:
        ctl = Controller(lib, name, base_config(lib, name, form))
        for inputs in seq[:3]:
            assert ctl.step(inputs)[0] >= 0
        flat = lib.ffi.new("wmr_real_t[25]", [x for v in seq[3] for x in v])
        tried = lib.ffi.new("long *")
        missed = getattr(lib.lib, f"bitflip_{name}")(
            ctl.state, ctl.cfg, lib.ffi.new("int[]", offsets), lib.ffi.new("int[]", sizes),
            len(offsets), flat, tried)
        bits = 8 * sum(sizes)
        assert tried[0] == bits * (bits + 1) // 2  # every pair and every single bit
        assert missed == 0, f"{form}: {missed} of {tried[0]} changes not refused"
        assert ctl.step(seq[3])[0] >= 0  # the unchanged configuration still steps


@pytest.mark.parametrize("name", CONTROLLERS)
def test_mirror_refuses_every_one_bit_change(name: str) -> None:
    """The Python mirror keeps the configuration's values (as C keeps its copy) and refuses
    a step given a configuration with any one bit of any value changed."""
    lib = cbuild.build(False)
    cfg = base_config(lib, name, own_form(name))
    py = pyctl.__dict__[name.upper()](_py_config(cfg))
    seq = smooth_sequence(2, float(BASE["h"]))
    py.step(*seq[0])
    flips = 0
    for k in range(len(py.config_bits)):
        for bit in range(64):
            changed = list(py.config_bits)
            changed[k] ^= 1 << bit
            if tuple(changed) == py.config_bits:
                continue
            mutated = _config_from_bits(py, tuple(changed))
            if mutated is None:  # an int field's bit beyond its range: not a value
                continue
            with pytest.raises(pyctl.ControllerError):
                py.step(*seq[1], config=mutated)
            flips += 1
    assert flips >= 64 * (len(py.config_bits) - 4)
    py.step(*seq[1])  # the original still steps


def _config_from_bits(py: Any, bits: tuple[int, ...]) -> Any:
    """A mirror Config whose values are ``bits`` (``value_bits`` order), or None when an int
    does not fit a C int."""
    import struct as _struct
    from dataclasses import replace

    def real(b: int) -> float:
        return float(_struct.unpack("=d", _struct.pack("=Q", b))[0])

    it = iter(bits)
    c = py.config
    nominal = {k: real(next(it)) for k in pyctl.PARAM_KEYS}
    changes: dict[str, Any] = {"nominal": nominal}
    for fname, kind in py.config_fields:
        if kind == "vector":
            changes[fname] = [real(next(it)) for _ in range(len(getattr(c, fname)))]
        elif kind == "int":
            value = next(it)
            if not -(2**31) <= value < 2**31:
                return None
            changes[fname] = value
        else:
            changes[fname] = real(next(it))
    return replace(c, **changes)


# ----- issue 25: accepted configurations and inputs never give a non-finite output -----

def _log_between(low: float, high: float) -> st.SearchStrategy[float]:
    """The bounds themselves, or log-uniform between them."""
    return st.one_of(st.sampled_from([low, high]),
                     st.floats(math.log(low), math.log(high)).map(math.exp)
                     .map(lambda x: min(max(x, low), high)))


@st.composite
def accepted_config(draw: st.DrawFn) -> dict[str, Any]:
    """Any configuration inside the plausibility bounds (the model's guards then refuse
    some nominal models; the test goes on with the accepted ones)."""
    gain = _log_between(pyctl.GAIN_MIN, GAIN_MAX)
    nominal = {}
    for k, v in DRISHTI.items():
        low, high = pyctl.NOMINAL_RANGES[k]
        nominal[k] = draw(st.one_of(st.just(v), _log_between(max(low, abs(v) / 1e3), high)))
    return {
        "k1": tuple(draw(gain) for _ in range(5)),
        "k2": tuple(draw(gain) for _ in range(5)),
        "q_pos": draw(gain), "q_vel": draw(gain), "eps": draw(gain),
        "h": draw(_log_between(pyctl.H_MIN, pyctl.H_MAX)),
        "tau_max": draw(_log_between(1e-30, pyctl.TORQUE_LIMIT_MAX)),
        "phi": draw(st.one_of(st.just(0.0), gain)),
        "alpha": draw(st.sampled_from([0.0, 0.3, 0.999999, 0.9999999])),
        "gamma": draw(st.one_of(st.just(0.0), gain)),
        "gain0": draw(st.one_of(st.just(0.0), gain)),
        "held_gain": draw(st.one_of(st.just(0.0), gain)),
        "hold_gain": draw(st.sampled_from([0, 1])),
        "a": draw(_log_between(1e-30, 1.0)),
        "n": draw(st.integers(2, 8)),
        "accel_estimator": draw(st.sampled_from([0, 1, 2])),
        "kx": draw(st.one_of(st.just(0.0), gain)), "ky": draw(st.one_of(st.just(0.0), gain)),
        "ktheta": draw(st.one_of(st.just(0.0), gain)), "kp": draw(gain),
        "ki": draw(st.one_of(st.just(0.0), gain)),
        "nominal": nominal,
    }


finite_input = st.one_of(st.sampled_from([0.0, 1e6, -1e6, 1e-30]),
                         st.floats(-1e6, 1e6, allow_nan=False))


@st.composite
def input_run(draw: st.DrawFn) -> list[tuple[list[float], ...]]:
    """Steps of finite inputs within the input bound, ending with a streak of exactly zero
    tracking error (q = q_des, qdot = qdot_des) of 30 steps."""
    scale = draw(st.sampled_from([1e-3, 1.0, 1e3, 1e6]))
    vec = st.lists(finite_input.map(lambda x: x * scale / 1e6), min_size=5, max_size=5)
    steps = [tuple(draw(vec) for _ in range(5)) for _ in range(draw(st.integers(0, 5)))]
    q, qdot, qddot = draw(vec), draw(vec), draw(vec)
    drift = draw(vec)
    for k in range(30):
        qk = [min(max(a + k * 1e-3 * b, -1e6), 1e6) for a, b in zip(q, drift, strict=True)]
        steps.append((qk, qdot, qk, qdot, qddot))
    return steps


@pytest.mark.parametrize(("name", "form"), FORMS)
def test_accepted_inputs_never_give_a_nonfinite_output(lib: cbuild.CLibrary, name: str,
                                                       form: str) -> None:
    """Issue 25: with any accepted configuration and finite inputs within the bound, every
    step returns OK or SATURATED with a finite tau, through streaks of exactly zero error
    (an accepted eps of 2^-1074 made those NaN: (k / eps) * 0)."""
    ok = {_status(lib, "WMR_OK"), _status(lib, "WMR_WARN_SATURATED")}

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    @given(values=accepted_config(), steps=input_run())
    def prop(values: dict[str, Any], steps: list[tuple[list[float], ...]]) -> None:
        cfg = _config(lib, name, form, dict(values))
        check = getattr(lib.lib, f"wmr_{name}_check_config")
        if int(check(cfg)) != 0:
            # Only the model's guards may refuse it (some drawn nominal models are not
            # positive definite): with Drishti's own nominal model the same configuration,
            # every field inside its documented bounds, is accepted (an over-strict field
            # check would be invisible if a refusal ended the example).
            own = _config(lib, name, form, {**values, "nominal": dict(DRISHTI)})
            assert int(check(own)) == 0, (name, form, values)
            return
        ctl = Controller(lib, name, cfg)
        for k, inputs in enumerate(steps):
            status, tau = ctl.step(inputs)
            assert status in ok and all(math.isfinite(x) for x in tau), (
                f"step {k}: status {status}, tau {tau}")

    prop()
