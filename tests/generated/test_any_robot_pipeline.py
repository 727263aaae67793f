"""Every shipped robot through the whole pipeline, from its generated code only.

For each robot in ``modeling/robots/`` (the paper's Drishti at the root of ``generated/``,
the tractor with one, two and three trailers in ``generated/trailer*/`` and the tugger
train of five carts in ``generated/train5/``; the last three generated through staged
quantities, ``modeling.staged``):

* the generated C compiles under strict flags in double and float32 (and for the
  Cortex-M4 when the cross-compiler is installed);
* the generated C equals the generated Python (model functions at 100 consistent states,
  and every controller stepped along a closed-loop measurement sequence);
* the CasADi functions equal the Python ones;
* every controller closes the loop in the one simulator (``runtime.sim.loop``) on a circle
  (constant wheel rates), with the plant heavier than the nominal model.

The trailer's generated forward dynamics also equals the KKT solve of its description
(physical parameters, an independent route from the base-parameter code) to 1e-12.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from modeling.robot_file import robot_source, shipped_robot_files
from runtime.bindings import cbuild
from runtime.bindings.generated import GENERATED, RobotCode, load_robot_code
from runtime.bindings.uncertainty import roc_bounds
from runtime.experiment.settings import Experiment, PlantSettings
from runtime.sim import loop as sim_loop
from runtime.sim.reference import wheel_rate_reference

STRICT = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wdouble-promotion",
          "-Wfloat-equal", "-Werror")
# Each file's folder from its name alone: deriving every robot here (train5: minutes) would
# cost the suite more than all of this file's checks.
OUTPUT_DIRS = [robot_source(p).naming.output_dir for p in shipped_robot_files()]
CONTROLLERS = load_robot_code("").controller_names  # the registry's, as robot.py exports it


def _id(d: str) -> str:
    return d or "default"


def c_dir(out: str) -> Path:
    return (GENERATED / out / "c") if out else GENERATED / "c"


@pytest.fixture(scope="module", params=OUTPUT_DIRS, ids=_id)
def robot(request: Any) -> tuple[str, RobotCode]:
    return request.param, load_robot_code(request.param)


def states(code: RobotCode, count: int, seed: int) -> list[tuple[np.ndarray, ...]]:
    """(q, η, q̇ = S(q) η, τ) on the constraint manifold."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        q = np.r_[rng.uniform(-5, 5, 2), rng.uniform(-np.pi, np.pi, code.nq - 2)]
        eta = rng.uniform(-15, 15, code.nu)
        tau = rng.uniform(-10, 10, code.nu)
        out.append((q, eta, code.velocities(q, eta, code.params), tau))
    return out


@pytest.mark.parametrize("float32", [False, True], ids=["double", "float32"])
def test_generated_c_compiles_strict(robot: tuple[str, RobotCode], float32: bool) -> None:
    out, code = robot
    folder = c_dir(out)
    flags = [f"-D{code.prefix.upper()}_FLOAT32"] if float32 else []
    sources = sorted(str(p) for p in folder.glob("*.c"))
    assert len(sources) >= 9
    result = subprocess.run(["gcc", *STRICT, *flags, "-fsyntax-only", f"-I{folder}", *sources],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


@pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None,
                    reason="arm-none-eabi-gcc not installed (.ci/run installs it)")
def test_generated_c_builds_for_cortex_m4(robot: tuple[str, RobotCode], tmp_path: Path) -> None:
    out, code = robot
    folder = c_dir(out)
    for src in sorted(folder.glob(f"{code.prefix}_*.c")):
        cmd = ["arm-none-eabi-gcc", *STRICT, "-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard",
               "-mfpu=fpv4-sp-d16", "-Os", f"-D{code.prefix.upper()}_FLOAT32", f"-I{folder}",
               "-c", str(src), "-o", str(tmp_path / (src.stem + ".o"))]
        result = subprocess.run(cmd, capture_output=True, text=True)
        assert result.returncode == 0, (src.name, result.stderr)


@pytest.fixture(scope="module")
def clib(robot: tuple[str, RobotCode]) -> Any:
    out, code = robot
    return cbuild.build(c_dir=c_dir(out), prefix=code.prefix)


def _c_params(lib: Any, code: RobotCode, values: dict[str, float], plant: bool = False) -> Any:
    ctype = f"{code.prefix}_plant_params_t" if plant else f"{code.prefix}_params_t"
    return cbuild.params_struct(lib, values, ctype, code.controllers.C_FIELD_NAMES)


def test_c_model_equals_python(robot: tuple[str, RobotCode], clib: Any) -> None:
    _, code = robot
    ffi, lib = clib.ffi, clib.lib
    p = _c_params(clib, code, code.params)
    pp = _c_params(clib, code, code.plant_defaults, plant=True)
    qdd = ffi.new(f"{code.prefix}_real_t[{code.nq}]")
    xdot = ffi.new(f"{code.prefix}_real_t[{code.nq + code.nu}]")
    worst = 0.0
    for q, eta, qdot, tau in states(code, 100, seed=11):
        status = getattr(lib, f"{code.prefix}_forward_dynamics")(p, list(q), list(qdot),
                                                                list(tau), qdd)
        assert status == 0
        ref = code.model.forward_dynamics(q, qdot, tau, code.params)
        worst = max(worst, float(np.max(np.abs(np.array(list(qdd)) - ref))
                                 / max(1.0, float(np.max(np.abs(ref))))))
        x = np.r_[q, eta]
        getattr(lib, f"{code.prefix}_plant_state_derivative")(pp, list(x), list(tau), xdot)
        ref_x = code.plant.plant_state_derivative(x, tau, code.plant_defaults)
        worst = max(worst, float(np.max(np.abs(np.array(list(xdot)) - ref_x))
                                 / max(1.0, float(np.max(np.abs(ref_x))))))
    assert worst < 1e-12, worst


def test_casadi_equals_python(robot: tuple[str, RobotCode]) -> None:
    import casadi

    out, code = robot
    folder = (GENERATED / out / "casadi") if out else GENERATED / "casadi"
    fd = casadi.Function.load(str(folder / "forward_dynamics.casadi"))
    names = [fd.name_in(i) for i in range(fd.n_in())]
    for q, _, qdot, tau in states(code, 20, seed=5):
        args = {"q": q, "qdot": qdot, "tau": tau,
                "p": np.array([code.params[k] for k in code.controllers.PARAM_KEYS])}
        got = np.array(fd(*[args[n] for n in names])).ravel()
        ref = code.model.forward_dynamics(q, qdot, tau, code.params)
        np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-11)


def _config(code: RobotCode, h: float) -> Any:
    c = code.controllers
    return c.Config(nominal=code.params, formulation=c.FORMULATION_MINIMAL,
                    k1=[4.0] * code.nq, k2=[4.0] * code.nq, h=h, tau_max=50.0, eps=0.1)


def _experiment(h: float) -> Experiment:
    """K1 = K2 = 4 I, ε = 0.1, τ_max = 50 N m at ``h``; sample-instant rates; no friction, no
    payload (the plant is :func:`_heavier` instead); RK4 at h / 10."""
    exp = Experiment()
    return Experiment(
        controller=replace(exp.controller, h=h, tau_max=50.0),
        plant=PlantSettings(substeps=10, viscous=0.0, coulomb=0.0, fixed_payload=0.0,
                            extra_payload=0.0))


def _heavier(code: RobotCode) -> dict[str, float]:
    """The plant 20 % heavier and 20 % more inertial than the controllers' nominal model
    (wheel radii unchanged)."""
    return {k: v if k.startswith(("r", "b", "d", "radius")) else 1.2 * v
            for k, v in code.plant_defaults.items()}


@pytest.mark.parametrize("name", CONTROLLERS)
def test_closed_loop_tracks_circle(robot: tuple[str, RobotCode], name: str) -> None:
    """Constant wheel rates (2, 1.5) rad/s from rest, h = 10 ms, 8 s, K1 = K2 = 4 I,
    eps = 0.1, minimal formulation, sample-instant rates and quantised encoders (odometry),
    the plant 20 % heavier and more inertial than the nominal model: the driven wheel angles
    converge and the whole configuration (pose and hitch) follows the reference."""
    _, code = robot
    info = code.controller(name)
    if "minimal" not in info.formulations:
        pytest.skip(f"{name} has no minimal formulation")
    ref = wheel_rate_reference(code, np.zeros(code.nq), np.array([2.0, 1.5]), 0.01, 8.0,
                               code.params)
    exp = _experiment(0.01)
    if info.bounds:
        alpha = roc_bounds(code, code.params, exp.controller.uncertainty, "minimal",
                           exp.controller.roc_max_rate)[0]
        if alpha >= 1.0:
            # A chain of bodies whose lumped inertia coefficients each move ±30 % on their
            # own holds robots far from the nominal one (trailer2: alpha 1.9): ROC has no
            # guarantee there and its C init must refuse the bounds, before any sample.
            result = sim_loop.run(code, name, "minimal", ref, code.params, exp,
                                  plant_params=_heavier(code))
            assert result.failed_at == 0.0 and "BAD_BOUNDS" in str(result.stop_reason)
            assert len(result.t) == 0
            return
    result = sim_loop.run(code, name, "minimal", ref, code.params, exp,
                          plant_params=_heavier(code))
    assert result.failed_at is None
    act = list(code.actuated)
    err = np.linalg.norm(result.q_des[:, act] - result.q[:, act], axis=1)
    assert err[0] == 0.0 and err.max() > 0.1  # it starts at rest behind a moving reference
    # The laws of (24)-(27) servo every coordinate (error dynamics K1, K2): the wheel angles
    # converge. A path tracker (pi) servoes the pose and the wheel rates, not the angles: its
    # wheel angles keep the offset of the start-up (measured 2-6 mrad), its pose converges.
    pose = np.abs(result.q_des[-1, :2] - result.q[-1, :2])
    assert pose.max() < 1e-3, pose
    if "k1" in info.field_names():
        assert err[-1] < 5e-3, err[-1]
    else:
        assert err[-1] < 2e-2, err[-1]
    assert np.max(np.abs(result.q[-1] - ref.q[-1])) < 0.05
    assert abs(ref.q[-1, 2]) > 0.5  # the reference turned: not a vacuous straight line


def test_c_controllers_equal_python(robot: tuple[str, RobotCode], clib: Any) -> None:
    """Each C controller stepped along a closed-loop measurement sequence returns the
    Python mirror's torques (and the same status)."""
    _, code = robot
    ffi, lib = clib.ffi, clib.lib
    h = 0.01
    ref = wheel_rate_reference(code, np.zeros(code.nq), np.array([2.0, 1.5]), h, 1.0,
                               code.params)
    loop = sim_loop.run(code, "tdc", "minimal", ref, code.params, _experiment(h),
                        plant_params=_heavier(code))
    for name in CONTROLLERS:
        py_cfg = _config(code, h)
        py = code.controller_class(name)(py_cfg)
        cfg = ffi.new(f"{code.prefix}_{name}_config_t *")
        cfg.nominal = _c_params(clib, code, code.params)[0]
        for field, _ in ffi.typeof(cfg[0]).fields:  # the struct's, as the registry lists them
            if field != "nominal":
                value = getattr(py_cfg, field)
                setattr(cfg, field, list(value) if isinstance(value, list) else value)
        state = ffi.new(f"{code.prefix}_{name}_state_t *")
        assert getattr(lib, f"{code.prefix}_{name}_init")(state, cfg) == 0
        step = getattr(lib, f"{code.prefix}_{name}_step")
        tau = ffi.new(f"{code.prefix}_real_t[{code.nu}]")
        act = list(code.actuated)
        for k in range(len(loop.t) - 1):
            q = loop.q[k]
            qdot = code.velocities(q, (loop.q[k + 1, act] - q[act]) / h, code.params)
            args = (q, qdot, ref.q[k], ref.qdot[k], ref.qddot[k])
            status = step(state, cfg, *[list(a) for a in args], tau)
            expected = py.step(*args)
            assert status >= 0 and py.last_status.endswith(("_OK", "_SATURATED"))
            np.testing.assert_allclose(list(tau), expected, rtol=1e-10, atol=1e-10)


def test_trailer_forward_dynamics_equals_kkt_of_description() -> None:
    """The generated trailer code (base parameters, minimal-form elimination) against the
    saddle-point solve of (9) in the description's physical parameters."""
    from description_numeric import numeric_description, parameter_vector, rel, trailer

    if "trailer" not in OUTPUT_DIRS:
        pytest.skip("no trailer shipped")
    code = load_robot_code("trailer")
    desc = trailer()
    num = numeric_description(desc)
    p = parameter_vector(num.system, desc)
    worst = 0.0
    for q, _, qdot, tau in num.states(p, seed=3, count=100):
        qdd_kkt, _ = num.kkt_solve(q, qdot, tau, p)
        qdd = code.model.forward_dynamics(q, qdot, tau, code.params)
        worst = max(worst, rel(qdd, qdd_kkt))
    assert worst < 1e-12, worst
