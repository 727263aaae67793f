"""``wmr faults``: what each controller reports under sensor and actuator faults, and how
many samples it needs to recover, on any robot with two driven wheels.

Each fault (``runtime.experiment.faults``; the experiment file's ``[[fault]]`` tables, or
:data:`DEFAULT_FAULTS`) is injected into the closed loop (``runtime.sim.loop``) on the
paper's circle scaled to the robot, for each controller generated for it in each
formulation, beside the same run without the fault. Per run the table gives:

* **status**: what ``<prefix>_<ctrl>_step`` returned from the fault's onset to the end of
  the run, by name (read from the generated ``STATUS``), other than ``<PREFIX>_OK``; ``not
  called`` counts the dropped samples;
* **monitors**: which of the runtime's fault monitors (:data:`MONITORS`, computed from what
  the control task sees) flagged it, with the delay in samples from the onset;
* **peak error**: the largest true position error ‖(x_c, y_c) − (x_dc, y_dc)‖ from the onset
  on, beside the fault-free run's over the same samples;
* **recovery**: samples after the fault's last sample until the error is back within
  :func:`tolerance` of the fault-free run and stays there (:func:`recovery_samples`), for the
  true position and for the position the odometry measures;
* **verdict**: recovered, bounded but not recovered (with the error at the end), or diverged
  (the run stopped on a status < 0 or a non-finite state).

Written: ``FAULTS.md`` and ``faults.csv`` (default folder: ``docs`` for the paper's robot,
``faults/<robot>`` for another; the command line is :mod:`runtime.commands.faults`); the
same inputs give the same bytes.
"""

from __future__ import annotations

import csv
import io
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from modeling import audit
from modeling.package_paths import default_output
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.faults import Fault
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.sim.loop import NOT_CALLED, Run
from runtime.sim.plant import spin_inertia_keys

DEFAULT_OUT = default_output("docs")  # the working directory when installed

FAULT_START = 8.0  # s on the circle: past the start-up transient, the extra payload on
DEFAULT_FAULTS: tuple[Fault, ...] = (
    Fault("encoder-glitch", FAULT_START, 0.0, 50, "right"),
    Fault("encoder-glitch", FAULT_START, 0.1, 50, "right"),
    Fault("dropped-sample", FAULT_START, 0.3),
    Fault("repeated-sample", FAULT_START, 0.0),
    Fault("traction-loss", FAULT_START, 0.3, 1.0, "right"),
    Fault("torque-saturation", FAULT_START, 1.0, 0.3, "both"),
)

# Recovery: |e| <= FACTOR * (fault-free |e| maximised over ±WINDOW samples) + SLACK, from
# the recovery sample to the end of the run, which must leave at least MIN_TAIL samples.
FACTOR = 1.1
SLACK = 1e-3  # m
WINDOW = 5
MIN_TAIL = 20

# Monitors: thresholds calibrated on the fault-free run of the same controller, as a
# firmware's would be at commissioning: CAL_FACTOR × its largest value after SETTLE s.
CAL_FACTOR = 2.0
SETTLE = 2.0  # s
ENCODER_FLOOR = 4.0  # counts: the encoder monitor never flags less
TORQUE_TOL = 1e-3  # N m
MONITORS = {
    "encoder": "encoder–rate residual: |Δθ − Δk h (ω_k + ω_prev)/2| between called samples "
    "(counts; Δk samples apart), above max(CAL_FACTOR × fault-free, ENCODER_FLOOR)",
    "tracking": "the controller's own ‖(e, ė)‖ above CAL_FACTOR × its fault-free maximum",
    "torque": "commanded minus delivered torque above TORQUE_TOL (needs the drive to report "
    "its torque, e.g. motor current)",
}


def status_names(code: RobotCode) -> dict[int, str]:
    """Status code -> name, from the generated modules (never typed here)."""
    return {value: name for name, value in code.controllers.STATUS.items()}


def tolerance(base: NDArray[np.float64], window: int = WINDOW) -> NDArray[np.float64]:
    """The band a faulted run must return to: FACTOR × the fault-free error's envelope
    (its maximum over ±``window`` samples) + SLACK."""
    n = len(base)
    env = np.array([base[max(0, j - window) : j + window + 1].max() for j in range(n)])
    return FACTOR * env + SLACK


def recovery_samples(
    err: NDArray[np.float64],
    base: NDArray[np.float64],
    k_end: int,
    window: int = WINDOW,
    min_tail: int = MIN_TAIL,
) -> int | None:
    """Samples from ``k_end`` (the first sample after the fault) until ``err`` is within
    :func:`tolerance` of ``base`` and stays there to the end; 0 if it never left it; None if
    it is not back at least ``min_tail`` samples before the end (or the run is shorter than
    ``base``: it stopped)."""
    if len(err) < len(base):
        return None
    tol = tolerance(base, window)
    outside = np.nonzero(err[k_end:] > tol[k_end:])[0]
    if len(outside) == 0:
        return 0
    k_rec = k_end + int(outside[-1]) + 1
    if k_rec > len(err) - min_tail:
        return None
    return k_rec - k_end


def encoder_residual(r: Run, counts_per_rad: float, h: float,
                     actuated: tuple[int, ...]) -> NDArray[np.float64]:
    """Per sample, the largest |Δθ − Δk h (ω_k + ω_prev)/2| over the driven wheels (their
    indices in q: ``actuated``) in counts, between consecutive called samples (0 where not
    evaluated)."""
    wheels = list(actuated)
    out = np.zeros(len(r.t))
    prev: int | None = None
    for k in range(1, len(r.t)):
        if r.status[k] == NOT_CALLED:
            continue
        if prev is not None and prev > 0:
            dk = k - prev
            dtheta = r.q_meas[k, wheels] - r.q_meas[prev, wheels]
            mean_rate = (r.qdot_meas[k, wheels] + r.qdot_meas[prev, wheels]) / 2
            out[k] = float(np.abs(dtheta - dk * h * mean_rate).max() * counts_per_rad)
        prev = k
    return out


@dataclass(frozen=True)
class Monitors:
    """Per-sample monitor signals of one run and the thresholds from the fault-free run
    (``actuated``: the driven wheels' indices in q)."""

    signals: dict[str, NDArray[np.float64]]
    thresholds: dict[str, float]
    actuated: tuple[int, ...]

    @classmethod
    def calibrate(cls, base: Run, exp: Experiment, actuated: tuple[int, ...]) -> Monitors:
        h = exp.controller.h
        settle = base.t >= SETTLE
        enc = encoder_residual(base, counts_per_rad(exp), h, actuated)
        return cls(
            {},
            {
                "encoder": max(CAL_FACTOR * float(enc[settle].max()), ENCODER_FLOOR),
                "tracking": CAL_FACTOR * float(base.error_norm[settle].max()),
                "torque": TORQUE_TOL,
            },
            actuated,
        )

    def signals_of(self, r: Run, exp: Experiment) -> dict[str, NDArray[np.float64]]:
        called = r.status != NOT_CALLED
        return {
            "encoder": encoder_residual(r, counts_per_rad(exp), exp.controller.h,
                                        self.actuated),
            "tracking": np.where(called, r.error_norm, 0.0),
            "torque": np.abs(r.tau - r.tau_applied).max(axis=1),
        }

    def first_flags(self, r: Run, exp: Experiment, k0: int) -> dict[str, int]:
        """Monitor -> samples from ``k0`` to its first flag at or after ``k0``."""
        out: dict[str, int] = {}
        for name, sig in self.signals_of(r, exp).items():
            hits = np.nonzero(sig[k0:] > self.thresholds[name])[0]
            if len(hits):
                out[name] = int(hits[0])
        return out

    def false_alarms(self, base: Run, exp: Experiment) -> int:
        """Samples after SETTLE at which a monitor flags the fault-free run."""
        settle = base.t >= SETTLE
        sig = self.signals_of(base, exp)
        return int(
            sum(np.count_nonzero(sig[m][settle] > self.thresholds[m]) for m in self.thresholds)
        )


def counts_per_rad(exp: Experiment) -> float:
    return exp.sensing.counts_per_wheel_rev() / (2 * math.pi)


@dataclass(frozen=True)
class Row:
    """One fault × controller × formulation."""

    fault: Fault
    controller: str
    formulation: str
    statuses: dict[str, int]  # name -> count from the onset on (not WMR_OK)
    flags: dict[str, int]  # monitor -> delay (samples) from the onset
    peak_error: float  # m, from the onset on
    base_peak_error: float
    end_error: float  # m, last sample
    base_end_error: float
    recovery: int | None  # samples, true position
    recovery_odometry: int | None  # samples, odometry position
    last_outside: float | None  # s: the last sample outside the tolerance (true position)
    peak_torque: float  # N m, commanded
    stopped_at: float | None
    stop_status: str | None  # the status < 0 that stopped the run (None: non-finite state)
    false_alarms: int  # monitor flags in the fault-free run after SETTLE

    @property
    def diverged(self) -> bool:
        """The simulated state became non-finite (the run stopped without a status)."""
        return self.stopped_at is not None and self.stop_status is None

    def verdict(self, h: float) -> str:
        if self.diverged:
            return f"diverged: non-finite state at {self.stopped_at:g} s"
        if self.stopped_at is not None:
            return f"stopped: step returned `{self.stop_status}` at {self.stopped_at:g} s"
        if self.recovery is not None:
            return f"recovered in {self.recovery} samples ({self.recovery * h:.1f} s)"
        return (
            f"bounded, not recovered: outside the tolerance until {self.last_outside:g} s; "
            f"{self.end_error * 1e3:.1f} mm at the end (fault-free {self.base_end_error * 1e3:.1f})"
        )


def odometry_error(r: Run) -> NDArray[np.float64]:
    """‖(x_c, y_c) measured − (x_dc, y_dc)‖ (the odometry pose the controller receives)."""
    return np.asarray(np.linalg.norm(r.q_meas[:, :2] - r.q_des[:, :2], axis=1))


def fault_row(code: RobotCode, fault: Fault, base: Run, faulted: Run, exp: Experiment,
              n: int) -> Row:
    """Compare a faulted run with the fault-free one."""
    h = exp.controller.h
    ks = fault.samples(h, n)
    k0 = ks.start
    k_end = k0 + 1 if fault.persists else ks.stop
    names = status_names(code)
    st = faulted.status[k0:]
    ok = code.controllers.STATUS[f"{code.prefix.upper()}_OK"]
    counts = Counter(
        "not called" if c == NOT_CALLED else names.get(int(c), f"status {int(c)}")
        for c in st
        if c != ok
    )
    stop = None
    if faulted.stop_status is not None:
        stop = names.get(faulted.stop_status, f"status {faulted.stop_status}")
        counts[stop] += 1
    monitors = Monitors.calibrate(base, exp, code.actuated)
    e, e0 = faulted.position_error, base.position_error
    m = len(e)
    outside = np.nonzero(e > tolerance(e0)[:m])[0]
    return Row(
        fault=fault,
        controller=faulted.controller,
        formulation=faulted.formulation,
        statuses=dict(sorted(counts.items())),
        flags=monitors.first_flags(faulted, exp, k0),
        peak_error=float(e[k0:].max()) if m > k0 else math.nan,
        base_peak_error=float(e0[k0:].max()),
        end_error=float(e[-1]),
        base_end_error=float(e0[-1]),
        recovery=recovery_samples(e, e0, k_end),
        recovery_odometry=recovery_samples(odometry_error(faulted), odometry_error(base), k_end),
        last_outside=float(faulted.t[outside[-1]]) if len(outside) else None,
        peak_torque=float(np.abs(faulted.tau).max()),
        stopped_at=faulted.failed_at,
        stop_status=stop,
        false_alarms=monitors.false_alarms(base, exp),
    )


@dataclass(frozen=True)
class FaultTable:
    experiment: Experiment
    robot: dict[str, float]
    faults: tuple[Fault, ...]
    rows: list[Row]
    samples: int
    thresholds: dict[tuple[str, str], dict[str, float]]  # (controller, formulation)
    code: RobotCode
    # (controller, formulation) -> why its fault-free run did not reach the settling time
    # (its init refused the configuration, or it stopped or diverged): no fault is injected
    # into a controller that does not run without one.
    not_run: dict[tuple[str, str], str] = field(default_factory=dict)
    # the physics audit's warnings on the robot file (modeling.audit), written into FAULTS.md
    warnings: tuple[str, ...] = ()

    @property
    def labels(self) -> dict[str, str]:
        return {c.name: c.label for c in self.code.controller_infos}


def fault_table(
    exp: Experiment,
    faults: Sequence[Fault] | None = None,
    robot: dict[str, float] | None = None,
    controllers: Sequence[str] | None = None,
    formulations: Sequence[str] | None = None,
    code: RobotCode | None = None,
    plant: dict[str, float] | None = None,
    progress: bool = False,
    warnings: Sequence[str] = (),
) -> FaultTable:
    """Run every fault on every controller and formulation (default: all generated for the
    robot; no files written); ``faults`` default to the experiment's ``[[fault]]`` tables,
    or :data:`DEFAULT_FAULTS`. ``code``: the robot's generated code (default: the paper's
    robot), ``robot`` its nominal parameters, ``plant`` the simulated robot's (before
    payload); ``warnings``: the physics audit's on the robot file, for FAULTS.md."""
    code = load_robot_code("") if code is None else code
    robot = dict(robot or code.params)
    chosen = tuple(faults if faults is not None else exp.faults or DEFAULT_FAULTS)
    ref = paths.circle(code, robot, exp)
    n = len(ref.t)
    rows: list[Row] = []
    thresholds: dict[tuple[str, str], dict[str, float]] = {}
    not_run: dict[tuple[str, str], str] = {}
    pairs = [(f, c.name) for f, c in code.runs(tuple(formulations or code.formulations))
             if controllers is None or c.name in controllers]
    for i, (form, ctrl) in enumerate(pairs, 1):
        base = loop.run(code, ctrl, form, ref, robot, exp, plant_params=plant,
                        plant=plant_for(code, exp, robot, plant))
        if base.failed_at is not None and base.failed_at < SETTLE:
            not_run[(ctrl, form)] = (f"the fault-free run stopped at {base.failed_at:g} s: "
                                     f"{base.stop_reason}")
            if progress:
                print(f"[{i}/{len(pairs)}] {ctrl}/{form}: not run ({not_run[(ctrl, form)]})",
                      flush=True)
            continue
        thresholds[(ctrl, form)] = Monitors.calibrate(base, exp, code.actuated).thresholds
        for fault in chosen:
            faulted = loop.run(code, ctrl, form, ref, robot, exp, plant_params=plant,
                               plant=plant_for(code, exp, robot, plant), faults=[fault])
            rows.append(fault_row(code, fault, base, faulted, exp, n))
        if progress:
            print(f"[{i}/{len(pairs)}] {ctrl}/{form}: {len(chosen)} faults", flush=True)
    order = {f: i for i, f in enumerate(chosen)}
    rows.sort(key=lambda r: order[r.fault])
    return FaultTable(exp, robot, chosen, rows, n, thresholds, code, not_run, tuple(warnings))


def _statuses(r: Row, prefix: str) -> str:
    if not r.statuses:
        return f"nothing (`{prefix.upper()}_OK`)"
    return ", ".join(
        f"{name} ×{c}" if name == "not called" else f"`{name}` ×{c}"
        for name, c in r.statuses.items()
    )


def _flags(r: Row) -> str:
    if not r.flags:
        return "none"
    return ", ".join(f"{m} (+{d})" for m, d in sorted(r.flags.items(), key=lambda x: x[1]))


def _samples(v: int | None) -> str:
    return "never" if v is None else str(v)


def csv_text(table: FaultTable) -> str:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(
        [
            "fault",
            "start_s",
            "duration_s",
            "magnitude",
            "wheel",
            "controller",
            "formulation",
            "statuses",
            "monitors",
            "peak_error_m",
            "fault_free_peak_error_m",
            "end_error_m",
            "fault_free_end_error_m",
            "recovery_samples",
            "recovery_samples_odometry",
            "peak_torque_nm",
            "stopped_at_s",
            "verdict",
        ]
    )
    for r in table.rows:
        f = r.fault
        w.writerow(
            [
                f.kind,
                f"{f.start:g}",
                f"{f.duration:g}",
                f"{f.magnitude:g}",
                "" if f.kind in ("dropped-sample", "repeated-sample") else f.wheel,
                r.controller,
                r.formulation,
                ";".join(f"{k}={v}" for k, v in r.statuses.items()),
                ";".join(f"{k}=+{v}" for k, v in r.flags.items()),
                f"{r.peak_error:.6g}",
                f"{r.base_peak_error:.6g}",
                f"{r.end_error:.6g}",
                f"{r.base_end_error:.6g}",
                "" if r.recovery is None else r.recovery,
                "" if r.recovery_odometry is None else r.recovery_odometry,
                f"{r.peak_torque:.6g}",
                "" if r.stopped_at is None else f"{r.stopped_at:g}",
                r.verdict(table.experiment.controller.h),
            ]
        )
    return out.getvalue()


def markdown(table: FaultTable) -> str:
    exp, c, s, p = (
        table.experiment,
        table.experiment.controller,
        table.experiment.sensing,
        (table.experiment.plant),
    )
    h = c.h
    robot = ", ".join(f"{k} = {v:g}" for k, v in table.robot.items())
    name, prefix = table.code.name, table.code.prefix
    spin = ", ".join(dict.fromkeys(spin_inertia_keys(table.code) or ("(none)",)))
    labels = table.labels
    lines = [
        "# Sensor and actuator faults in the closed loop",
        "",
        "Generated by `python -m runtime faults` (do not edit: `tests/runtime/test_faults.py`",
        "fails if this file differs from the command's output).",
        "",
        "## Conditions",
        "",
        f"* Robot: {name[:1].upper() + name[1:]}'s nominal parameters ({robot}); plant with "
        "the payload schedule "
        f"({p.fixed_payload:g} kg fixed, {p.extra_payload:g} kg on from {p.extra_on_at:g} s "
        f"every {p.extra_period:g} s for half the period) and wheel friction "
        f"(viscous {p.viscous:g} N m s/rad, Coulomb {p.coulomb:g} N m) unknown to the "
        f"controllers; RK4 with {p.substeps} steps per sample.",
        f"* Path: the paper's circle, {exp.paths.circle_duration:g} s, {table.samples} samples "
        f"of h = {h:g} s.",
        f"* Sensing: `{s.velocity}` wheel rates, {s.encoder_ppr}-ppr quadrature encoders "
        f"({s.counts_per_wheel_rev():g} counts per wheel revolution), odometry pose; "
        f"q̈(t − h) estimator `{s.accel_estimator}`.",
        f"* Gains: K1 = {c.k1:g} I, K2 = {c.k2:g} I, Q = diag({c.q_pos:g}, {c.q_vel:g}), "
        f"ε = {c.eps:g}, TDROC n = {c.n}, a = {c.a:g}, ROC bounds {c.uncertainty:g}, "
        f"ASMC γ = {c.gamma:g}, τ_max = {c.tau_max:g} N m (the controllers' own limit).",
        f"* Experiment: {exp.source}.",
        "",
        *audit.section(table.warnings),
        "## Faults",
        "",
        "Faults act at sample granularity (see `runtime/experiment/faults.py`):",
        "",
    ]
    lines += [f"* {f.describe()}" for f in table.faults]
    lines += [
        "",
        "The traction loss is a proxy of slip in the no-slip plant: the lost fraction of the",
        f"wheel's net torque spins the wheel on its own inertia {spin}, the encoder and the drive",
        "read the spinning wheel, and when traction returns the spin stops at once with the",
        "slip angle left in the encoder count. The torque limit is the actuator's; the",
        "controller is not told.",
        "",
        "## How to read the table",
        "",
        f"* **status**: what `{prefix}_<ctrl>_step` returned from the fault's onset to the end "
        f"of the run, other than `{prefix.upper()}_OK`; *not called* counts dropped samples.",
        "* **monitors**: the runtime's monitors that flagged the fault, with the delay in "
        "samples from the onset (not part of the generated controllers). Thresholds are set "
        f"on the fault-free run of the same controller after {SETTLE:g} s:",
    ]
    lines += [f"  * *{name}*: {text}" for name, text in MONITORS.items()]
    lines += [
        f"  (CAL_FACTOR = {CAL_FACTOR:g}, ENCODER_FLOOR = {ENCODER_FLOOR:g} counts, "
        f"TORQUE_TOL = {TORQUE_TOL:g} N m).",
        "* **peak error**: the largest true position error from the onset on, mm (fault-free "
        "run in parentheses).",
        "* **recovery**: samples after the fault's last sample (for a persisting miscount, "
        "after its onset) until the position error is within "
        f"{FACTOR:g} × the fault-free run's error maximised over ±{WINDOW} samples "
        f"+ {SLACK * 1e3:g} mm and stays there to the end of the run, with at least "
        f"{MIN_TAIL} samples left; *never* otherwise. *true*: the robot's position; "
        "*odometry*: the position the controller is given.",
        "* **verdict**: *stopped* if `step` returned a status < 0 (the run ends there: the "
        "controller reported the fault and refused the step); *diverged* if the simulated "
        "state became non-finite; otherwise recovered or bounded (finite state and torque "
        "to the end of the run).",
        "",
        "| fault | ctrl | form | status | monitors | peak error, mm | recovery true / "
        "odometry | peak τ, N m | verdict |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in table.rows:
        lines.append(
            f"| {r.fault.label()} | {labels[r.controller]} | {r.formulation} | "
            f"{_statuses(r, prefix)} | "
            f"{_flags(r)} | {r.peak_error * 1e3:.1f} ({r.base_peak_error * 1e3:.1f}) | "
            f"{_samples(r.recovery)} / {_samples(r.recovery_odometry)} | "
            f"{r.peak_torque:.2f} | {r.verdict(h)} |"
        )
    alarms = {(r.controller, r.formulation): r.false_alarms for r in table.rows}
    lines += [
        "",
        "Monitor thresholds and false alarms (flags after the settling time in the fault-free "
        "run):",
        "",
        "| ctrl | form | encoder, counts | tracking ‖(e, ė)‖ | false alarms |",
        "|---|---|---|---|---|",
    ]
    for (ctrl, form), th in table.thresholds.items():
        lines.append(
            f"| {labels[ctrl]} | {form} | {th['encoder']:.3g} | {th['tracking']:.3g} | "
            f"{alarms.get((ctrl, form), 0)} |"
        )
    if table.not_run:
        lines += ["", "Not run (no fault is injected into a controller that does not run "
                  "without one):", ""]
        lines += [f"* {labels[ctrl]} / {form}: {why}."
                  for (ctrl, form), why in table.not_run.items()]
    lines += ["", *summary(table), ""]
    return "\n".join(lines)


def summary(table: FaultTable) -> list[str]:
    """Findings computed from the rows (counts, never typed)."""
    out = ["## Findings", ""]
    for f in table.faults:
        rows = [r for r in table.rows if r.fault == f]
        reported = [r for r in rows if any(k != "not called" for k in r.statuses)]
        flagged = [r for r in rows if r.flags]
        recovered = [r for r in rows if r.recovery is not None]
        diverged = [r for r in rows if r.diverged]
        stopped = [r for r in rows if r.stop_status is not None]
        skipped = [r for r in rows if "not called" in r.statuses]
        worst = max((r.recovery for r in recovered if r.recovery is not None), default=None)
        out.append(
            f"* {f.describe()}: a controller status reported it in {len(reported)} of "
            f"{len(rows)} runs, a monitor in {len(flagged)}"
            + (
                f", the control task's own count of skipped steps in {len(skipped)}"
                if skipped
                else ""
            )
            + f"; recovered in {len(recovered)}"
            + (f" (slowest {worst} samples)" if worst is not None else "")
            + f", stopped by a status in {len(stopped)}, diverged in {len(diverged)}."
        )
    out += [
        "",
        "What would change the verdicts: the fault's size and timing (a larger miscount, a "
        "longer loss of traction or a lower torque limit), the sensing (`encoder-average` "
        "rates make an encoder miscount a rate spike as well), the gains and h, the path, and "
        "the recovery tolerance above.",
        "",
        "Mechanisms to read the rows with: an encoder miscount enters the odometry (a heading "
        "error integrated into the pose) and the wheel angles at once, which no controller here "
        "can tell from a motion; in the minimal formulation the controllers track the wheel "
        "angles only, so a fault that changes the path the wheels took leaves a pose offset "
        "they do not see; the time-delay controllers (TDC, TDROC) take the torque they "
        "commanded as the torque applied, so an actuator limit they are not told of, or a "
        "wheel spinning on its own inertia, enters their estimate Ĥ1 of (17).",
    ]
    return out


def write(table: FaultTable, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    md, cs = out / "FAULTS.md", out / "faults.csv"
    md.write_text(markdown(table), encoding="utf-8")
    cs.write_text(csv_text(table), encoding="utf-8")
    return [md, cs]
