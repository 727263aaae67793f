"""The report of ``wmr reproduce`` on a robot other than the paper's: ``REPORT.md``,
``metrics.md``, ``metrics.csv`` and ``tracking.png`` written from the runs of the one driver
(:func:`runtime.reproduction.driver.reproduce`), with the model checks and the sampled-data
verdict of the robot's nominal model and scaled experiment. (The paper's robot's report is
:mod:`runtime.paper`'s.) Nothing written depends on the clock.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from modeling import audit
from runtime.bindings.physical_bounds import box_of, physical_roc_bounds
from runtime.bindings.robots import RobotSetup
from runtime.bindings.uncertainty import inertial_keys, roc_bounds, schedule_tde, tde_alpha
from runtime.experiment.settings import Experiment
from runtime.reproduction.driver import Reproduction, colors
from runtime.setting.robot import Setting
from runtime.sim.outcome import OFF_PATH_FRACTION
from runtime.sim.payload import plant_params_at
from runtime.stability.analysis import analyse_all, table
from runtime.stability.sampled_loop import covers


@dataclass(frozen=True)
class ModelChecks:
    """Over the uncertainty box, per formulation: the TDE condition's max ‖M⁻¹ M̂ − I‖₂
    (symmetric box, must be < 1 for TDC/TDROC; NaN where the box holds a robot the
    controllers would not accept) and ROC's (α, φ) (box above nominal)."""

    tde: float
    alpha: float
    phi: float


def model_checks(setup: RobotSetup, exp: Experiment, formulation: str) -> ModelChecks:
    """The TDE condition and ROC's bounds of the robot's nominal model over the box."""
    c = exp.controller
    try:
        tde = tde_alpha(setup.code, setup.nominal, c.uncertainty, formulation=formulation)[0]
    except ValueError:  # the box holds robots the controllers would not accept as models
        tde = float("nan")
    if exp.physical:  # ROC's bounds over the declared physical box, as ROC takes them
        b = physical_roc_bounds(setup.code, setup.nominal, box_of(setup.code, exp.physical),
                                formulation, c.roc_max_rate)
        return ModelChecks(tde, b.alpha, b.phi)
    alpha, phi = roc_bounds(setup.code, setup.nominal, c.uncertainty, formulation,
                            c.roc_max_rate)
    return ModelChecks(tde, alpha, phi)


def sampled_data_table(setting: Setting, sensing: str, grip: bool = False) -> str:
    """The sampled-data verdict of every controller and formulation with this sensing model:
    ``wmr stability``'s table for the same robot, scaled experiment and code
    (:func:`runtime.stability.analysis.analyse_all`, k̂ measured as it measures it); with
    ``grip``, its saturation, wind-up and grip verdict too (``slips`` with the wheel, time
    and the ``traction_mu`` to set, at the experiment's ``[plant] friction``)."""
    code, exp = setting.robot.code, setting.experiment
    if not covers(code):
        return "No sampled-data verdict: the root's pose is not the first coordinates.\n"
    e = replace(exp, sensing=replace(exp.sensing, velocity=sensing))
    return table(analyse_all(code, setting.robot.nominal, e, saturation=grip), code)


# --------------------------------------------------------------------------- outputs


def _fmt(x: float) -> str:
    return f"{x * 1000:.2f}"


def metrics_lines(rep: Reproduction) -> list[str]:
    lines = [
        "| sensing | path | form | controller | RMS error [mm] | max [mm] | final [mm] "
        "| RMS [% of scale] | RMS τ [N m] | max |τ| [N m] | saturated steps | outcome |",
        "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    labels = rep.labels
    for r in rep.table:
        result = r.status if r.status == "ok" else f"{r.status}: {r.detail}"
        lines.append(
            f"| {r.sensing} | {r.path} | {r.formulation} | {labels[r.controller]} "
            f"| {_fmt(r.rms_error)} | {_fmt(r.max_error)} | {_fmt(r.final_error)} "
            f"| {r.rms_percent:.2f} | {r.rms_torque:.3g} | {r.max_torque:.3g} "
            f"| {r.saturated_steps} | {result} |"
        )
    return lines


def schedule_tdes(setup: RobotSetup, exp: Experiment) -> dict[str, float]:
    """Per formulation: ‖M⁻¹M̂ − I‖ of the nominal model against the simulated robot with
    the experiment's payloads off and on."""
    code = setup.code
    loaded = [plant_params_at(code, exp, 0.0, setup.plant),
              plant_params_at(code, exp, exp.plant.extra_on_at, setup.plant)]
    return {f: schedule_tde(code, setup.nominal, loaded, f) for f in code.formulations}


def report_lines(rep: Reproduction) -> list[str]:
    s, exp = rep.setting.robot, rep.experiment
    checks = {f: model_checks(s, exp, f) for f in s.code.formulations}
    tde = schedule_tdes(s, exp)
    # The grip verdict (a simulation per controller) once, at the first sensing model: the
    # saturation and grip columns of the others would repeat it within their sensing noise.
    verdicts = {sensing: sampled_data_table(rep.setting, sensing, grip=i == 0)
                for i, sensing in enumerate(rep.sensings)}
    c, pl, se = exp.controller, exp.plant, exp.sensing
    inertial = inertial_keys(s.code, s.nominal)
    out = [
        f"# The paper's experiment on robot '{s.name}'",
        "",
        f"Robot `{Path(s.source).as_posix()}`; generated code `{s.code.prefix}_` "
        f"({s.code.nq} coordinates, {s.code.nu} driven wheels; formulations "
        f"{', '.join(s.code.formulations)}; controllers "
        f"{', '.join(c.label for c in s.code.controller_infos)}). Written by `wmr reproduce "
        "--robot`.",
        "",
        "## Conditions",
        "",
        f"- Sampling h = {c.h:g} s; plant: the generated model, RK4 in C with {pl.substeps} "
        "steps per sample; zero-order hold.",
        f"- Gains K1 = {c.k1:g} I, K2 = {c.k2:g} I, Q = diag({c.q_pos:g} I, {c.q_vel:g} I); "
        f"ε = {c.eps:g}; TDROC n = {c.n}, a = {c.a:g}; ASMC γ = {c.gamma:g}; "
        f"τ_max = {c.tau_max:.4g} N m.",
        f"- Sensing: {', '.join(rep.sensings)} (wheel encoders {se.encoder_ppr} ppr, "
        f"quadrature; every other coordinate by odometry); q̈(t − h) estimator "
        f"{se.accel_estimator}.",
        f"- Nominal model: the robot's numbers. Simulated robot: the same plus a payload "
        f"of {pl.fixed_payload:.4g} kg at ({pl.fixed_payload_x:.3g}, {pl.fixed_payload_y:.3g}) "
        f"m on the root body, and {pl.extra_payload:.4g} kg at ({pl.extra_payload_x:.3g}, "
        f"{pl.extra_payload_y:.3g}) m on for half of every {pl.extra_period:g} s from "
        f"t = {pl.extra_on_at:g} s; wheel friction {pl.viscous:.3g} N m s/rad + "
        f"{pl.coulomb:.3g} N m (unknown to the controllers).",
        "",
        "Scaled from the paper's setting (fields an experiment file sets are kept):",
        "",
        *[f"- {line}" for line in rep.setting.scaling],
        "",
        *audit.section(s.warnings),  # the warnings travel with the robot (MODEL.md too)
        "## Model checks",
        "",
        f"Inertial parameters (those the kinematics does not depend on): {', '.join(inertial)}.",
        "",
        "| formulation | TDE ‖M⁻¹M̂ − I‖ with the payloads | over a ±"
        f"{100 * c.uncertainty:g} % box | ROC α | ROC φ |",
        "|---|---:|---:|---:|---:|",
    ]
    for f, b in checks.items():
        box = "—" if math.isnan(b.tde) else f"{b.tde:.3g}"
        out.append(f"| {f} | {tde[f]:.3g} | {box} | {b.alpha:.3g} "
                   f"| {b.phi:.3g} |")
    out += [
        "",
        "TDC and TDROC need the TDE value below 1 (condition of (17)). The box perturbs every "
        "inertial parameter independently, combinations no physical robot has when the "
        "parameters are base parameters, so it is a conservative bound; the payload column "
        "is this experiment's."
        + (" —: the box holds robots the controllers would not accept as a model (a mass "
           "matrix that is not positive definite, e.g. m I ≤ K²), so the condition is not "
           "defined over it." if any(math.isnan(b.tde) for b in checks.values()) else "")
        + (f" ROC's α and φ are sound bounds over the experiment's [physical_uncertainty] "
           f"({exp.physical.describe()}; runtime.bindings.physical_bounds), not the box."
           if exp.physical else ""),
        "",
        "## Results",
        "",
        "Error: distance of the root body's frame origin from its reference, at the sample "
        "instants. Scale: the circle's radius, the lawn mower's leg spacing. Outcome: `ok` "
        "only if the configuration was accepted, no step failed and the final and RMS errors "
        f"are both within {100 * OFF_PATH_FRACTION:g} % of the path's scale "
        "(`runtime/sim/outcome.py`); `off path` otherwise.",
        "",
        *metrics_lines(rep),
        "",
        "![tracking](tracking.png)",
        "",
    ]
    if verdicts:
        out += ["## Sampled-data verdict", "",
                "Predicted as `wmr stability` predicts it for this robot and scaled experiment "
                "(nominal robot, no friction, linearised about the circle's steady motion; "
                "`runtime/stability/`); the saturation column, at the first sensing model, is "
                "its torque, wind-up and grip verdict (the payload on, the experiment's "
                f"friction μ = {exp.plant.friction:g}, loads from the one load model):", ""]
        for sensing, text in verdicts.items():
            out += [f"{sensing}:", "", *text.rstrip("\n").split("\n"), ""]
    return out


def write_csv(rep: Reproduction, path: Path) -> None:
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["sensing", "path", "formulation", "controller", "rms_error_m",
                    "max_error_m", "final_error_m", "rms_percent", "rms_torque_Nm",
                    "max_torque_Nm", "saturated_steps", "failed_at_s", "status"])
        for r in rep.table:
            w.writerow([r.sensing, r.path, r.formulation, r.controller, f"{r.rms_error:.6g}",
                        f"{r.max_error:.6g}", f"{r.final_error:.6g}", f"{r.rms_percent:.4g}",
                        f"{r.rms_torque:.6g}", f"{r.max_torque:.6g}", r.saturated_steps,
                        "" if r.failed_at is None else f"{r.failed_at:g}", r.status])


def plot(rep: Reproduction, path: Path) -> None:
    """Paths in the plane (reference and each controller) and the error over time, for the
    first sensing model and the minimal formulation."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sensing, form = rep.sensings[0], "minimal"
    fig = Figure(figsize=(11, 7.5), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    infos = rep.code.controller_infos
    color = colors(rep.code)
    for col, name in enumerate(rep.refs):
        ref = rep.refs[name]
        ax = axes[0, col]
        ax.plot(ref.q[:, 0], ref.q[:, 1], color="black", lw=2.5, alpha=0.35, label="reference")
        for info in infos:
            if form not in info.formulations:
                continue
            r = rep.runs[(sensing, info.name, form, name)]
            ax.plot(r.q[:, 0], r.q[:, 1], color=color[info.name], lw=1, label=info.label)
            axes[1, col].semilogy(r.t, np.maximum(r.position_error, 1e-7) * 1000,
                                  color=color[info.name], lw=1, label=info.label)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{name}: root frame origin (x, y) [m]")
        ax.legend(fontsize=8)
        axes[1, col].set_title(f"{name}: position error [mm]")
        axes[1, col].set_xlabel("t [s]")
    fig.suptitle(f"robot '{rep.setting.robot.name}', {sensing}, {form} formulation, h = "
                 f"{rep.experiment.controller.h:g} s, payload schedule and friction as in "
                 "REPORT.md")
    fig.savefig(path, metadata={"Software": None})


def write_outputs(rep: Reproduction, out: Path, plots: bool = True) -> None:
    report = "\n".join(report_lines(rep))  # its checks may refuse the robot: before any file
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.md").write_text("\n".join(metrics_lines(rep)) + "\n", encoding="utf-8")
    write_csv(rep, out / "metrics.csv")
    (out / "REPORT.md").write_text(report, encoding="utf-8")
    if plots:
        plot(rep, out / "tracking.png")
