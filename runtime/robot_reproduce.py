"""``python -m runtime reproduce --robot FILE``: the paper's experiment on any robot.

The experiment of :mod:`runtime.paper.reproduce` — circle and lawn mower, the four controllers in
every formulation the robot's code has, each ``--sensing`` model, payload put on and taken
off, friction the controllers do not know — scaled to the robot
(:mod:`runtime.robot_scale`; the scaled settings are printed and written), simulated through
the robot's generated C (:mod:`runtime.robot_simulation`). Writes ``REPORT.md``,
``metrics.md``, ``metrics.csv`` and ``tracking.png`` to the output folder; nothing written
depends on the clock.
"""

from __future__ import annotations

import csv
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from runtime import cbuild
from runtime.experiment import Experiment
from runtime.paper.paths import DRISHTI_RADIUS, ROC_MAX_RATE
from runtime.robot_model_checks import ModelBounds, model_bounds, schedule_tde
from runtime.robot_paths import Path as RefPath
from runtime.robot_paths import circle, lawnmower
from runtime.robot_scale import (
    RobotScale,
    inertial_keys,
    robot_scale,
    scaled_experiment,
)
from runtime.robot_simulation import RobotRun, plant_params_at, run
from runtime.robot_source import RobotSetup

CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")
LABELS = {"tdc": "TDC", "tdroc": "TDROC", "roc": "ROC", "asmc": "ASMC"}


@dataclass(frozen=True)
class Row:
    """One run's numbers."""

    sensing: str
    path: str
    formulation: str
    controller: str
    rms_error: float  # m, root frame origin
    max_error: float
    final_error: float
    rms_percent: float  # of the path's scale
    rms_torque: float
    max_torque: float
    saturated_steps: int
    failed_at: float | None
    status: str


@dataclass(frozen=True)
class RobotReproduction:
    setup: RobotSetup
    experiment: Experiment  # scaled
    scale: RobotScale
    settings: list[str]  # what scaling did, one line per field
    sensings: tuple[str, ...]
    paths: dict[str, RefPath]
    bounds: dict[str, ModelBounds]  # per formulation, over the uncertainty box
    schedule_tde: dict[str, float]  # per formulation: ‖M⁻¹M̂ − I‖ with the payloads on
    runs: dict[tuple[str, str, str, str], RobotRun]  # (sensing, path, form, controller)
    rows: list[Row]
    seconds: float


def _row(r: RobotRun, sensing: str, scale: float) -> Row:
    e = r.position_error
    if not len(e):  # refused at init
        nan = float("nan")
        return Row(sensing, r.path, r.formulation, r.controller, nan, nan, nan, nan, nan, nan,
                   0, r.failed_at, r.status)
    rms = float(np.sqrt(np.mean(e**2)))
    return Row(sensing, r.path, r.formulation, r.controller, rms, float(e.max()), float(e[-1]),
               100 * rms / scale, float(np.sqrt(np.mean(r.tau**2))), float(np.abs(r.tau).max()),
               r.saturated, r.failed_at, r.status)


def reproduce_robot(setup: RobotSetup, exp: Experiment, sensings: Sequence[str],
                    progress: bool = False) -> RobotReproduction:
    """Run the scaled experiment (no files written)."""
    start = time.perf_counter()
    code = setup.code
    scale = robot_scale(code, setup.nominal)
    exp, lines = scaled_experiment(exp, scale)
    if progress:
        print(f"robot '{setup.name}' from {setup.source}:", *lines, sep="\n  ", flush=True)
    h = exp.controller.h
    paths = {
        "circle": circle(code, scale, setup.nominal, h, exp.paths.circle_duration),
        "lawnmower": lawnmower(code, scale, setup.nominal, h, exp.paths.lawnmower_duration),
    }
    forms = tuple(code.robot.FORMULATIONS)
    # ROC's bounds over wheel rates up to Drishti's 8 rad/s scaled like the paths' rates.
    max_rate = ROC_MAX_RATE * scale.size * DRISHTI_RADIUS / scale.wheel_radius
    bounds = {f: model_bounds(code, setup.nominal, exp.controller.uncertainty, f, max_rate)
              for f in forms}
    loaded = [plant_params_at(code, exp, 0.0, setup.plant),
              plant_params_at(code, exp, exp.plant.extra_on_at, setup.plant)]
    tde = {f: schedule_tde(code, setup.nominal, loaded, f) for f in forms}
    lib = cbuild.build(c_dir=code.c_dir, prefix=code.prefix)
    runs: dict[tuple[str, str, str, str], RobotRun] = {}
    rows: list[Row] = []
    total = len(sensings) * len(paths) * len(forms) * len(CONTROLLERS)
    for sensing in sensings:
        e = replace(exp, sensing=replace(exp.sensing, velocity=sensing))
        for name, path in paths.items():
            for form in forms:
                for ctrl in CONTROLLERS:
                    # the simulated robot: the file's numbers, with the experiment's payloads
                    r = run(lib, code, ctrl, form, name, path.ref, setup.nominal, e,
                            bounds[form], plant_base=setup.plant)
                    runs[(sensing, name, form, ctrl)] = r
                    rows.append(_row(r, sensing, path.scale))
                    if progress:
                        print(f"[{len(rows):2d}/{total}] {sensing:15s} {name:9s} {form:7s} "
                              f"{LABELS[ctrl]:5s} RMS {rows[-1].rms_error * 1000:9.2f} mm",
                              flush=True)
    return RobotReproduction(setup, exp, scale, lines, tuple(sensings), paths, bounds, tde,
                             runs, rows, time.perf_counter() - start)


# --------------------------------------------------------------------------- outputs


def _fmt(x: float) -> str:
    return f"{x * 1000:.2f}"


def metrics_lines(rep: RobotReproduction) -> list[str]:
    lines = [
        "| sensing | path | form | controller | RMS error [mm] | max [mm] | final [mm] "
        "| RMS [% of scale] | RMS τ [N m] | max |τ| [N m] | saturated steps | outcome |",
        "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rep.rows:
        outcome = "ok" if r.failed_at is None else f"failed at {r.failed_at:g} s: {r.status}"
        lines.append(
            f"| {r.sensing} | {r.path} | {r.formulation} | {LABELS[r.controller]} "
            f"| {_fmt(r.rms_error)} | {_fmt(r.max_error)} | {_fmt(r.final_error)} "
            f"| {r.rms_percent:.2f} | {r.rms_torque:.3g} | {r.max_torque:.3g} "
            f"| {r.saturated_steps} | {outcome} |"
        )
    return lines


def report_lines(rep: RobotReproduction) -> list[str]:
    s, exp = rep.setup, rep.experiment
    c, pl, se = exp.controller, exp.plant, exp.sensing
    inertial = inertial_keys(s.code, s.nominal)
    out = [
        f"# The paper's experiment on robot '{s.name}'",
        "",
        f"Robot file `{Path(s.source).as_posix()}`; generated code `{s.code.prefix}_` "
        f"({s.code.nq} coordinates, {s.code.nu} driven wheels; formulations "
        f"{', '.join(s.code.robot.FORMULATIONS)}). Written by `python -m runtime reproduce "
        "--robot`.",
        "",
        "## Conditions",
        "",
        f"- Sampling h = {c.h:g} s; plant RK4 with {pl.substeps} steps per sample; zero-order "
        "hold.",
        f"- Gains K1 = {c.k1:g} I, K2 = {c.k2:g} I, Q = diag({c.q_pos:g} I, {c.q_vel:g} I); "
        f"ε = {c.eps:g}; TDROC n = {c.n}, a = {c.a:g}; ASMC γ = {c.gamma:g}; "
        f"τ_max = {c.tau_max:.4g} N m.",
        f"- Sensing: {', '.join(rep.sensings)} (wheel encoders {se.encoder_ppr} ppr, "
        f"quadrature; every other coordinate by odometry); q̈(t − h) estimator "
        f"{se.accel_estimator}.",
        f"- Nominal model: the robot file's numbers. Simulated robot: the same plus a payload "
        f"of {pl.fixed_payload:.4g} kg at ({pl.fixed_payload_x:.3g}, {pl.fixed_payload_y:.3g}) "
        f"m on the root body, and {pl.extra_payload:.4g} kg at ({pl.extra_payload_x:.3g}, "
        f"{pl.extra_payload_y:.3g}) m on for half of every {pl.extra_period:g} s from "
        f"t = {pl.extra_on_at:g} s; wheel friction {pl.viscous:.3g} N m s/rad + "
        f"{pl.coulomb:.3g} N m (unknown to the controllers).",
        "",
        "Scaled from the paper's setting (fields an experiment file sets are kept):",
        "",
        *[f"- {line}" for line in rep.settings],
        "",
        "## Model checks",
        "",
        f"Inertial parameters (those the kinematics does not depend on): {', '.join(inertial)}.",
        "",
        "| formulation | TDE ‖M⁻¹M̂ − I‖ with the payloads | over a ±"
        f"{100 * c.uncertainty:g} % box | ROC α | ROC φ |",
        "|---|---:|---:|---:|---:|",
    ]
    for f, b in rep.bounds.items():
        out.append(f"| {f} | {rep.schedule_tde[f]:.3g} | {b.tde:.3g} | {b.alpha:.3g} "
                   f"| {b.phi:.3g} |")
    out += [
        "",
        "TDC and TDROC need the TDE value below 1 (condition of (17)). The box perturbs every "
        "inertial parameter independently, combinations no physical robot has when the "
        "parameters are base parameters, so it is a conservative bound; the payload column "
        "is this experiment's.",
        "",
        "## Results",
        "",
        "Error: distance of the root body's frame origin from its reference, at the sample "
        "instants. Scale: the circle's radius, the lawn mower's leg spacing.",
        "",
        *metrics_lines(rep),
        "",
        "![tracking](tracking.png)",
        "",
    ]
    return out


def write_csv(rep: RobotReproduction, path: Path) -> None:
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["sensing", "path", "formulation", "controller", "rms_error_m",
                    "max_error_m", "final_error_m", "rms_percent", "rms_torque_Nm",
                    "max_torque_Nm", "saturated_steps", "failed_at_s", "status"])
        for r in rep.rows:
            w.writerow([r.sensing, r.path, r.formulation, r.controller, f"{r.rms_error:.6g}",
                        f"{r.max_error:.6g}", f"{r.final_error:.6g}", f"{r.rms_percent:.4g}",
                        f"{r.rms_torque:.6g}", f"{r.max_torque:.6g}", r.saturated_steps,
                        "" if r.failed_at is None else f"{r.failed_at:g}", r.status])


def plot(rep: RobotReproduction, path: Path) -> None:
    """Paths in the plane (reference and each controller) and the error over time, for the
    first sensing model and the minimal formulation."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sensing, form = rep.sensings[0], "minimal"
    fig = Figure(figsize=(11, 7.5), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    colors = {"tdc": "tab:blue", "tdroc": "tab:red", "roc": "tab:green", "asmc": "tab:purple"}
    for col, name in enumerate(rep.paths):
        ref = rep.paths[name].ref
        ax = axes[0, col]
        ax.plot(ref.q[:, 0], ref.q[:, 1], color="black", lw=2.5, alpha=0.35, label="reference")
        for ctrl in CONTROLLERS:
            r = rep.runs[(sensing, name, form, ctrl)]
            ax.plot(r.q[:, 0], r.q[:, 1], color=colors[ctrl], lw=1, label=LABELS[ctrl])
            axes[1, col].semilogy(r.t, np.maximum(r.position_error, 1e-7) * 1000,
                                  color=colors[ctrl], lw=1, label=LABELS[ctrl])
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{name}: root frame origin (x, y) [m]")
        ax.legend(fontsize=8)
        axes[1, col].set_title(f"{name}: position error [mm]")
        axes[1, col].set_xlabel("t [s]")
    fig.suptitle(f"robot '{rep.setup.name}', {sensing}, {form} formulation, h = "
                 f"{rep.experiment.controller.h:g} s, payload schedule and friction as in "
                 "REPORT.md")
    fig.savefig(path, metadata={"Software": None})


def write_outputs(rep: RobotReproduction, out: Path, plots: bool = True) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.md").write_text("\n".join(metrics_lines(rep)) + "\n", encoding="utf-8")
    write_csv(rep, out / "metrics.csv")
    (out / "REPORT.md").write_text("\n".join(report_lines(rep)), encoding="utf-8")
    if plots:
        plot(rep, out / "tracking.png")
