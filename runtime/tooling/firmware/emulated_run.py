"""The emulated run: the controller calls of a closed loop (lawn-mower path through
``runtime.sim.loop.run(float32=True)``) recorded, replayed on the emulated Cortex-M4 and on
the host builds (float32 and double), and the torques compared (in ulps and absolute).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from runtime.tooling.firmware.emulator import Emulator


@dataclass(frozen=True)
class Recording:
    """A closed-loop run's controller inputs and outputs, step by step."""

    config: dict[str, Any]
    inputs: list[list[list[float]]]  # per step: q, qdot, q_des, qdot_des, qddot_des
    status: list[int]
    tau: list[list[float]]
    gain: list[float]


def record_closed_loop(
    controller: str = "tdroc", formulation: str = "paper", eps: float = 0.5, float32: bool = True,
    robot: str = "",
) -> Recording:
    """Run the closed loop (:func:`runtime.sim.loop.run`) on the lawn-mower path and record
    every controller call: its configuration, and per step the inputs as the C received
    them (rounded to float for a float32 build), the status, τ and the gain.

    ``robot``: a shipped robot's generated code (``load_robot_code``'s name; "" Drishti,
    whose loop also passes the toolchain's configuration checks). Another robot runs with
    its own parameters as the nominal model and without them: a recording only needs the
    inputs of a consistent closed loop (the trailer's default ±30 % box fails the TDE
    condition, a statement about robustness, not about these inputs)."""
    from modeling.robot_file import load_robot
    from runtime.bindings.config import controller_config
    from runtime.bindings.generated import load_robot_code
    from runtime.experiment.settings import Experiment
    from runtime.sim import loop, paths
    from runtime.sim.plant import library_for
    from runtime.stability.checks import check_configuration

    code = load_robot_code(robot)
    nominal = dict(load_robot().lumped) if not robot else dict(code.params)
    exp = Experiment()
    exp = replace(exp, controller=replace(exp.controller, eps=eps))
    ref = paths.lawnmower(code, nominal, exp)
    if not robot:
        check_configuration(code, controller, formulation, nominal, exp)
    r = loop.run(code, controller, formulation, ref, nominal, exp, float32=float32)
    lib = library_for(code, float32)
    cfg = controller_config(lib, code, controller, formulation, nominal, exp)

    def as_c(v: Any) -> list[float]:
        return [float(np.float32(x)) if float32 else float(x) for x in v]

    inputs = [[as_c(v) for v in (r.q_meas[k], r.qdot_meas[k], ref.q[k], ref.qdot[k],
                                 ref.qddot[k])] for k in range(len(r.t))]
    return Recording(config_values(lib.ffi, cfg), inputs, [int(s) for s in r.status],
                     [[float(x) for x in t] for t in r.tau], [float(g) for g in r.gain])


def config_values(ffi: Any, cfg: Any) -> dict[str, Any]:
    """A controller configuration's values: "params" the nominal parameters in their
    struct's order (for Drishti ``emulator.PARAM_FIELDS``), then every other field by name."""
    fields = [name for name, _ in ffi.typeof(cfg.nominal).fields]
    out: dict[str, Any] = {"params": [float(getattr(cfg.nominal, p)) for p in fields]}
    for name, _ in ffi.typeof(cfg[0]).fields:
        if name == "nominal":
            continue
        value = getattr(cfg, name)
        out[name] = [float(x) for x in value] if isinstance(value, ffi.CData) else value
    return out


def tdroc_config(ffi: Any, values: dict[str, Any], prefix: str = "wmr") -> Any:
    """A ``<prefix>_tdroc_config_t *`` of ``ffi`` holding :func:`config_values`'
    ``values``."""
    cfg = ffi.new(f"{prefix}_tdroc_config_t *")
    fields = [name for name, _ in ffi.typeof(cfg.nominal).fields]
    for p, value in zip(fields, values["params"], strict=True):
        setattr(cfg.nominal, p, value)
    for name, value in values.items():
        if name != "params":
            setattr(cfg, name, value)
    return cfg


def replay_host(rec: Recording, float32: bool) -> tuple[list[int], list[list[float]], list[float]]:
    """The recorded inputs through the host build (cffi, the bindings' controller wrapper),
    TDROC: (status, tau, gain)."""
    from runtime.bindings import cbuild
    from runtime.bindings.controller import Controller

    lib = cbuild.build(float32)
    ctl = Controller(lib, "wmr", "tdroc", tdroc_config(lib.ffi, rec.config), 5, 2)
    if ctl.init() != 0:
        raise RuntimeError("host init failed")
    statuses, taus, gains = [], [], []
    for inputs in rec.inputs:
        statuses.append(ctl.step(inputs))
        taus.append([float(ctl.tau[0]), float(ctl.tau[1])])
        gains.append(float(ctl.state.gain))
    return statuses, taus, gains


@dataclass(frozen=True)
class EmulationResult:
    steps: int
    instructions: list[int]
    stack_bytes: int  # high-water mark over all steps (measured)
    init_instructions: int
    status: list[int]
    tau: list[list[float]]
    gain: list[float]


def emulate(rec: Recording, elf: Path, binary: Path) -> EmulationResult:
    emu = Emulator(elf, binary)
    cfg = rec.config
    emu.write("params", cfg["params"])
    for name in ("k1", "k2"):
        emu.write(name, cfg[name])
    for name in (
        "q_pos",
        "q_vel",
        "h",
        "tau_max",
        "eps",
        "a",
        "formulation",
        "accel_estimator",
        "n",
    ):
        emu.write(name, [cfg[name]])
    init_insns, _ = emu.call("harness_init")
    if emu.read("status")[0] != 0:
        raise RuntimeError(f"emulated init failed: {emu.read('status')[0]}")
    counts, stack, status, taus, gains = [], 0, [], [], []
    for inputs in rec.inputs:
        emu.write("in", [x for v in inputs for x in v])
        n, used = emu.call("harness_step")
        counts.append(n)
        stack = max(stack, used)
        status.append(int(emu.read("status")[0]))
        taus.append(list(emu.read("tau")))
        gains.append(float(emu.read("gain")[0]))
    return EmulationResult(len(counts), counts, stack, init_insns, status, taus, gains)


def ulps(a: float, b: float) -> int:
    """Distance between two float32 values in units in the last place."""

    def ordered(x: float) -> int:
        i: int = struct.unpack("<i", struct.pack("<f", x))[0]
        return i if i >= 0 else -(i & 0x7FFFFFFF)

    if math.isnan(a) or math.isnan(b):
        return 2**31
    return abs(ordered(a) - ordered(b))


@dataclass(frozen=True)
class Comparison:
    max_ulps: int  # ARM vs host float32, torques
    median_ulps: float
    max_abs_vs_float: float
    scale_ulps_vs_float: float  # max abs difference in ulps of the run's largest |torque|
    torque_scale: float  # the run's largest |torque| (host double) [N m]
    max_abs_vs_double: float  # ARM vs host double, torques [N m]
    max_rel_vs_double: float  # relative to max |tau| of the run
    host_float_reproduces_loop: bool
    same_status: bool


def compare(rec: Recording, emu: EmulationResult) -> Comparison:
    s_f, tau_f, _ = replay_host(rec, True)
    s_d, tau_d, _ = replay_host(rec, False)
    arm = np.array(emu.tau)
    tf, td = np.array(tau_f), np.array(tau_d)
    dist = [ulps(a, b) for a, b in zip(arm.ravel(), tf.ravel(), strict=True)]
    scale = float(np.max(np.abs(td)))
    return Comparison(
        max_ulps=max(dist),
        median_ulps=float(np.median(dist)),
        max_abs_vs_float=float(np.max(np.abs(arm - tf))),
        scale_ulps_vs_float=float(np.max(np.abs(arm - tf)) / np.spacing(np.float32(scale))),
        torque_scale=scale,
        max_abs_vs_double=float(np.max(np.abs(arm - td))),
        max_rel_vs_double=float(np.max(np.abs(arm - td)) / scale),
        host_float_reproduces_loop=tau_f == rec.tau and s_f == rec.status,
        same_status=emu.status == s_f == s_d,
    )
