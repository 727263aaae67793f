"""The run-time check of the TDROC and ASMC steps' float32 certificate conditions
(``<prefix>_<ctrl>_within_certificate``, issue 50): those steps' certified torque bounds
hold only while the switching gain (k-hat of (25); ASMC's adapted gain) stays in the law's
gain box and (25)'s ||Mhat^-1|| and window difference norms in the gain function's box.

Compiled from generated/ (float32, as the firmware), the function must say OK after the
steps of a run that tracks well, and WARN_UNCERTIFIED after a run driven out of those boxes;
after every step its answer must be what the state's values say against the boxes the
certifier certified over, read from the stored certificate (codegen/certify/results/, not
from the generator's module), to the last float32 step of each threshold.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from codegen.certify.runtime_check import gate_of
from codegen.certify.stored import robot_results
from generated.python import controllers as drishti_py
from runtime.bindings import cbuild
from runtime.bindings.config import controller_config
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.settings import Experiment
from runtime.tooling.firmware import build
from runtime.tooling.firmware.symbols import all_symbol_names, symbols

OK, WARN, NULL, NOT_INIT = 0, 3, -1, -15
ROBOTS = ("", "trailer", "trailer2", "trailer3", "train5")  # every robot generated
CASES = [(robot, name, form) for robot in ROBOTS for name in ("tdroc", "asmc")
         for form in ("paper", "minimal")
         if form in load_robot_code(robot).controller(name).formulations]
IDS = [f"{r or 'drishti'}-{n}-{f}" for r, n, f in CASES]


def _certified_boxes(prefix: str) -> dict[str, tuple[float, float]]:
    """The boxes the stored certificates hold over: the laws' gain input, and the window
    gain function's ||Mhat^-1|| and difference norms (each one box for all its entries)."""
    found: dict[str, set[tuple[float, float]]] = {}
    for row in robot_results(prefix)["functions"]:
        for access, box in row["box"].items():
            arg = access.split("[")[0]
            if (arg == "gain" and "_law" in row["function"]) or (
                    row["function"] == "tdroc_weighted_gain"
                    and arg in ("minv_norm", "dn_new", "dn_kept")):
                found.setdefault("window" if arg.startswith("dn_") else arg, set()).add(
                    (float(box[0]), float(box[1])))
    assert set(found) == {"gain", "minv_norm", "window"}, found
    assert all(len(v) == 1 for v in found.values()), found
    return {k: next(iter(v)) for k, v in found.items()}


class Run:
    """A float32 build of one robot's controller, its state after _init, and the check."""

    def __init__(self, robot: str, name: str, form: str, **changes: Any) -> None:
        code: RobotCode = load_robot_code(robot)
        self.code, self.name, self.pre = code, name, code.prefix
        self.lib = cbuild.build(True, c_dir=code.c_dir, prefix=code.prefix)
        self.ffi = self.lib.ffi
        self.cfg = controller_config(self.lib, code, name, form, code.params, Experiment())
        for key, value in changes.items():
            setattr(self.cfg, key, value)
        self.state = self.ffi.new(f"{self.pre}_{name}_state_t *")
        assert self.fn("init")(self.state, self.cfg) == OK
        self.tau = self.ffi.new(f"{self.pre}_real_t[{code.nu}]")

    def fn(self, suffix: str) -> Any:
        return getattr(self.lib.lib, f"{self.pre}_{self.name}_{suffix}")

    def within(self) -> int:
        return int(self.fn("within_certificate")(self.state))

    def step(self, *inputs: np.ndarray) -> int:
        arrays = [self.ffi.new(f"{self.pre}_real_t[{self.code.nq}]", [float(x) for x in a])
                  for a in inputs]
        return int(self.fn("step")(self.state, self.cfg, *arrays, self.tau))

    def window(self) -> list[float]:
        """The difference norms (25) read in the last step, newest first."""
        s = self.state
        return [float(s.omega_ring[s.omega_head + i]) for i in range(len(s.omega_ring) // 2)]

    def expected(self, boxes: dict[str, tuple[float, float]]) -> int:
        """What the state says against ``boxes``: the gain, and where (25) computed it the
        norm and the window."""
        s = self.state

        def inside(x: float, box: tuple[float, float]) -> bool:
            return box[0] <= x <= box[1]

        ok = inside(float(s.gain), boxes["gain"])
        if self.name == "tdroc" and not self.cfg.hold_gain and s.omega_count >= 2:
            ok = ok and inside(float(s.minv_norm), boxes["minv_norm"]) and all(
                inside(d, boxes["window"]) for d in self.window())
        return OK if ok else WARN


def _trajectory(nq: int, steps: int, error: float, rate: float,
                seed: int) -> Iterator[tuple[np.ndarray, ...]]:
    """A smooth reference and a measurement ``error`` away from it (a sinusoid of ``rate``
    rad/s in every coordinate): q, qdot, q_des, qdot_des, qddot_des."""
    rng = np.random.default_rng(seed)
    amp, freq = rng.uniform(0.2, 1.0, nq), rng.uniform(0.3, 1.5, nq)
    for k in range(steps):
        t = 0.01 * k
        q_des, qdot_des = amp * np.sin(freq * t), amp * freq * np.cos(freq * t)
        qddot_des = -amp * freq**2 * np.sin(freq * t)
        yield (q_des + error * np.sin(rate * t), qdot_des + error * rate * np.cos(rate * t),
               q_des, qdot_des, qddot_des)


def _boxes(robot: str) -> dict[str, tuple[float, float]]:
    # the robots without stored results share Drishti's envelope (boxes.ENVELOPE)
    prefix = load_robot_code(robot).prefix
    return _certified_boxes(prefix if robot_results(prefix) else "wmr")


@pytest.mark.parametrize(("robot", "name", "form"), CASES, ids=IDS)
def test_ok_while_tracking_and_uncertified_when_driven_out(robot: str, name: str,
                                                           form: str) -> None:
    boxes = _boxes(robot)
    inside = Run(robot, name, form)
    assert inside.within() == OK  # after _init: gain 0 or gain0
    for args in _trajectory(inside.code.nq, 150, error=0.01, rate=3.0, seed=3):
        assert inside.step(*args) in (0, 1)
        assert inside.within() == OK == inside.expected(boxes)
    # driven out: tracking errors of a radian at 40 rad/s (TDROC: (17)'s estimate jumps,
    # so the difference norms leave their box); ASMC: a fast adaptation raises the gain
    outside = Run(robot, name, form, **({"gamma": 500.0} if name == "asmc" else {}))
    answers = []
    for args in _trajectory(outside.code.nq, 150, error=1.0, rate=40.0, seed=3):
        assert outside.step(*args) in (0, 1)
        answers.append(outside.within())
        assert answers[-1] == outside.expected(boxes)
    assert WARN in answers
    if name == "asmc":  # the adapted gain never falls: once out, out for good
        assert answers[answers.index(WARN):] == [WARN] * (len(answers) - answers.index(WARN))


def _py_value(ffi: Any, value: Any) -> Any:
    """A C configuration field as the Python Config takes it."""
    return [float(x) for x in value] if isinstance(value, ffi.CData) else value


def _next32(x: float, direction: float) -> float:
    return float(np.nextafter(np.float32(x), np.float32(direction)))


@pytest.mark.parametrize("robot", ["", "trailer"], ids=["drishti", "trailer"])
def test_thresholds_are_the_certified_boxes_to_the_last_step(robot: str) -> None:
    """Each threshold is where the stored certificate's box ends: its end passes, the next
    float32 beyond it does not (a threshold from anywhere else, or a dropped check, fails)."""
    boxes = _boxes(robot)
    run = Run(robot, "tdroc", "minimal")
    for args in _trajectory(run.code.nq, 12, error=0.01, rate=3.0, seed=5):
        run.step(*args)
    s = run.state
    assert s.omega_count >= 2 and run.within() == OK
    saved = run.ffi.buffer(s)[:]

    def probe(set_value: Any, box: tuple[float, float]) -> None:
        for end, beyond in ((box[0], -np.inf), (box[1], np.inf)):
            set_value(end)
            assert run.within() == OK, end
            set_value(_next32(end, beyond))
            assert run.within() == WARN, _next32(end, beyond)
            set_value(float("nan"))
            assert run.within() == WARN
        run.ffi.buffer(s)[:] = saved

    probe(lambda v: setattr(s, "gain", v), boxes["gain"])
    probe(lambda v: setattr(s, "minv_norm", v), boxes["minv_norm"])
    width = len(s.omega_ring) // 2
    for i in range(width):  # every difference norm (25) reads, newest first
        probe(lambda v, i=i: s.omega_ring.__setitem__(s.omega_head + i, v), boxes["window"])
    # the ring's other copies are not read by (25): not checked
    for i in range(width):
        k = (s.omega_head + width + i) % (2 * width)
        if not s.omega_head <= k < s.omega_head + width:
            s.omega_ring[k] = 1e30
    assert run.within() == OK
    run.ffi.buffer(s)[:] = saved
    # fewer than two Omega's: k-hat is 0, not (25)'s, and the window is not read
    s.omega_count, s.minv_norm = 1, 1e30
    assert run.within() == OK
    run.ffi.buffer(s)[:] = saved
    asmc = Run(robot, "asmc", "minimal")
    probe_state = asmc.state
    for end, beyond in ((boxes["gain"][0], -np.inf), (boxes["gain"][1], np.inf)):
        probe_state.gain = end
        assert asmc.within() == OK
        probe_state.gain = _next32(end, beyond)
        assert asmc.within() == WARN


def test_held_gain_checks_the_gain_only() -> None:
    """With k-hat held (hold_gain = 1) (25) is not evaluated: the window does not matter,
    the held gain does."""
    run = Run("", "tdroc", "paper", hold_gain=1, held_gain=3.0)
    for args in _trajectory(run.code.nq, 40, error=1.0, rate=40.0, seed=3):
        run.step(*args)
    assert max(run.window()) > _boxes("")["window"][1]  # out of (25)'s box, unread
    assert run.within() == OK
    run.state.gain = _next32(_boxes("")["gain"][1], np.inf)
    assert run.within() == WARN


def test_null_uninitialised_and_corrupted_states() -> None:
    for name in ("tdroc", "asmc"):
        run = Run("", name, "minimal")
        assert int(run.fn("within_certificate")(run.ffi.NULL)) == NULL
        fresh = run.ffi.new(f"wmr_{name}_state_t *")
        assert int(run.fn("within_certificate")(fresh)) == NOT_INIT
    run = Run("", "tdroc", "minimal")
    width = len(run.state.omega_ring) // 2
    for field, value in (("omega_head", width), ("omega_head", -1),
                         ("omega_count", width + 2)):
        saved = getattr(run.state, field)
        setattr(run.state, field, value)
        assert run.within() == NOT_INIT, (field, value)
        setattr(run.state, field, saved)
    assert run.within() == OK


@pytest.mark.parametrize(("name", "form"), [("tdroc", "paper"), ("tdroc", "minimal"),
                                            ("asmc", "paper"), ("asmc", "minimal")])
def test_python_mirror_answers_as_the_c(name: str, form: str) -> None:
    """``within_certificate()`` of the generated Python controllers (double) says what the
    C says after each step of both runs (away from the thresholds: the two differ in
    precision), with the same boxes."""
    cls = getattr(drishti_py, name.upper())
    gate = gate_of(load_robot_code("").controller(name))
    assert gate is not None and cls.certificate_gain == gate.gain
    if gate.window:
        assert (cls.certificate_norm, cls.certificate_window) == (gate.norm, gate.window)
    for error, rate in ((0.01, 3.0), (1.0, 40.0)):
        changes = {"gamma": 500.0} if name == "asmc" else {}
        c_run = Run("", name, form, **changes)
        code = c_run.code
        py_cfg = drishti_py.Config(nominal=dict(code.params), **{
            f: _py_value(c_run.ffi, getattr(c_run.cfg, f))
            for f in drishti_py.Config.__dataclass_fields__
            if f != "nominal" and hasattr(c_run.cfg, f)})
        py = cls(py_cfg)
        answers = set()
        for args in _trajectory(code.nq, 120, error=error, rate=rate, seed=3):
            c_run.step(*args)
            py.step(*args)
            c_answer = {OK: "WMR_OK", WARN: "WMR_WARN_UNCERTIFIED"}[c_run.within()]
            assert py.within_certificate() == c_answer
            answers.add(c_answer)
        assert ("WMR_WARN_UNCERTIFIED" in answers) == (error > 0.1), answers
    with pytest.raises(AttributeError):
        drishti_py.TDC.within_certificate(object.__new__(drishti_py.TDC))


CHECK_BUDGET = 256  # bytes of Cortex-M4 code per check (measured: TDROC 184, ASMC 64)


@pytest.mark.skipif(not build.have_toolchain() or not build.have_newlib(),
                    reason="arm-none-eabi-gcc with newlib not installed")
def test_m4_check_is_small_and_not_in_the_step_image(tmp_path: Path) -> None:
    """Cortex-M4F float32 (-Os, one section per function): the check is its own small
    function, and an image that calls _init and _step only (the firmware report's) does
    not link it: it costs a step nothing."""
    objs = build.compile_generated(tmp_path / "f32", True, callgraph=False)
    sizes = {n: size for o in objs.objects for n, (_, size, _) in symbols(o).items()}
    for name in ("tdroc", "asmc"):
        assert 0 < sizes[f"wmr_{name}_within_certificate"] <= CHECK_BUDGET, sizes
        image = all_symbol_names(build.link_controller(objs, name))
        assert f"wmr_{name}_step" in image
        assert not any(s.endswith("_within_certificate") for s in image)
