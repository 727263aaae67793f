"""The one reproduce driver (``wmr reproduce``), for every robot: the paper's experiment
(Section "Experimental results and comparison") run on the setting's robot, with the
experiment scaled to it (:mod:`runtime.setting.scale`; the identity on the paper's robot).

For each sensing model chosen (default: ``sample-instant`` and ``encoder-average``, see
:class:`runtime.experiment.settings.SensingSettings`; the experiment's other ``[sensing]``
fields, the estimator of q̈(t − h) in (17) among them, apply to each): 2 paths (circle, lawn
mower) × every controller generated for the robot × every formulation it has, closed loop
through the generated C (:mod:`runtime.sim.loop`), payload put on and taken off, friction
the controllers do not know. The same code for every robot:

* each run through :func:`runtime.reproduction.runs.checked_run` (a configuration the
  checks refuse is not run), on the experiment's plant under the slip monitor
  (:mod:`runtime.sim.slip_monitor`) where the robot's layout can be had;
* each run's :class:`Metrics`, with its outcome (:mod:`runtime.sim.outcome`: a run off
  its path is not ``ok``).

The paper's extras are switched on by the setting, not by another driver: on the paper's
robot (:attr:`runtime.setting.robot.Setting.is_paper_robot`, declared in the generated
``robot.py``) :func:`reproduce` also sweeps TDROC's boundary layer ε of (25) per sensing
model, and, when ``encoder-average`` is chosen, with the plain ``backward`` estimator: the
pairing that made TDROC unstable at ε = 0.1 before the matched estimator existed.

Nothing is written here: :mod:`runtime.reproduction.robot_report` writes any robot's
report, :mod:`runtime.paper` the paper's tables, verdicts, report and figures. Nothing
computed depends on the clock but :attr:`Reproduction.seconds` (printed, never written).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.reproduction.runs import checked_run
from runtime.setting.layout import robot_layout
from runtime.setting.robot import Setting
from runtime.sim import paths
from runtime.sim.loop import Run
from runtime.sim.outcome import outcome
from runtime.sim.reference import Reference
from runtime.sim.slip_monitor import MonitoredPlant, SlipMonitor

DEFAULT_SENSINGS = ("sample-instant", "encoder-average")
EPS_SWEEP = (0.1, 0.2, 0.5, 1.0)
# The contrast of the ε sweep: encoder-average rates with the plain backward quotient.
CONTRAST = ("encoder-average", "backward")
# A TDROC run is called unstable when its RMS error exceeds this multiple of TDC's under
# the same sensing, estimator and path (the measured unstable runs are ≥ 50× TDC's).
UNSTABLE_FACTOR = 10.0
# One colour per controller, in the registry's order (TDC blue, TDROC red, ROC green, ASMC
# purple, ...), in every robot's figures.
PALETTE = ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown",
           "tab:pink", "tab:olive", "tab:cyan")

RunKey = tuple[str, str, str, str]  # (sensing, controller, formulation, path)
SweepKey = tuple[str, str, float, str]  # (sensing, estimator, ε, path)


def labels(code: RobotCode) -> dict[str, str]:
    """Each controller's label (``tdroc`` → ``TDROC``), in the registry's order."""
    return {c.name: c.label for c in code.controller_infos}


def colors(code: RobotCode) -> dict[str, str]:
    """Each controller's colour in the figures, from :data:`PALETTE` in the registry's
    order."""
    return {c.name: PALETTE[i % len(PALETTE)] for i, c in enumerate(code.controller_infos)}


@dataclass(frozen=True)
class Metrics:
    """One run's numbers (a row of the metrics tables)."""

    sensing: str  # velocity model of [sensing]
    controller: str
    formulation: str
    path: str
    rms_error: float  # m, the root frame origin's distance from its reference
    max_error: float  # m
    final_error: float  # m
    rms_percent: float  # RMS error in % of the path's scale (R1, or the lawn-mower legs)
    rms_torque: float  # N m
    max_torque: float  # N m, max |τ|
    torque_variation: float  # N m, total variation of tau (chattering)
    median_gain: float  # k̂: units of the switching term Δu_a (see figures.GAIN_UNIT)
    max_gain: float
    saturated_steps: int
    discarded_u: float  # RMS of ||u rows 1-3|| (paper formulation)
    failed_at: float | None
    status: str  # the outcome: ok, off path, failed, (init) refused (runtime.sim.outcome)
    detail: str  # why it is not ok
    # The slip monitor (runtime.sim.slip_monitor): the largest friction coefficient the run
    # needs, max over samples and driven wheels of sqrt(F_x² + F_y²)/N (NaN: not monitored).
    friction_needed: float = float("nan")


def rms(x: np.ndarray) -> float:
    """Root mean square (NaN for a run with no sample: refused)."""
    return float(np.sqrt(np.mean(x**2))) if len(x) else float("nan")


def metrics(r: Run, ref: Reference, sensing: str,
            friction_needed: float = float("nan")) -> Metrics:
    """The metrics of one run on ``ref``: position error ‖(x_c, y_c) − (x_dc, y_dc)‖ (in %
    of the reference's scale: R1 for the circle, the spacing of the lawn mower's legs; the
    paper's figures use the paper's own scales), torque, k̂, and the run's outcome."""
    e = r.position_error
    result = outcome(r, ref.scale)
    if not len(e):  # refused: no sample ran
        nan = float("nan")
        return Metrics(sensing, r.controller, r.formulation, r.path, nan, nan, nan, nan, nan,
                       nan, nan, nan, nan, 0, nan, r.failed_at, result.status, result.detail,
                       friction_needed)
    return Metrics(
        sensing=sensing,
        controller=r.controller,
        formulation=r.formulation,
        path=r.path,
        rms_error=rms(e),
        max_error=float(e.max()),
        final_error=float(e[-1]),
        rms_percent=100.0 * rms(e) / ref.scale,
        rms_torque=rms(r.tau),
        max_torque=float(np.abs(r.tau).max()),
        torque_variation=float(np.abs(np.diff(r.tau, axis=0)).sum()),
        median_gain=float(np.median(r.gain)),
        max_gain=float(r.gain.max()),
        saturated_steps=r.saturated,
        discarded_u=rms(r.u_discarded),
        failed_at=r.failed_at,
        status=result.status,
        detail=result.detail,
        friction_needed=friction_needed,
    )


@dataclass(frozen=True)
class SweepRow:
    """TDROC (paper formulation) at one ε of (25) under one sensing and estimator, beside
    TDC's RMS error under the same sensing, estimator and path."""

    sensing: str
    estimator: str
    eps: float
    metrics: Metrics
    tdc_rms: float  # m

    @property
    def ratio(self) -> float:
        return self.metrics.rms_error / self.tdc_rms

    @property
    def stable(self) -> bool:
        """RMS error within ``UNSTABLE_FACTOR`` × TDC's, no failure."""
        return self.ratio <= UNSTABLE_FACTOR and self.metrics.failed_at is None


@dataclass(frozen=True)
class Reproduction:
    """The runs on the setting's robot; ``sweep`` and ``sweep_runs`` are the paper's extras
    (empty on another robot)."""

    setting: Setting  # the robot and its (scaled) experiment, as run
    sensings: tuple[str, ...]
    refs: dict[str, Reference]
    runs: dict[RunKey, Run]
    table: list[Metrics]  # in the order run: sensing, path, (formulation, controller)
    seconds: float  # simulation wall time (printed, never written to a file)
    sweep: list[SweepRow] = field(default_factory=list)
    sweep_runs: dict[SweepKey, Run] = field(default_factory=dict)  # TDROC, paper formulation

    @property
    def experiment(self) -> Experiment:
        """The experiment as run (per-sensing copies from :meth:`experiment_for`)."""
        return self.setting.experiment

    @property
    def code(self) -> RobotCode:
        return self.setting.robot.code

    @property
    def robot(self) -> dict[str, float]:
        """The controllers' nominal parameters."""
        return self.setting.robot.nominal

    @property
    def labels(self) -> dict[str, str]:
        return labels(self.code)

    @property
    def colors(self) -> dict[str, str]:
        return colors(self.code)

    def controllers(self, formulation: str = "paper") -> tuple[str, ...]:
        """The controllers run in ``formulation``, in the registry's order."""
        return tuple(c.name for f, c in self.code.runs((formulation,)))

    def switching(self, formulation: str = "paper") -> tuple[str, ...]:
        """Those with a switching term (24)/(25)."""
        return tuple(c.name for f, c in self.code.runs((formulation,)) if c.switching)

    def experiment_for(self, sensing: str, estimator: str | None = None) -> Experiment:
        return with_sensing(self.experiment, sensing, estimator)

    @property
    def estimator(self) -> str:
        return self.experiment.sensing.accel_estimator

    def rows(self, sensing: str) -> list[Metrics]:
        return [m for m in self.table if m.sensing == sensing]

    def sweep_sets(self) -> list[tuple[str, str]]:
        """The (sensing, estimator) pairs of the sweep, in order."""
        return list(dict.fromkeys((s.sensing, s.estimator) for s in self.sweep))

    def contrast(self) -> tuple[str, str] | None:
        """The encoder-average/backward set, when it was run."""
        return CONTRAST if CONTRAST in self.sweep_sets() else None


def with_sensing(exp: Experiment, velocity: str, estimator: str | None = None) -> Experiment:
    """``exp`` with [sensing] velocity (and optionally accel_estimator) replaced."""
    est = estimator or exp.sensing.accel_estimator
    return replace(exp, sensing=replace(exp.sensing, velocity=velocity, accel_estimator=est))


def with_eps(exp: Experiment, eps: float) -> Experiment:
    return replace(exp, controller=replace(exp.controller, eps=eps))


class _Simulator:
    """Runs each distinct (sensing, estimator, ε, controller, formulation, path) once, on the
    setting's robot: the controllers get its nominal parameters, the plant its simulated
    ones."""

    def __init__(self, setting: Setting, refs: dict[str, Reference]):
        setup = setting.robot
        self.code, self.exp, self.refs = setup.code, setting.experiment, refs
        self.nominal, self.plant = setup.nominal, setup.plant
        self.cache: dict[tuple[str, str, float, str, str, str], Run] = {}
        self.needed: dict[int, float] = {}  # id(run) -> friction coefficient it needs
        self.monitor = slip_monitor(self.code, self.exp, {**self.nominal, **self.plant})

    def __call__(
        self, sensing: str, estimator: str, eps: float, ctrl: str, form: str, path: str
    ) -> Run:
        if not self.code.controller(ctrl).switching:  # ε enters only a switching term
            eps = self.exp.controller.eps
        key = (sensing, estimator, eps, ctrl, form, path)
        if key not in self.cache:
            e = with_eps(with_sensing(self.exp, sensing, estimator), eps)
            plant = None
            if self.monitor is not None:
                plant = MonitoredPlant(plant_for(self.code, e, self.nominal, self.plant),
                                       self.monitor)
            run = checked_run(self.code, ctrl, form, self.refs[path], self.nominal, e,
                              plant_params=self.plant, plant=plant)
            if plant is not None and plant.needed:
                self.needed[id(run)] = float(np.max(plant.needed))
            self.cache[key] = run
        return self.cache[key]

    def friction_needed(self, run: Run) -> float:
        return self.needed.get(id(run), float("nan"))


def slip_monitor(code: RobotCode, exp: Experiment, robot: Mapping[str, float]
                 ) -> SlipMonitor | None:
    """The slip monitor of the runs on the simulated robot ``robot`` (plant-only parameters
    at the robot's defaults unless given; None where its layout cannot be had at these
    parameters: a bodies-and-wheels robot with drawn parameters)."""
    try:
        return SlipMonitor(code, robot_layout(code, {**code.plant_defaults, **robot}), exp)
    except ValueError:
        return None


def sweep_sets(exp: Experiment, sensings: Sequence[str]) -> list[tuple[str, str]]:
    """Each sensing with the experiment's estimator, plus encoder-average/backward when
    encoder-average is chosen and the experiment's estimator is not already backward."""
    est = exp.sensing.accel_estimator
    sets = [(s, est) for s in sensings]
    if CONTRAST[0] in sensings and CONTRAST not in sets:
        sets.append(CONTRAST)
    return sets


def sweep_eps(exp: Experiment) -> tuple[float, ...]:
    """EPS_SWEEP, with the experiment's ε added if it is not in it."""
    return tuple(sorted({*EPS_SWEEP, exp.controller.eps}))


def reproduce(setting: Setting, sensings: Sequence[str] = DEFAULT_SENSINGS,
              progress: bool = False) -> Reproduction:
    """Run the experiment on the setting's robot (no files written); on the paper's robot,
    TDROC's ε sweep too."""
    start = time.perf_counter()
    code, exp = setting.robot.code, setting.experiment
    est, eps0 = exp.sensing.accel_estimator, exp.controller.eps
    refs = {name: paths.reference(code, setting.robot.nominal, exp, name)
            for name in paths.PATHS}
    sim = _Simulator(setting, refs)
    runs: dict[RunKey, Run] = {}
    table: list[Metrics] = []
    pairs = code.runs()
    total = len(sensings) * len(refs) * len(pairs)
    for sensing in sensings:
        for path in refs:
            for form, info in pairs:
                r = sim(sensing, est, eps0, info.name, form, path)
                runs[(sensing, info.name, form, path)] = r
                table.append(metrics(r, refs[path], sensing, sim.friction_needed(r)))
                if progress:
                    m = table[-1]
                    print(f"[{len(table):2d}/{total}] {sensing:15s} {path:9s} {form:7s} "
                          f"{info.label:5s} RMS {m.rms_error * 1000:9.2f} mm {m.status}",
                          flush=True)
    sweep: list[SweepRow] = []
    sweep_runs: dict[SweepKey, Run] = {}
    for sensing, estimator in sweep_sets(exp, sensings) if setting.is_paper_robot else ():
        for eps in sweep_eps(exp):
            for path in refs:
                r = sim(sensing, estimator, eps, "tdroc", "paper", path)
                tdc = sim(sensing, estimator, eps0, "tdc", "paper", path)
                sweep_runs[(sensing, estimator, eps, path)] = r
                sweep.append(SweepRow(sensing, estimator, eps, metrics(r, refs[path], sensing),
                                      rms(tdc.position_error)))
    return Reproduction(setting, tuple(sensings), refs, runs, table,
                        time.perf_counter() - start, sweep, sweep_runs)
