"""Float32 in the loop: the lawn-mower experiment (paper formulation) with the float32
build against the double build, TDROC (ε = 0.5) and TDC.

``runtime.sim.loop.run(float32=True)`` switches the whole C library to float32: the
controller *and* the simulated plant (RK4 at 1 kHz). Measured largest deviation of the
robot's path (point C) between the float32 and double runs:

    TDROC ε = 0.5: 1.08 mm      TDC: 1.86 mm

so the 1 mm goal is not met by that comparison. The excess comes from the plant, not the
controller: integrating x += dt·ẋ in float32 with dt = 1 ms over 60 000 substeps at
|x| up to ~10 m (float32 spacing ~1 µm there) drifts. With the float32 *controller* in
the loop of the double plant (the firmware situation; ``float_controller_library``
below), the deviations are 0.57 mm (TDROC) and 0.65 mm (TDC): within 1 mm. Both are
tested, with bounds a little above the measured values. About 6 s.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from modeling.robot_file import load_robot
from runtime.bindings.cbuild import CLibrary
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.settings import Experiment, SensingSettings
from runtime.sim import loop, paths
from runtime.sim.plant import library_for
from runtime.sim.reference import Reference
from runtime.stability.checks import check_configuration
from runtime.tooling.bad_input.runner import to_python

CODE = load_robot_code("")

# m: float32 controller and float32 plant. Measured 2.56 mm for TDROC with the generated
# sincosf of the step, 1.29 mm with newlib's/glibc's sinf/cosf, and 1.26 mm when the generated
# cos is moved by one ulp: this closed loop amplifies last-bit differences, so the bound is
# set above the spread (the step's torques agree with the double build within 8e-7 N m on
# recorded inputs, docs/FIRMWARE.md; the float32 controller alone stays within 1 mm below).
FULL_FLOAT_BOUND = 3.5e-3
CONTROLLER_BOUND = 1.0e-3  # m: float32 controller, double plant (measured ≤ 0.65 mm)
CASES = {"tdroc": 0.5, "tdc": None}  # controller: eps


@pytest.fixture(scope="module")
def setting() -> tuple[dict[str, float], Experiment, Reference]:
    robot = dict(load_robot().lumped)
    # The ≤ 1 mm goal was set and met with encoder-averaged rates (the sensing of the time);
    # with rates at the sample instant the float32 and double paths part by ~14 mm (open,
    # see the issue note): the sensing is stated here, not inherited from the default.
    exp = Experiment(
        sensing=SensingSettings(velocity="encoder-average", accel_estimator="backward")
    )
    ref = paths.lawnmower(CODE, robot, exp)
    return robot, exp, ref


def _experiment(exp: Experiment, eps: float | None) -> Experiment:
    return exp if eps is None else replace(exp, controller=replace(exp.controller, eps=eps))


def _copy_into(ffi_src: Any, src: Any, ffi_dst: Any, ctype: str) -> Any:
    """A struct of one build (double) as the same struct of another build (float32)."""
    dst = ffi_dst.new(f"{ctype} *")

    def fill(target: Any, values: dict[str, Any]) -> None:
        for key, value in values.items():
            if isinstance(value, dict):
                fill(getattr(target, key), value)
            elif isinstance(value, list):
                arr = getattr(target, key)
                for i, v in enumerate(value):
                    if isinstance(v, list):
                        arr[i][0 : len(v)] = v
                    else:
                        arr[i] = v
            else:
                setattr(target, key, value)

    fill(dst[0], to_python(ffi_src, src[0]))
    return dst


def float_controller_library(name: str) -> CLibrary:
    """The double simulation library with the controller's init/step replaced by the
    float32 build's (inputs rounded to float32, torques widened back): a float32
    controller in the loop of the double plant."""
    dbl, flt = library_for(CODE, False), library_for(CODE, True)
    store: dict[str, Any] = {}

    class Lib:
        def __getattr__(self, attr: str) -> Any:
            if attr == f"wmr_{name}_init":

                def init(state: Any, cfg: Any) -> int:
                    store["cfg"] = _copy_into(dbl.ffi, cfg, flt.ffi, f"wmr_{name}_config_t")
                    store["state"] = flt.ffi.new(f"wmr_{name}_state_t *")
                    return int(getattr(flt.lib, attr)(store["state"], store["cfg"]))

                return init
            if attr == f"wmr_{name}_step":

                def step(state: Any, cfg: Any, *arrays: Any) -> int:
                    args = [flt.ffi.new("wmr_real_t[]", list(a)) for a in arrays]
                    status = int(getattr(flt.lib, attr)(store["state"], store["cfg"], *args))
                    arrays[-1][0:2] = list(args[-1])
                    fs = store["state"]
                    state.gain, state.s_norm, state.u_discarded = fs.gain, fs.s_norm, fs.u_discarded
                    return status

                return step
            return getattr(dbl.lib, attr)

    return CLibrary(dbl.ffi, Lib(), False, dbl.path)


def _path_deviation(a: loop.Run, b: loop.Run) -> float:
    assert a.failed_at is None and b.failed_at is None
    assert len(a.t) == len(b.t)
    return float(np.max(np.linalg.norm(a.q[:, :2] - b.q[:, :2], axis=1)))


@pytest.mark.parametrize("name", list(CASES))
def test_float32_in_the_loop(
    setting: tuple[dict[str, float], Experiment, Reference],
    name: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    robot, exp, ref = setting
    exp = _experiment(exp, CASES[name])
    check_configuration(CODE, name, "paper", robot, exp)  # a configuration the toolchain runs
    double = loop.run(CODE, name, "paper", ref, robot, exp, float32=False)
    full = loop.run(CODE, name, "paper", ref, robot, exp, float32=True)
    deviation_full = _path_deviation(full, double)

    hybrid_lib = float_controller_library(name)

    def hybrid_library(code: RobotCode, float32: bool = False) -> CLibrary:
        return hybrid_lib

    monkeypatch.setattr(loop, "library_for", hybrid_library)
    hybrid = loop.run(CODE, name, "paper", ref, robot, exp, float32=False)
    monkeypatch.undo()
    deviation_controller = _path_deviation(hybrid, double)

    print(
        f"{name}: path deviation float32 vs double: whole loop {deviation_full * 1e3:.3f} mm, "
        f"float32 controller only {deviation_controller * 1e3:.3f} mm"
    )
    # The runs track: the deviation is small against the tracking error itself.
    assert double.position_error.max() < 0.02
    assert abs(full.position_error.max() - double.position_error.max()) < 1e-3
    assert deviation_full <= FULL_FLOAT_BOUND
    assert deviation_controller <= CONTROLLER_BOUND
    # The controller's own float32 error is the smaller part.
    assert deviation_controller < deviation_full
