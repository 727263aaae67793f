"""``python -m runtime reproduce``: the paper's experiments (Section "Experimental results
and comparison") on its robot, with figures, a metrics table and a report. This module runs
them; the outputs are built by the modules of the floors above it:

* :mod:`runtime.reproduction.paper` (here): the runs, their :class:`Metrics` and TDROC's ε
  sweep, gathered in a :class:`Reproduction` by :func:`reproduce` (no files written); each
  run through :func:`runtime.reproduction.runs.checked_run`, as on any robot (a
  configuration the checks refuse is not run);
* :mod:`runtime.paper.reproduction_tables`: ``metrics.md`` and ``metrics.csv``;
* :mod:`runtime.paper.reproduction_verdicts`: the paper's claims and the stability bounds,
  evaluated on the runs;
* :mod:`runtime.paper.reproduction_report`: ``REPORT.md``;
* :mod:`runtime.paper.figures`: the figures;
* :mod:`runtime.commands.reproduce`: the command line, which writes them all.

For each sensing model chosen with ``--sensing`` (default: ``sample-instant`` and
``encoder-average``, see :class:`runtime.experiment.settings.SensingSettings`; the experiment file's
other ``[sensing]`` fields, the estimator of q̈(t − h) in (17) among them, apply to each):
2 paths (circle, lawn mower) × 4 controllers (TDC, TDROC, ROC, ASMC) × 2 formulations
(paper, minimal), closed loop through the generated C. Then a sweep of TDROC's boundary
layer ε of (25) per sensing model, and, when ``encoder-average`` is chosen, the same sweep
with the plain ``backward`` estimator: the pairing that made TDROC unstable at ε = 0.1
before the matched estimator existed.

Written to the output folder (default ``docs/reproduction``): the figures of
:mod:`runtime.paper.figures` (PNG), ``metrics.csv``, ``metrics.md`` and ``REPORT.md``. Nothing
written depends on the wall time or the machine's clock, so two runs give the same bytes.
The wall time (:attr:`Reproduction.seconds`) is printed on the console only.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from modeling.package_paths import default_output
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.reproduction.robot import PALETTE
from runtime.reproduction.runs import checked_run
from runtime.setting.layout import robot_layout
from runtime.sim import paths
from runtime.sim.loop import Run
from runtime.sim.reference import Reference
from runtime.sim.slip_monitor import MonitoredPlant, SlipMonitor


@dataclass(frozen=True)
class Figure:
    """A written figure: its file, the title (naming the paper's figure) and a caption."""

    path: Path
    title: str
    caption: str


DEFAULT_OUT = default_output("docs/reproduction")  # ./reproduction when installed
DEFAULT_SENSINGS = ("sample-instant", "encoder-average")
EPS_SWEEP = (0.1, 0.2, 0.5, 1.0)
FORMULATIONS = ("paper", "minimal")
# The contrast of the ε sweep: encoder-average rates with the plain backward quotient.
CONTRAST = ("encoder-average", "backward")
# A TDROC run is called unstable when its RMS error exceeds this multiple of TDC's under
# the same sensing, estimator and path (the measured unstable runs are ≥ 50× TDC's).
UNSTABLE_FACTOR = 10.0
PAPER_CODE = load_robot_code("")  # the paper's robot: the default generated code
LABELS = {c.name: c.label for c in PAPER_CODE.controller_infos}
# One colour per controller, in the registry's order (TDC blue, TDROC red, ROC green, ASMC
# purple).
COLORS = {name: PALETTE[i % len(PALETTE)] for i, name in enumerate(LABELS)}

RunKey = tuple[str, str, str, str]  # (sensing, controller, formulation, path)
SweepKey = tuple[str, str, float, str]  # (sensing, estimator, ε, path)


@dataclass(frozen=True)
class Metrics:
    """One run's numbers (the row of ``metrics.csv``)."""

    sensing: str  # velocity model of [sensing]
    controller: str
    formulation: str
    path: str
    rms_error: float  # m
    max_error: float  # m
    rms_percent: float  # RMS error in % of the path's scale (R1, or the lawn-mower legs)
    rms_torque: float  # N m
    torque_variation: float  # N m, total variation of tau (chattering)
    median_gain: float  # k̂: units of the switching term Δu_a (see figures.GAIN_UNIT)
    max_gain: float
    saturated_steps: int
    discarded_u: float  # RMS of ||u rows 1-3|| (paper formulation)
    failed_at: float | None
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
    figures use the paper's own scales), torque, k̂."""
    e = r.position_error
    if not len(e):  # refused: no sample ran
        nan = float("nan")
        return Metrics(sensing, r.controller, r.formulation, r.path, nan, nan, nan, nan, nan,
                       nan, nan, 0, nan, r.failed_at, friction_needed)
    return Metrics(
        sensing=sensing,
        controller=r.controller,
        formulation=r.formulation,
        path=r.path,
        rms_error=rms(e),
        max_error=float(e.max()),
        rms_percent=100.0 * rms(e) / ref.scale,
        rms_torque=rms(r.tau),
        torque_variation=float(np.abs(np.diff(r.tau, axis=0)).sum()),
        median_gain=float(np.median(r.gain)),
        max_gain=float(r.gain.max()),
        saturated_steps=r.saturated,
        discarded_u=rms(r.u_discarded),
        failed_at=r.failed_at,
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
    experiment: Experiment  # as loaded; per-sensing copies from :meth:`experiment_for`
    sensings: tuple[str, ...]
    refs: dict[str, Reference]
    runs: dict[RunKey, Run]
    table: list[Metrics]
    sweep: list[SweepRow]
    sweep_runs: dict[SweepKey, Run]  # TDROC, paper formulation
    seconds: float  # simulation wall time (printed, never written to a file)
    robot: dict[str, float] = field(default_factory=dict)
    code: RobotCode = PAPER_CODE

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
    """Runs each distinct (sensing, estimator, ε, controller, formulation, path) once."""

    def __init__(
        self, code: RobotCode, exp: Experiment, robot: dict[str, float],
        refs: dict[str, Reference]
    ):
        self.code, self.exp, self.robot, self.refs = code, exp, robot, refs
        self.cache: dict[tuple[str, str, float, str, str, str], Run] = {}
        self.needed: dict[int, float] = {}  # id(run) -> friction coefficient it needs
        self.monitor = slip_monitor(code, exp, robot)

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
                plant = MonitoredPlant(plant_for(self.code, e, self.robot), self.monitor)
            run = checked_run(self.code, ctrl, form, self.refs[path], self.robot, e,
                              plant=plant)
            if plant is not None and plant.needed:
                self.needed[id(run)] = float(np.max(plant.needed))
            self.cache[key] = run
        return self.cache[key]

    def friction_needed(self, run: Run) -> float:
        return self.needed.get(id(run), float("nan"))


def slip_monitor(code: RobotCode, exp: Experiment, robot: dict[str, float]
                 ) -> SlipMonitor | None:
    """The slip monitor of the runs (None where the robot's layout cannot be had at these
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


def reproduce(
    exp: Experiment,
    robot: dict[str, float] | None = None,
    progress: bool = False,
    sensings: Sequence[str] = DEFAULT_SENSINGS,
    code: RobotCode = PAPER_CODE,
) -> Reproduction:
    """Run every experiment (no files written) on the robot ``code`` with the nominal and
    simulated parameters ``robot`` (default: the paper's robot's own)."""
    start = time.perf_counter()
    robot = dict(robot or code.params)
    est, eps0 = exp.sensing.accel_estimator, exp.controller.eps
    refs = {name: paths.reference(code, robot, exp, name) for name in paths.PATHS}
    sim = _Simulator(code, exp, robot, refs)
    runs: dict[RunKey, Run] = {}
    table: list[Metrics] = []
    pairs = code.runs(FORMULATIONS)
    total = len(sensings) * len(refs) * len(pairs)
    for sensing in sensings:
        for path in refs:
            for form, info in pairs:
                r = sim(sensing, est, eps0, info.name, form, path)
                runs[(sensing, info.name, form, path)] = r
                table.append(metrics(r, refs[path], sensing, sim.friction_needed(r)))
                if progress:
                    m = table[-1]
                    print(
                        f"[{len(table):2d}/{total}] {sensing:15s} {path:9s} {form:7s} "
                        f"{info.label:5s} RMS {m.rms_error * 1000:8.2f} mm",
                        flush=True,
                    )
    sweep: list[SweepRow] = []
    sweep_runs: dict[SweepKey, Run] = {}
    for sensing, estimator in sweep_sets(exp, sensings):
        for eps in sweep_eps(exp):
            for path in refs:
                r = sim(sensing, estimator, eps, "tdroc", "paper", path)
                tdc = sim(sensing, estimator, eps0, "tdc", "paper", path)
                sweep_runs[(sensing, estimator, eps, path)] = r
                sweep.append(
                    SweepRow(sensing, estimator, eps, metrics(r, refs[path], sensing),
                             rms(tdc.position_error))
                )
    seconds = time.perf_counter() - start
    return Reproduction(exp, tuple(sensings), refs, runs, table, sweep, sweep_runs, seconds, robot,
                        code)
