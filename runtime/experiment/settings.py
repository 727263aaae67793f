"""Experiment files (TOML): the paper's setting is the default; every field is checked.

    [controller]   gains and TDROC/ROC/ASMC/PI parameters (paper: K1 = K2 = 4 I, Q = I,
                   a = 0.9, n = 4, eps = 0.1, h = 0.1 s, ROC bounds 30 %)
    [plant]        which plant (``model``: the generated model or the MuJoCo engine),
                   integration rate, wheel friction, payload schedule, and the engine's
                   wheel-ground contact (``friction``, ``tyre_width``, ``contact_timeconst``)
    [sensing]      how wheel angles and rates are measured, and the estimator of q̈(t − h)
                   that (17) pairs with them (see :class:`SensingSettings`)
    [paths]        the circle and the lawn mower: sizes, wheel rates, durations
    [[fault]]      (optional, repeatable) a sensor or actuator fault for
                   ``python -m runtime faults`` (see :mod:`runtime.experiment.faults`)
    robot = "F"    (top level, optional) the robot file the experiment is for, relative to
                   the experiment file; ``reproduce`` then runs it on that robot

A field that is unknown, missing its type, non-finite or out of range is rejected with an
error naming it (``section.field``).

The defaults are the paper's setting for its robot, :data:`PAPER_ROBOT` (Drishti): sizes,
masses, torques and wheel rates are Drishti's. :mod:`runtime.setting.scale` scales the
fields an experiment file leaves at these defaults to any other robot, measuring both
robots on their generated code: no number of Drishti's is typed here.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from runtime.experiment.faults import Fault, FaultSpecError, fault_from_table
from runtime.experiment.physical import SECTION as PHYSICAL_SECTION
from runtime.experiment.physical import (
    PhysicalUncertainty,
    PhysicalUncertaintyError,
    parse_physical,
)


class ExperimentFileError(ValueError):
    """An experiment file that cannot be run; the message names the field."""


# The robot the defaults below are written for (its generated robot.py NAME): scaling an
# experiment to another robot measures both on their generated code.
PAPER_ROBOT = "drishti"


@dataclass(frozen=True)
class ControllerSettings:
    k1: float = 4.0  # K1 = k1 I (paper)
    k2: float = 4.0  # K2 = k2 I
    q_pos: float = 1.0  # Q = I
    q_vel: float = 1.0
    h: float = 0.1  # s, sampling time of Drishti
    eps: float = 0.1
    n: int = 4
    a: float = 0.9
    uncertainty: float = 0.3  # ROC: bounds 30 % above nominal
    roc_max_rate: float = 8.0  # rad/s: ROC's bounds are sampled over wheel rates up to this
    gamma: float = 2.0  # ASMC adaptation rate
    tau_max: float = 40.0  # N m per wheel
    # Traction-aware torque limit (runtime.setting.layout.traction_torque_limit): the floor's
    # friction coefficient to stay under; tau_max becomes min(tau_max, traction_mu N r) with
    # N the driven wheel's load at rest (one load model), lightest over the payload states.
    # 0: off.
    traction_mu: float = 0.0
    # The wheel-velocity PI baseline (modeling.controllers.wheel_pi_law): the path tracker's
    # gains and the wheel loop's bandwidth, from which kp = J bandwidth and
    # ki = kp bandwidth / 4 (J: the wheel inertia of the nominal model's S^T M S).
    pi_kx: float = 1.0  # 1/s
    pi_ky: float = 8.0  # 1/m^2
    pi_ktheta: float = 4.0  # 1/m
    pi_bandwidth: float = 6.0  # rad/s
    # Latency: the torque computed at a sample reaches the wheels delay·h + delay_time
    # later (computation and the link to the drives), each sample's delay within
    # ± (jitter·h + jitter_time) of it (never below 0). The analysis
    # (runtime.stability.sampled_loop) includes the delay in the loop's state, the loop
    # (runtime.sim.loop) applies it.
    delay: float = 0.0  # fraction of h
    delay_time: float = 0.0  # s
    jitter: float = 0.0  # fraction of h
    jitter_time: float = 0.0  # s
    # The measured timing a ros2_control user has (0: not given): the worst sampling period
    # seen (the mean being h) and the worst latency from a sample to its torque. `wmr
    # stability --jitter` proves (or not) the loop for every sequence of periods within
    # ± (worst − h) of h and latencies in [0, worst] (runtime.stability.jitter).
    period_worst: float = 0.0  # s
    latency_worst: float = 0.0  # s

    def delay_seconds(self) -> float:
        """The nominal delay from a sample to its torque at the wheels (s)."""
        return self.delay * self.h + self.delay_time

    def jitter_seconds(self) -> float:
        """The bound on each sample's deviation from :meth:`delay_seconds` (s)."""
        return self.jitter * self.h + self.jitter_time


@dataclass(frozen=True)
class PlantSettings:
    """The simulated robot. ``model`` names the plant (``runtime.sim.plant.PLANTS``):
    ``generated``, the derived model integrated by RK4 in C (ideal rolling: the wheels never
    slip), or ``mujoco``, the MuJoCo engine on the MJCF the toolchain writes from the
    robot's description (``modeling.mjcf_export``; the same inertias, wheels that roll only
    as far as friction lets them). The three contact fields act on ``mujoco`` only:

    * ``friction``: μ, the wheel-ground sliding friction coefficient; a wheel slips when its
      contact force would leave the cone |f_t| ≤ μ N (1: dry rubber on concrete; 0.1: wet
      ice-like floor);
    * ``tyre_width``: 0 (default) gives each wheel one contact point under its centre (a
      sphere), as the derived rolling constraints assume; a width gives two contact points
      ± width/2 from the wheel's mid-plane (a capsule), whose scrub resists turning and
      moves the effective track;
    * ``contact_timeconst``: the contact's softness, MuJoCo's ``solref`` time constant (s):
      larger is softer (deeper sinkage, more creep under traction); at least two
      integration steps (h / substeps) or MuJoCo stiffens it silently.
    ``viscous`` and ``coulomb`` are wheel-bearing friction on both plants (MuJoCo: joint
    damping and frictionloss)."""

    model: str = "generated"  # which Plant simulates the robot (runtime.sim.plant.PLANTS)
    substeps: int = 100  # RK4 steps per control sample (1 kHz at h = 0.1 s)
    viscous: float = 0.05  # N m s/rad per wheel, unknown to the controllers
    coulomb: float = 0.3  # N m per wheel
    fixed_payload: float = 6.0  # kg, rangefinder, always on
    fixed_payload_x: float = -0.05  # m ahead of C (on the axis)
    fixed_payload_y: float = 0.0
    extra_payload: float = 3.0  # kg, added and removed periodically
    extra_payload_x: float = 0.10  # off the robot's axis ...
    extra_payload_y: float = 0.12  # ... to the left: K_lat the model does not have
    extra_on_at: float = 5.0  # s: first time the extra payload is put on
    extra_period: float = 20.0  # s: on for half a period, off for the other half
    friction: float = 1.0  # mujoco: wheel-ground friction coefficient μ
    tyre_width: float = 0.0  # m, mujoco: 0 = point contact, else two points ± width/2
    contact_timeconst: float = 0.005  # s, mujoco: contact softness (solref time constant)

    def extra_on(self, t: float) -> bool:
        """Whether the extra payload is on board at time t."""
        if t < self.extra_on_at:
            return False
        return ((t - self.extra_on_at) % self.extra_period) < self.extra_period / 2


# The plants a closed loop can run on (runtime.sim.plant.PLANTS has one factory each).
PLANT_MODELS = ("generated", "mujoco")
VELOCITY_MODELS = ("sample-instant", "encoder-average", "motor-encoder")
ACCEL_ESTIMATORS = ("matched", "backward", "central")
# accel_estimator of the experiment file -> <PREFIX>_ACCEL_* of the generated configs.
ACCEL_CODES = {"backward": 0, "central": 1, "matched": 2}


@dataclass(frozen=True)
class SensingSettings:
    """How the controller's measurements are made (an open choice of the paper, which only
    says that Drishti has 500-ppr wheel encoders and that h = 100 ms is set by its link).

    ``velocity``:
      * ``sample-instant`` (default): the wheel rate at the sample instant, as a motor drive
        that runs its own fast loop reports it over the link. The paper's h is the link's
        period, not the drive's, so this is the reading closest to Drishti's architecture.
      * ``encoder-average``: the wheel-encoder counts differenced over the whole sample,
        Δθ/h: the mean rate over [t − h, t], half a sample old.
      * ``motor-encoder``: an encoder on the motor side of a ``gear_ratio`` gearbox
        (``encoder_ppr`` per motor revolution), the rate taken over the last ``window`` s.
    Wheel angles (and the odometry pose from them) are always the quantised encoder angles.

    ``accel_estimator`` is q̈(t − h) of (17): ``matched`` (default) pairs the backward
    quotient with the blend of inputs that produced it for this sensing, exact under
    zero-order hold for a constant H1; ``backward`` and ``central`` are the plain quotients.
    """

    velocity: str = "sample-instant"
    encoder_ppr: int = 500  # pulses per revolution, quadrature: 4 counts per pulse
    gear_ratio: float = 20.0  # motor revolutions per wheel revolution (motor-encoder)
    window: float = 0.01  # s, span of the motor-encoder rate (motor-encoder)
    accel_estimator: str = "matched"

    def rate_window(self, h: float) -> float:
        """The span over which the rate is measured: 0, h or ``window``."""
        return {"sample-instant": 0.0, "encoder-average": h}.get(self.velocity, self.window)

    def counts_per_wheel_rev(self) -> float:
        gear = self.gear_ratio if self.velocity == "motor-encoder" else 1.0
        return 4.0 * self.encoder_ppr * gear


@dataclass(frozen=True)
class PathSettings:
    """The paper's two paths (the references are built from them: ``runtime.sim.paths``).

    Circle: the root's frame origin (Drishti's C) on a circle of ``circle_radius`` at the
    angular rate ``circle_rate``, from (R, R) heading along +x. Lawn mower: straight legs
    with both driven wheels at ``lawnmower_fast`` and U-turns with the inner one at
    ``lawnmower_slow``, one leg and turn per ``lawnmower_period`` / 2 on average."""

    circle_duration: float = 30.0
    lawnmower_duration: float = 60.0
    circle_radius: float = 1.5  # m, R1
    circle_rate: float = 0.25  # rad/s, θ̇_d
    lawnmower_fast: float = 3.0  # rad/s, the paper's a
    lawnmower_slow: float = 1.6  # rad/s, the paper's b (< lawnmower_fast)
    lawnmower_period: float = 25.0  # s, the paper's T


@dataclass(frozen=True)
class Experiment:
    controller: ControllerSettings = ControllerSettings()
    plant: PlantSettings = PlantSettings()
    sensing: SensingSettings = SensingSettings()
    paths: PathSettings = PathSettings()
    source: str = "<paper defaults>"
    robot: str | None = None  # robot file named by the experiment (resolved path)
    faults: tuple[Fault, ...] = ()  # [[fault]] tables, in file order
    # [physical_uncertainty] (runtime.experiment.physical): ROC's bounds over these ranges of
    # a bodies-and-wheels robot's masses, inertias, centres of mass instead of the lumped box
    physical: PhysicalUncertainty = field(default_factory=PhysicalUncertainty)


_POSITIVE = {
    "pi_bandwidth",
    "k1",
    "k2",
    "q_pos",
    "q_vel",
    "h",
    "eps",
    "a",
    "tau_max",
    "substeps",
    "encoder_ppr",
    "gear_ratio",
    "window",
    "coulomb_speed",
    "circle_duration",
    "lawnmower_duration",
    "extra_period",
    "roc_max_rate",
    "circle_radius",
    "circle_rate",
    "lawnmower_fast",
    "lawnmower_period",
    "contact_timeconst",
}
_NON_NEGATIVE = {
    "pi_kx",
    "pi_ky",
    "pi_ktheta",
    "uncertainty",
    "gamma",
    "viscous",
    "coulomb",
    "fixed_payload",
    "extra_payload",
    "extra_on_at",
    "lawnmower_slow",
    "friction",
    "tyre_width",
    "traction_mu",
    "delay",
    "delay_time",
    "jitter",
    "jitter_time",
    "period_worst",
    "latency_worst",
}
MAX_DELAY = 4.0  # samples: the largest delay plus jitter an experiment may state


_CHOICES = {"velocity": VELOCITY_MODELS, "accel_estimator": ACCEL_ESTIMATORS,
            "model": PLANT_MODELS}
_MOVED = {"plant.encoder_ppr": "sensing.encoder_ppr"}


def check_number(where: str, label: str, value: Any, *, integer: bool = False,
                 positive: bool = False, non_negative: bool = False,
                 low: float | None = None, high: float | None = None,
                 error: type[ValueError] = ExperimentFileError) -> float:
    """``value`` as a float, checked: a number (not a bool), an integer if asked, finite,
    then the asked bounds; otherwise ``error`` naming the file and the field (shared by the
    experiment and campaign files)."""
    def bad(what: str) -> ValueError:
        return error(f"{where}: field '{label}' must be {what}, got {value!r}")

    if isinstance(value, bool) or not isinstance(value, int | float):
        raise bad("a number")
    if integer and not isinstance(value, int):
        raise bad("an integer")
    if not math.isfinite(value):
        raise bad("finite")
    if positive and value <= 0:
        raise bad("positive")
    if non_negative and value < 0:
        raise bad("non-negative")
    if low is not None and value < low:
        raise bad(f"at least {low:g}")
    if high is not None and value > high:
        raise bad(f"at most {high:g}")
    return float(value)


def _section(where: str, name: str, data: Any, cls: type) -> Any:
    if not isinstance(data, dict):
        raise ExperimentFileError(f"{where}: [{name}] must be a table")
    known = {f.name: f for f in fields(cls)}
    values: dict[str, Any] = {}
    for key, value in data.items():
        label = f"{name}.{key}"
        if label in _MOVED:
            raise ExperimentFileError(
                f"{where}: field '{label}' has moved to '{_MOVED[label]}' ([sensing] section)"
            )
        if label == "plant.engine":
            raise ExperimentFileError(
                f"{where}: field 'plant.engine' is spelled 'plant.model' (one field names "
                f"the plant: {', '.join(repr(m) for m in PLANT_MODELS)})"
            )
        if key not in known:
            raise ExperimentFileError(
                f"{where}: unknown field '{label}' (expected one of {', '.join(known)})"
            )
        if key in _CHOICES:
            if value not in _CHOICES[key]:
                raise ExperimentFileError(
                    f"{where}: field '{label}' must be one of "
                    f"{', '.join(repr(c) for c in _CHOICES[key])}, got {value!r}"
                )
            values[key] = value
            continue
        want_int = known[key].type in ("int", int)
        check_number(where, label, value, integer=want_int, positive=key in _POSITIVE,
                     non_negative=key in _NON_NEGATIVE)
        values[key] = int(value) if want_int else float(value)
    out = replace(cls(), **values)
    if cls is ControllerSettings:
        if not 2 <= out.n <= 8:
            raise ExperimentFileError(f"{where}: field 'controller.n' must be in 2..8, got {out.n}")
        if out.a > 1:
            raise ExperimentFileError(
                f"{where}: field 'controller.a' must be in (0, 1], got {out.a}"
            )
        late = (out.delay_seconds() + out.jitter_seconds()) / out.h
        if late > MAX_DELAY:
            raise ExperimentFileError(
                f"{where}: fields 'controller.delay', 'delay_time', 'jitter' and "
                f"'jitter_time' give {late:.3g} samples of delay plus jitter; at most "
                f"{MAX_DELAY:g} samples of controller.h = {out.h!r} s"
            )
        if out.uncertainty >= 1:
            raise ExperimentFileError(
                f"{where}: field 'controller.uncertainty' must be below 1, got {out.uncertainty}"
            )
    if cls is PathSettings and not out.lawnmower_slow < out.lawnmower_fast:
        raise ExperimentFileError(
            f"{where}: field 'paths.lawnmower_slow' must be below paths.lawnmower_fast = "
            f"{out.lawnmower_fast!r}, got {out.lawnmower_slow!r}"
        )
    return out


def parse_experiment(text: str, where: str = "<string>") -> Experiment:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ExperimentFileError(f"{where}: not valid TOML: {exc}") from None
    sections = {
        "controller": ControllerSettings,
        "plant": PlantSettings,
        "sensing": SensingSettings,
        "paths": PathSettings,
    }
    robot = data.pop("robot", None)
    faults = parse_faults(data.pop("fault", []), where)
    try:
        physical = parse_physical(data.pop(PHYSICAL_SECTION), where) if (
            PHYSICAL_SECTION in data) else PhysicalUncertainty()
    except PhysicalUncertaintyError as exc:
        raise ExperimentFileError(str(exc)) from None
    if robot is not None and (not isinstance(robot, str) or not robot.strip()):
        raise ExperimentFileError(
            f"{where}: field 'robot' must be the path of a robot file, got {robot!r}"
        )
    unknown = sorted(set(data) - set(sections))
    if unknown:
        raise ExperimentFileError(
            f"{where}: unknown section '{unknown[0]}' (expected {', '.join(sections)}, "
            f"[{PHYSICAL_SECTION}], [[fault]], or a top-level robot = \"FILE\")"
        )
    parts = {k: _section(where, k, data.get(k, {}), cls) for k, cls in sections.items()}
    exp = Experiment(**parts, source=where, robot=robot, faults=faults, physical=physical)
    check_sensing(exp, where)
    check_sample_count(exp, where)
    check_contact(exp, where)
    return exp


def check_contact(exp: Experiment, where: str = "<experiment>") -> None:
    """On the MuJoCo plant the contact's time constant must span two integration steps
    (MuJoCo would stiffen a shorter one silently)."""
    pl = exp.plant
    dt = exp.controller.h / pl.substeps
    if pl.model == "mujoco" and pl.contact_timeconst < 2 * dt:
        raise ExperimentFileError(
            f"{where}: field 'plant.contact_timeconst' = {pl.contact_timeconst!r} s must be at "
            f"least two integration steps, 2 controller.h / plant.substeps = {2 * dt:.6g} s"
        )


def parse_faults(data: Any, where: str) -> tuple[Fault, ...]:
    """The ``[[fault]]`` tables; an error names the table by its position."""
    if not isinstance(data, list):
        raise ExperimentFileError(f"{where}: 'fault' must be an array of tables ([[fault]])")
    out = []
    for i, table in enumerate(data, 1):
        try:
            out.append(fault_from_table(table))
        except FaultSpecError as exc:
            raise ExperimentFileError(f"{where}: [[fault]] #{i}: {exc}") from None
    return tuple(out)


MAX_SAMPLES = 1_000_000  # per path: the runs keep every sample in memory


def check_sample_count(exp: Experiment, where: str = "<experiment>") -> None:
    """Each path's duration / h must stay within MAX_SAMPLES (a tiny h would otherwise try
    to allocate gigabytes before the first step)."""
    h = exp.controller.h
    for name in ("circle_duration", "lawnmower_duration"):
        duration = getattr(exp.paths, name)
        if duration / h > MAX_SAMPLES:
            raise ExperimentFileError(
                f"{where}: field 'controller.h' = {h!r} s gives {duration / h:.3g} samples over "
                f"paths.{name} = {duration!r} s; at most {MAX_SAMPLES:,} (raise h or shorten "
                "the path)"
            )


def check_sensing(exp: Experiment, where: str = "<experiment>") -> None:
    """The motor-encoder window must fit in a sample and on the simulator's time grid."""
    sensing, h = exp.sensing, exp.controller.h
    if sensing.velocity != "motor-encoder":
        return
    if sensing.window > h:
        raise ExperimentFileError(
            f"{where}: field 'sensing.window' = {sensing.window!r} s must not exceed the "
            f"sample time controller.h = {h!r} s"
        )
    dt = h / exp.plant.substeps
    steps = sensing.window / dt
    if abs(steps - round(steps)) > 1e-9 * max(1.0, steps):
        raise ExperimentFileError(
            f"{where}: field 'sensing.window' = {sensing.window!r} s must be a multiple of "
            f"the integration step controller.h / plant.substeps = {dt:.6g} s"
        )


def load_experiment(path: str | Path | None = None) -> Experiment:
    """The paper's setting (``None``) or a TOML file overriding some of its fields."""
    if path is None:
        return Experiment()
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ExperimentFileError(f"{p}: experiment file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ExperimentFileError(f"{p}: cannot read experiment file: {exc}") from None
    exp = parse_experiment(text, str(p))
    if exp.robot is not None:  # relative to the experiment file, as a user reads it
        exp = replace(exp, robot=str(p.parent / exp.robot))
    return exp
