"""``python -m runtime reproduce``: the paper's experiments (Section "Experimental results
and comparison"), with figures, a metrics table and a report.

For each sensing model chosen with ``--sensing`` (default: ``sample-instant`` and
``encoder-average``, see :class:`runtime.experiment.SensingSettings`; the experiment file's
other ``[sensing]`` fields, the estimator of q̈(t − h) in (17) among them, apply to each):
2 paths (circle, lawn mower) × 4 controllers (TDC, TDROC, ROC, ASMC) × 2 formulations
(paper, minimal), closed loop through the generated C. Then a sweep of TDROC's boundary
layer ε of (25) per sensing model, and, when ``encoder-average`` is chosen, the same sweep
with the plain ``backward`` estimator: the pairing that made TDROC unstable at ε = 0.1
before the matched estimator existed.

Writes to the output folder (default ``docs/reproduction``): the figures of
:mod:`runtime.paper.figures` (PNG), ``metrics.csv``, ``metrics.md`` and ``REPORT.md``. Nothing
written depends on the wall time or the machine's clock, so two runs give the same bytes.
The wall time is printed on the console only.
"""

from __future__ import annotations

import csv
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from runtime.experiment import (
    Experiment,
)
from runtime.generated_modules import robot as default_robot
from runtime.paper import references
from runtime.paper.simulate import CONTROLLERS, Run, run


@dataclass(frozen=True)
class Figure:
    """A written figure: its file, the title (naming the paper's figure) and a caption."""

    path: Path
    title: str
    caption: str


ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = ROOT / "docs" / "reproduction"
DEFAULT_SENSINGS = ("sample-instant", "encoder-average")
EPS_SWEEP = (0.1, 0.2, 0.5, 1.0)
FORMULATIONS = ("paper", "minimal")
# The contrast of the ε sweep: encoder-average rates with the plain backward quotient.
CONTRAST = ("encoder-average", "backward")
# A TDROC run is called unstable when its RMS error exceeds this multiple of TDC's under
# the same sensing, estimator and path (the measured unstable runs are ≥ 50× TDC's).
UNSTABLE_FACTOR = 10.0
LABELS = {"tdc": "TDC", "tdroc": "TDROC", "roc": "ROC", "asmc": "ASMC"}
COLORS = {"tdc": "tab:blue", "tdroc": "tab:red", "roc": "tab:green", "asmc": "tab:purple"}

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
    rms_percent: float  # RMS error in % of the path's scale (R1, or the lawn-mower leg)
    rms_torque: float  # N m
    torque_variation: float  # N m, total variation of tau (chattering)
    median_gain: float  # k̂: units of the switching term Δu_a (see figures.GAIN_UNIT)
    max_gain: float
    saturated_steps: int
    discarded_u: float  # RMS of ||u rows 1-3|| (paper formulation)
    failed_at: float | None


def path_scale(path: str, params: dict[str, float]) -> float:
    """The length ``rms_percent`` refers to: R1 for the circle, the U-turn diameter (the
    spacing of the legs) for the lawn mower. (The figures use the paper's own scales.)"""
    if path == "circle":
        return references.R1
    return references.lawnmower_leg_spacing(params)


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2)))


def metrics(r: Run, params: dict[str, float], sensing: str) -> Metrics:
    """The metrics of one run: position error ‖(x_c, y_c) − (x_dc, y_dc)‖, torque, k̂."""
    e = r.position_error
    return Metrics(
        sensing=sensing,
        controller=r.controller,
        formulation=r.formulation,
        path=r.path,
        rms_error=rms(e),
        max_error=float(e.max()),
        rms_percent=100.0 * rms(e) / path_scale(r.path, params),
        rms_torque=rms(r.tau),
        torque_variation=float(np.abs(np.diff(r.tau, axis=0)).sum()),
        median_gain=float(np.median(r.gain)),
        max_gain=float(r.gain.max()),
        saturated_steps=r.saturated,
        discarded_u=rms(r.u_discarded),
        failed_at=r.failed_at,
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
    refs: dict[str, references.Reference]
    runs: dict[RunKey, Run]
    table: list[Metrics]
    sweep: list[SweepRow]
    sweep_runs: dict[SweepKey, Run]  # TDROC, paper formulation
    seconds: float  # simulation wall time (printed, never written to a file)
    robot: dict[str, float] = field(default_factory=dict)

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
        self, exp: Experiment, robot: dict[str, float], refs: dict[str, references.Reference]
    ):
        self.exp, self.robot, self.refs = exp, robot, refs
        self.cache: dict[tuple[str, str, float, str, str, str], Run] = {}

    def __call__(
        self, sensing: str, estimator: str, eps: float, ctrl: str, form: str, path: str
    ) -> Run:
        if ctrl == "tdc":  # ε does not enter TDC
            eps = self.exp.controller.eps
        key = (sensing, estimator, eps, ctrl, form, path)
        if key not in self.cache:
            e = with_eps(with_sensing(self.exp, sensing, estimator), eps)
            self.cache[key] = run(ctrl, form, self.refs[path], self.robot, e)
        return self.cache[key]


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
) -> Reproduction:
    """Run every experiment (no files written)."""
    start = time.perf_counter()
    robot = dict(robot or default_robot.PARAMS)
    h, est, eps0 = exp.controller.h, exp.sensing.accel_estimator, exp.controller.eps
    refs = {
        "circle": references.circle(robot, h, exp.paths.circle_duration),
        "lawnmower": references.lawnmower(robot, h, exp.paths.lawnmower_duration),
    }
    sim = _Simulator(exp, robot, refs)
    runs: dict[RunKey, Run] = {}
    table: list[Metrics] = []
    total = len(sensings) * len(refs) * len(CONTROLLERS) * len(FORMULATIONS)
    for sensing in sensings:
        for path in refs:
            for form in FORMULATIONS:
                for ctrl in CONTROLLERS:
                    r = sim(sensing, est, eps0, ctrl, form, path)
                    runs[(sensing, ctrl, form, path)] = r
                    table.append(metrics(r, robot, sensing))
                    if progress:
                        m = table[-1]
                        print(
                            f"[{len(table):2d}/{total}] {sensing:15s} {path:9s} {form:7s} "
                            f"{LABELS[ctrl]:5s} RMS {m.rms_error * 1000:8.2f} mm",
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
                    SweepRow(
                        sensing, estimator, eps, metrics(r, robot, sensing), rms(tdc.position_error)
                    )
                )
    seconds = time.perf_counter() - start
    return Reproduction(exp, tuple(sensings), refs, runs, table, sweep, sweep_runs, seconds, robot)


# --------------------------------------------------------------------------- tables


def fmt_mm(x: float) -> str:
    return f"{x * 1000:.2f}"


def sensing_label(rep: Reproduction, sensing: str, estimator: str | None = None) -> str:
    """What a table or claim holds for: sensing, estimator, ε, h and the gains."""
    c = rep.experiment.controller
    return (
        f"sensing `{sensing}`, estimator `{estimator or rep.estimator}`; ε = {c.eps:g}, "
        f"h = {c.h:g} s, K1 = K2 = {c.k1:g} I, Q = I, n = {c.n}, a = {c.a:g}"
    )


def metrics_table(rows: Iterable[Metrics]) -> list[str]:
    lines = [
        "| path | form | controller | RMS error [mm] | max error [mm] | RMS [% of scale] "
        "| RMS τ [N m] | TV(τ) [N m] | median k̂ | max k̂ | saturated steps | RMS ‖u₁₋₃‖ |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for m in rows:
        lines.append(
            f"| {m.path} | {m.formulation} | {LABELS[m.controller]} | {fmt_mm(m.rms_error)} "
            f"| {fmt_mm(m.max_error)} | {m.rms_percent:.2f} | {m.rms_torque:.2f} "
            f"| {m.torque_variation:.1f} | {m.median_gain:.3f} | {m.max_gain:.3f} "
            f"| {m.saturated_steps} | {m.discarded_u:.2f} |"
        )
    return lines


def metrics_markdown(rep: Reproduction) -> str:
    """``metrics.md``: one table per sensing model (headed ``### sensing …``)."""
    parts: list[str] = []
    for sensing in rep.sensings:
        parts += [f"### {sensing_label(rep, sensing)}", "", *metrics_table(rep.rows(sensing)), ""]
    return "\n".join(parts)


CSV_COLUMNS = (
    "path",
    "formulation",
    "controller",
    "rms_error_m",
    "max_error_m",
    "rms_percent",
    "rms_torque_Nm",
    "torque_variation_Nm",
    "median_gain",
    "max_gain",
    "saturated_steps",
    "rms_discarded_u",
    "failed_at_s",
    "sensing",  # appended LAST: the older columns keep their positions
)


def write_csv(rep: Reproduction, path: Path) -> None:
    """``metrics.csv``: the columns it always had, in the same order, then ``sensing``
    appended as the last column. Rows: per sensing, path, formulation, controller."""
    with path.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(CSV_COLUMNS)
        for m in rep.table:
            w.writerow(
                [
                    m.path,
                    m.formulation,
                    m.controller,
                    f"{m.rms_error:.6g}",
                    f"{m.max_error:.6g}",
                    f"{m.rms_percent:.4g}",
                    f"{m.rms_torque:.4g}",
                    f"{m.torque_variation:.4g}",
                    f"{m.median_gain:.4g}",
                    f"{m.max_gain:.4g}",
                    m.saturated_steps,
                    f"{m.discarded_u:.4g}",
                    "" if m.failed_at is None else f"{m.failed_at:.3g}",
                    m.sensing,
                ]
            )


# --------------------------------------------------------------------------- claims


@dataclass(frozen=True)
class Claim:
    text: str
    holds: bool
    evidence: str


def best(rep: Reproduction, sensing: str, path: str, formulation: str) -> str:
    rows = [m for m in rep.rows(sensing) if m.path == path and m.formulation == formulation]
    return min(rows, key=lambda m: m.rms_error).controller


def claims(rep: Reproduction, sensing: str) -> list[Claim]:
    """The paper's three claims (Section 5, Figures 4–8 and 11–14), evaluated on the runs of
    one sensing model: (1) TDROC tracks best of the four (paper formulation, both paths);
    (2) ASMC's k̂ never decreases (both formulations and paths); (3) TDROC's median k̂ is
    the lowest of TDROC, ROC, ASMC (paper formulation, both paths)."""
    out = []
    winners = {p: best(rep, sensing, p, "paper") for p in rep.refs}
    rms_of = {
        (m.path, m.controller): m.rms_error for m in rep.rows(sensing) if m.formulation == "paper"
    }
    out.append(
        Claim(
            "TDROC has the lowest tracking error of the four controllers on both paths",
            all(w == "tdroc" for w in winners.values()),
            "; ".join(
                f"{p}: lowest RMS by {LABELS[w]} (TDROC {fmt_mm(rms_of[(p, 'tdroc')])} mm, "
                f"TDC {fmt_mm(rms_of[(p, 'tdc')])} mm, ROC {fmt_mm(rms_of[(p, 'roc')])} mm, "
                f"ASMC {fmt_mm(rms_of[(p, 'asmc')])} mm; TDROC/TDC "
                f"{rms_of[(p, 'tdroc')] / rms_of[(p, 'tdc')]:.3f})"
                for p, w in winners.items()
            ),
        )
    )
    diffs = [
        float(np.diff(rep.runs[(sensing, "asmc", f, p)].gain).min())
        for f in FORMULATIONS
        for p in rep.refs
    ]
    out.append(
        Claim(
            "ASMC's switching gain grows monotonically",
            min(diffs) >= 0.0,
            f"smallest step-to-step change of k̂ (both formulations and paths): {min(diffs):.3g}",
        )
    )
    lowest = {}
    for p in rep.refs:
        med = {
            c: float(np.median(rep.runs[(sensing, c, "paper", p)].gain))
            for c in ("tdroc", "roc", "asmc")
        }
        lowest[p] = (min(med, key=lambda c: med[c]), med)
    out.append(
        Claim(
            "TDROC's switching gain is the lowest of TDROC, ROC and ASMC",
            all(c == "tdroc" for c, _ in lowest.values()),
            "; ".join(
                f"{p}: median k̂ " + ", ".join(f"{LABELS[c]} {v:.3g}" for c, v in med.items())
                for p, (_, med) in lowest.items()
            ),
        )
    )
    return out


# --------------------------------------------------------------------------- stability


@dataclass(frozen=True)
class StabilityRow:
    sensing: str
    controller: str
    path: str
    tde_bound: float  # k̄ of (23), measured: max ‖M̂⁻¹‖ ‖Ĥ1(t + h) − Ĥ1(t)‖
    varpi: float  # ϖ1 of (21) (TDC) or ϖ3 of (30) (TDROC)
    ultimate_bound: float  # √(λmax(P)/λmin(P)) ϖ
    measured: float  # max ‖(e, ė)‖ after the start-up (t > 5 s)
    varpi2: float | None = None  # ϖ2 of (27) (TDROC, ‖s‖ ≥ ε): 2 max(k̄ − k̂, 0)‖BᵀP‖/λmin(Q)


def stability(
    rep: Reproduction, sensing: str, robot: dict[str, float] | None = None
) -> list[StabilityRow]:
    """The ultimate bounds (21) (TDC) and (30) (TDROC) for the experiment's gains and the
    measured time-delay estimation error, beside the measured errors (paper formulation,
    one sensing model).

    (21): ϖ1 = 2‖PB‖ k̄ / λmin(Q); (27) (case ‖s‖ ≥ ε of Theorem 2):
    ϖ2 = 2 (k̄ − k̂)‖BᵀP‖ / λmin(Q), zero when k̂ ≥ k̄; (30): ϖ3 = √(ε k̄² / (2 k̂ λmin(Q)))
    with k̂ the median switching gain; each ultimate bound is √(λmax(P)/λmin(P)) ϖ.
    """
    from runtime.generated_modules import wmr_laws

    robot = dict(robot or rep.robot or default_robot.PARAMS)
    c = rep.experiment.controller
    p11, p12, p22 = wmr_laws.lyapunov_p([c.k1, c.k2, c.q_pos, c.q_vel])
    eig = np.linalg.eigvalsh(np.array([[p11, p12], [p12, p22]]))
    cond = float(np.sqrt(eig.max() / eig.min()))
    pb = float(np.hypot(p12, p22))
    lam_q = min(c.q_pos, c.q_vel)
    minv = float(wmr_laws.paper_minv_norm(robot)[0])
    rows = []
    for path in rep.refs:
        for ctrl in ("tdc", "tdroc"):
            r = rep.runs[(sensing, ctrl, "paper", path)]
            late = r.t[1:] > min(2.0, 0.25 * r.t[-1])
            kbar = float(minv * np.linalg.norm(np.diff(r.h1hat, axis=0), axis=1)[late].max())
            varpi2 = None
            if ctrl == "tdc":
                varpi = 2 * pb * kbar / lam_q
            else:
                khat = max(float(np.median(r.gain)), 1e-12)
                varpi = float(np.sqrt(c.eps * kbar**2 / (2 * khat * lam_q)))
                varpi2 = 2 * max(kbar - khat, 0.0) * pb / lam_q
            measured = float(r.error_norm[r.t >= min(5.0, 0.5 * r.t[-1])].max())
            rows.append(
                StabilityRow(sensing, ctrl, path, kbar, varpi, cond * varpi, measured, varpi2)
            )
    return rows


# --------------------------------------------------------------------------- report

Section = Callable[["Reproduction", Sequence["Figure"]], list[str]]


def section_setting(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """What was simulated: plant, payload, sensing models, controller parameters."""
    c, pl, se = rep.experiment.controller, rep.experiment.plant, rep.experiment.sensing
    sens = ", ".join(f"`{s}`" for s in rep.sensings)
    return [
        "# Reproduction of Roy et al. (2017), Section 5",
        "",
        "Generated by `python -m runtime reproduce` (`make reproduce`); do not edit by hand.",
        f"Experiment: `{rep.experiment.source}`.",
        "",
        "Closed loop through the generated C. Plant: the constrained dynamics with a fixed",
        f"{pl.fixed_payload:g} kg payload (the rangefinder) and {pl.extra_payload:g} kg "
        f"placed off the robot's axis ({pl.extra_payload_x:g} m ahead of C, "
        f"{pl.extra_payload_y:g} m to the left), put on at t = {pl.extra_on_at:g} s for "
        f"{pl.extra_period / 2:g} s of every {pl.extra_period:g} s; viscous "
        f"({pl.viscous:g} N m s/rad) and Coulomb ({pl.coulomb:g} N m) wheel friction that no",
        "controller models; RK4 at "
        f"{pl.substeps} steps per sample. The controllers' nominal model is the bare robot",
        f"(m = {rep.robot.get('m', 0):g} kg, I = {rep.robot.get('I', 0):g} kg m²).",
        "",
        f"Controllers (all runs unless a table says otherwise): h = {c.h} s, K1 = {c.k1} I, "
        f"K2 = {c.k2} I, Q = I, ε = {c.eps}, n = {c.n}, a = {c.a}, ROC bounds "
        f"{c.uncertainty:.0%} above nominal, ASMC γ = {c.gamma}, |τ| ≤ {c.tau_max} N m.",
        "",
        f"Sensing models run: {sens} (`[sensing]` of the experiment file, "
        "`runtime/experiment.py::SensingSettings`), each with the estimator of q̈(t − h) in",
        f"(17) `accel_estimator = {se.accel_estimator}` and {se.encoder_ppr}-ppr wheel "
        "encoders (angles and odometry pose always from the quantised counts):",
        "",
        "* `sample-instant`: the wheel rate at the sample instant, as a motor drive reports it;",
        "* `encoder-average`: Δθ/h of the encoder counts over the whole sample (the mean rate",
        "  over [t − h, t]);",
        "* `matched`: (17) pairs the backward quotient (q̇(t) − q̇(t − h))/h with the input",
        "  blend (1 − c) u(t − h) + c u(t − 2h), c = rate window / 2h, that produced it;",
        "  `backward` pairs it with u(t − h) alone (exact only for `sample-instant`).",
        "",
        "The figures reproduce the paper's Figures 3–14 for the first sensing model "
        f"(`{rep.sensings[0]}`), paper formulation; the tables cover every model.",
        "",
    ]


def section_figures(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """Each figure with its caption naming the paper's figure it reproduces."""
    if not figures:
        return []
    lines = ["## Figures", ""]
    for f in figures:
        lines += [f"### {f.title}", "", f"![{f.title}]({f.path.name})", "", f.caption, ""]
    return lines


def section_references(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """The printed references (Section 5) and how ours differ (READING.md item 9)."""
    p = rep.robot
    r, b, d = p["r"], p["b"], p["d"]
    th = references.THETA_DOT
    printed_r = th * (references.R1 + b / 2) / r
    printed_l = th * (references.R1 - b / 2) / r
    v = th * float(np.sqrt(references.R1**2 - d**2))
    ours_r, ours_l = (v + th * b / 2) / r, (v - th * b / 2) / r
    centre = circle_centre(rep.refs["circle"])
    spacing = references.lawnmower_leg_spacing(p)
    turn = np.pi / (r * (references.LAWN_A - references.LAWN_B) / b)
    return [
        "## The reference paths: printed and ours",
        "",
        "The paper's printed definitions are not kinematically consistent: no robot obeying",
        "the constraints (6)–(8) can follow them exactly. The controllers are fed references",
        "built from wheel-rate profiles and integrated through (31)",
        "(`runtime/paper/references.py`), so every reference is a motion the robot can make;",
        "the printed ones are drawn beside ours in Figures 4, 9, 10 and 11 (`printed_circle`,",
        "`printed_lawnmower`).",
        "",
        f"* **Circle** (R1 = {references.R1} m, θ̇d = {th} rad/s, start (1.5, 1.5, 0)). Printed:",
        "  x_dc = R1 cos(θ̇d t + θ0), y_dc = R1 + R1 sin(θ̇d t + θ0), θd = θ0 + θ̇d t,",
        f"  θ̇dr,l = θ̇d (R1 ± b/2)/r = {printed_r:.3f}, {printed_l:.3f} rad/s. At t = 0 the "
        "printed point",
        "  moves along +y while θd = 0 points along +x: the heading is not the path's tangent,",
        "  and the wheel rates put the axle centre (not C, which is d ahead of it) on R1.",
        "  Ours: the same θ̇d, C exactly on a circle of radius R1 (axle centre on",
        f"  √(R1² − d²)), heading tangent to the axle's circle, θ̇dr,l = {ours_r:.3f}, "
        f"{ours_l:.3f} rad/s,",
        f"  after a 2 s start-up ramp from rest. Starting at (1.5, 1.5) with θ = 0, our "
        f"circle's centre is ({centre[0]:.3f}, {centre[1]:.3f});",
        "  the printed one's is (0, 1.5).",
        "* **Lawn mower.** Printed: x_dc = 0.1t + 0.3 sin(0.4t), y_dc = 1.2 + 1.2 cos(0.2t − T),",
        f"  and square-wave wheel rates (Fourier series) between a = {references.LAWN_A:g} and "
        f"b = {references.LAWN_B:g} rad/s,",
        f"  period T = {references.LAWN_T:g} s, the left wheel half a period behind the right; "
        "θd = c∫(θ̇r − θ̇l)dt with c",
        "  unclear. These wheel rates never drive straight (one wheel is always at a, the other",
        "  at b), so they describe a chain of alternating arcs, not the printed (x_dc, y_dc).",
        f"  Ours: straight legs with both wheels at a, U-turns of {turn:.2f} s with one wheel at b",
        f"  (alternately left and right), legs parallel and {spacing:.3f} m apart, one cycle "
        "per T on",
        f"  average, every switch smoothed by tanh over {references.RAMP} s; start at the "
        "origin from rest.",
        "",
    ]


def circle_centre(ref: references.Reference) -> np.ndarray:
    """Centre of the circle through three points of the steady part of the reference."""
    pts = ref.q[ref.t > 0.5 * ref.t[-1], :2]
    (x1, y1), (x2, y2), (x3, y3) = pts[0], pts[len(pts) // 3], pts[2 * len(pts) // 3]
    a = np.array([[x2 - x1, y2 - y1], [x3 - x1, y3 - y1]])
    rhs = 0.5 * np.array([x2**2 - x1**2 + y2**2 - y1**2, x3**2 - x1**2 + y3**2 - y1**2])
    return np.asarray(np.linalg.solve(a, rhs))


def section_metrics(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """The metrics tables, one per sensing model (``metrics.md``)."""
    return [
        "## Metrics",
        "",
        "Position error = ‖(x_c, y_c) − (x_dc, y_dc)‖ of the true pose. RMS [% of scale]: of R1",
        "(circle) or the lawn mower's leg spacing. k̂ is in the units of the switching term",
        "Δu_a (rad/s² for the minimal formulation; mixed m/s² and rad/s² for the paper's).",
        "TV(τ): total variation of τ (chattering). RMS ‖u₁₋₃‖: the rows of u that τ = Bᵀu",
        "discards (paper formulation).",
        "",
        metrics_markdown(rep),
    ]


def section_claims(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """The paper's claims, one table per sensing model, naming what they hold for."""
    lines = [
        "## The paper's claims",
        "",
        "Claims 1 and 3 compare the paper-formulation runs (Figures 4–8, 11–14), claim 2 every",
        "ASMC run. Not tuned: every parameter is the paper's.",
        "",
    ]
    for sensing in rep.sensings:
        lines += [
            f"### {sensing_label(rep, sensing)}",
            "",
            "| claim | reproduces? | evidence |",
            "|---|---|---|",
            *[
                f"| {cl.text} | {'yes' if cl.holds else '**no**'} | {cl.evidence} |"
                for cl in claims(rep, sensing)
            ],
            "",
            "Not part of the claims: in the minimal formulation the lowest RMS error is "
            + "; ".join(
                f"{LABELS[best(rep, sensing, p, 'minimal')]}'s on the {p}" for p in rep.refs
            )
            + ".",
            "",
        ]
    return lines


def section_stability(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """The ultimate bounds (21), (27), (30) beside the measured errors, per sensing."""
    lines = [
        "## Stability numbers (paper formulation)",
        "",
        "Ultimate bounds of (21) (TDC) and (30) (TDROC, ‖s‖ < ε) from the gains and the",
        "measured time-delay estimation error k̄ of (23) (max ‖M̂⁻¹‖ ‖Ĥ1(t + h) − Ĥ1(t)‖ after",
        "the start-up), with k̂ the median switching gain, beside the largest measured",
        "‖(e, ė)‖ after 5 s. ϖ2 of (27) (TDROC, ‖s‖ ≥ ε) is 2 (k̄ − k̂)‖BᵀP‖/λmin(Q), zero",
        "when k̂ ≥ k̄. A bound below the measurement means the measured k̄ underestimates the",
        "true TDE (it sees only sample-to-sample changes) or that the sampled loop left the",
        "continuous-time analysis behind.",
        "",
    ]
    for sensing in rep.sensings:
        lines += [
            f"### {sensing_label(rep, sensing)}",
            "",
            "| controller | path | k̄ measured | ϖ1 (21) / ϖ3 (30) | ϖ2 (27) | ultimate bound "
            "| measured max ‖(e, ė)‖ | within bound? |",
            "|---|---|---:|---:|---:|---:|---:|---|",
            *[
                f"| {LABELS[s.controller]} | {s.path} | {s.tde_bound:.3g} | {s.varpi:.3g} "
                f"| {'' if s.varpi2 is None else f'{s.varpi2:.3g}'} | {s.ultimate_bound:.3g} "
                f"| {s.measured:.3g} | {'yes' if s.measured <= s.ultimate_bound else '**no**'} |"
                for s in stability(rep, sensing)
            ],
            "",
        ]
    return lines


def stable_on_all_paths(rep: Reproduction, sensing: str, estimator: str) -> list[float]:
    """The swept ε at which TDROC is stable on every path (sensing, estimator)."""
    rows = [s for s in rep.sweep if s.sensing == sensing and s.estimator == estimator]
    return sorted({s.eps for s in rows} - {s.eps for s in rows if not s.stable})


def contrast_sentence(rep: Reproduction) -> list[str]:
    """The estimator, not TDROC: TDROC at the experiment's ε under encoder-average rates
    with the experiment's and the backward estimator. The wording follows the data."""
    c = rep.experiment.controller
    if rep.contrast() is None:
        return []
    at_eps = [s for s in rep.sweep if s.sensing == CONTRAST[0] and s.eps == c.eps]
    out = []
    for path in rep.refs:
        parts = [
            f"`{r.estimator}` {fmt_mm(r.metrics.rms_error)} mm RMS "
            f"({'stable' if r.stable else 'unstable'}, {r.ratio:.2f}× TDC's "
            f"{fmt_mm(r.tdc_rms)} mm, {r.metrics.saturated_steps} saturated steps)"
            for r in at_eps
            if r.metrics.path == path
        ]
        out.append(f"* {path}: " + "; ".join(parts) + ".")
    stable_eps = {
        est: stable_on_all_paths(rep, CONTRAST[0], est)
        for est in dict.fromkeys(s.estimator for s in rep.sweep if s.sensing == CONTRAST[0])
    }
    by_est = {r.estimator: r for r in at_eps}
    verdict = [
        f"Over the sweep, with `{CONTRAST[0]}` rates TDROC is stable on both paths at "
        + "; ".join(
            f"ε ∈ {{{', '.join(f'{e:g}' for e in eps) or 'none'}}} with `{est}`"
            for est, eps in stable_eps.items()
        )
        + ".",
    ]
    backward_bad = CONTRAST[1] in by_est and not by_est[CONTRAST[1]].stable
    others_ok = all(r.stable for e, r in by_est.items() if e != CONTRAST[1])
    if backward_bad and others_ok and len(by_est) > 1:
        verdict.append(
            f"At the paper's ε = {c.eps:g} only the `{CONTRAST[1]}` pairing is unstable: "
            "the estimator, not TDROC, destabilised the loop."
        )
    return [
        f"With `{CONTRAST[0]}` rates, TDROC at the paper's ε = {c.eps:g} (h = {c.h:g} s, "
        f"K1 = K2 = {c.k1:g} I, Q = I, n = {c.n}, a = {c.a:g}) gives, by estimator:",
        "",
        *out,
        "",
        "Why the estimator matters: under zero-order hold the mean rate over [t − h, t] that",
        "`encoder-average` measures is produced by both u(t − h) and u(t − 2h). The",
        "`backward` estimator pairs its quotient with u(t − h) alone, so Ĥ1 of (17) is off by a",
        "term proportional to u(t − h) − u(t − 2h); the `matched` blend removes that term.",
        "TDROC's k̂ of (25) is built from the same Ω differences, and inside the boundary",
        "layer k̂/ε acts as an extra feedback gain, so a small ε amplifies the error.",
        *verdict,
        "",
    ]


def section_sweep(rep: Reproduction, figures: Sequence[Figure]) -> list[str]:
    """TDROC's ε of (25) per sensing (and the encoder-average/backward contrast)."""
    c = rep.experiment.controller
    return [
        "## TDROC's boundary layer ε (paper formulation)",
        "",
        f"TDROC with ε varied, h = {c.h} s, K1 = K2 = {c.k1:g} I, Q = I, n = {c.n}, a = {c.a};",
        "TDC under the same sensing and estimator alongside. Inside the boundary layer",
        "Δu_a = k̂ s/ε is an extra feedback gain k̂/ε. 'unstable' means an RMS error above",
        f"{UNSTABLE_FACTOR:g}× TDC's (same sensing, estimator, path). Nothing was tuned: "
        "the defaults are the paper's.",
        "",
        *contrast_sentence(rep),
        "| sensing | estimator | ε | path | RMS error [mm] | max error [mm] | TDC RMS [mm] "
        "| RMS ÷ TDC | median k̂ | median k̂/ε | saturated steps | verdict |",
        "|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|",
        *[
            f"| {s.sensing} | {s.estimator} | {s.eps:g} | {s.metrics.path} "
            f"| {fmt_mm(s.metrics.rms_error)} | {fmt_mm(s.metrics.max_error)} "
            f"| {fmt_mm(s.tdc_rms)} | {s.ratio:.2f} | {s.metrics.median_gain:.3g} "
            f"| {s.metrics.median_gain / s.eps:.3g} "
            f"| {s.metrics.saturated_steps} | {'stable' if s.stable else '**unstable**'} |"
            for s in rep.sweep
        ],
        "",
    ]


# The report is these sections, in order. Append a section (a function of the
# reproduction and the figures returning Markdown lines) to extend it, or pass it to
# ``report_markdown(rep, figures, extra=(...))``.
REPORT_SECTIONS: list[Section] = [
    section_setting,
    section_figures,
    section_references,
    section_metrics,
    section_claims,
    section_stability,
    section_sweep,
]


def report_markdown(
    rep: Reproduction, figures: Sequence[Figure], extra: Sequence[Section] = ()
) -> str:
    """``REPORT.md``: the sections of ``REPORT_SECTIONS`` then ``extra``, in order."""
    lines: list[str] = []
    for section in (*REPORT_SECTIONS, *extra):
        lines += section(rep, figures)
    while lines and lines[-1] == "":
        lines.pop()
    return "\n".join(lines) + "\n"
