"""The generated-model plant and MuJoCo side by side: ``docs/MUJOCO.md``.

    python -m runtime.commands.compare_plants [--robot ROBOT] [--experiment FILE] [--out FILE]

Every controller and formulation of the robot, on both paths, under each sensing model, is
run on the generated plant (ideal rolling) and on MuJoCo (``runtime.mujoco.plant``) at the
floors of :data:`CASES`: μ = 1, 0.2, 0.1, and μ = 0.1 with the traction-aware torque limit
(``[controller] traction_mu``). Per run: RMS and max position error, outcome
(``runtime.sim.outcome``), samples whose torque was clipped, and in MuJoCo the driven
wheels' measured slip (rim speed less the centre's speed along the heading): its largest
value and the first instant it exceeds :data:`SLIP_THRESHOLD`. The document also states the
wheels' static loads (``modeling.contact_loads.static_loads``) against the engine's at rest,
and the run time of a run on each plant. Not a test: ``tests/runtime/test_mujoco.py`` runs a
shortened experiment through :func:`compare` and :func:`markdown`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np
from numpy.typing import NDArray

from modeling.contact_loads import static_loads
from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.mujoco.plant import MujocoPlant
from runtime.setting.layout import robot_layout, traction_torque_limit
from runtime.setting.robot import Setting
from runtime.sim import loop, paths
from runtime.sim.outcome import outcome
from runtime.sim.plant import GeneratedPlant, library_for
from runtime.sim.slip_monitor import MonitoredPlant, SlipMonitor
from runtime.stability import agreement

Array = NDArray[np.float64]
# (label, floor's μ, traction_mu of the controllers' torque limit; 0: the experiment's)
CASES: tuple[tuple[str, float, float], ...] = (
    ("μ = 1", 1.0, 0.0),
    ("μ = 0.2", 0.2, 0.0),
    ("μ = 0.1", 0.1, 0.0),
    ("μ = 0.1, traction limit", 0.1, 0.1),
)
SENSINGS = ("sample-instant", "encoder-average")
ONSET_FRICTIONS = (0.05, 0.1, 0.15, 0.2, 0.3)  # μ of the slip monitor's verification
SLIP_THRESHOLD = 0.02  # m/s: a wheel slips (μ = 1 creep stays below 1 mm/s on Drishti)


class SlipRecordingPlant(MujocoPlant):
    """The MuJoCo plant, recording the driven wheels' slip after every sample."""

    def __init__(self, code: RobotCode, exp: Experiment, base: dict[str, float]) -> None:
        super().__init__(code, exp, robot_layout(code, base))
        self.slips: list[Array] = []

    def advance(self, tau: list[float], dt: float, nsub: int) -> bool:
        ok = super().advance(tau, dt, nsub)
        self.slips.append(self.slip())
        return ok


@dataclass(frozen=True)
class Cell:
    """One run: errors (m), outcome, clipped samples, slip (m/s; nan on the model plant),
    slip onset (s; None: never above the threshold), wall time (s)."""

    rms: float
    max: float
    status: str
    saturated: int
    slip_max: float
    slip_onset: float | None
    seconds: float


@dataclass(frozen=True)
class Row:
    sensing: str
    path: str
    formulation: str
    controller: str
    model: Cell
    engine: tuple[Cell, ...]  # one per case


@dataclass(frozen=True)
class Onset:
    """The slip monitor on a model-plant run (the largest friction coefficient it needs,
    and when it first needs more than each μ of :data:`ONSET_FRICTIONS`) against the slip
    MuJoCo measures at that μ (first instant above :data:`SLIP_THRESHOLD`)."""

    path: str
    formulation: str
    controller: str
    needed_max: float
    predicted: tuple[float | None, ...]
    measured: tuple[float | None, ...]


@dataclass(frozen=True)
class Comparison:
    setting: Setting
    cases: tuple[tuple[str, float, float], ...]
    rows: tuple[Row, ...]
    limits: tuple[float, ...]  # the torque limit of each case (N m)
    loads: dict[str, tuple[float, float]]  # contact -> (stated static load, engine at rest)
    onsets: tuple[Onset, ...] = ()  # the slip monitor against the engine
    onset_frictions: tuple[float, ...] = ()  # the μ of each onset column
    verdicts: tuple[agreement.Case, ...] = ()  # wmr stability against the engine


def _cell(r: loop.Run, scale: float, seconds: float, slips: list[Array] | None,
          h: float) -> Cell:
    o = outcome(r, scale)
    e = r.position_error
    rms = float(np.sqrt(np.mean(e**2))) if len(e) else math.nan
    peak = float(e.max()) if len(e) else math.nan
    slip_max, onset = math.nan, None
    if slips:
        s = np.max(np.abs(np.array(slips)), axis=1)
        slip_max = float(s.max())
        above = np.nonzero(s > SLIP_THRESHOLD)[0]
        onset = float((above[0] + 1) * h) if len(above) else None
    return Cell(rms, peak, o.status, r.saturated, slip_max, onset, seconds)


def engine_loads(code: RobotCode, exp: Experiment, base: dict[str, float],
                 masses: Sequence[float] | None = None) -> dict[str, float]:
    """The normal force on each contact of the MuJoCo robot at rest, with the payloads of
    ``masses`` (kg: fixed, extra; default: the fixed payload on); a contact that lifted
    off is absent."""
    plant = MujocoPlant(code, exp, robot_layout(code, base))
    plant.set_payload(np.array([exp.plant.fixed_payload, 0.0] if masses is None
                               else masses, dtype=np.float64))
    plant.start(np.zeros(code.nq))
    m, d = plant.model, plant.data
    mujoco.mj_step(m, d, nstep=round(0.5 / m.opt.timestep))
    out: dict[str, float] = {}
    force = np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        mujoco.mj_contactForce(m, d, i, force)
        name = m.geom(c.geom[1]).name or m.geom(c.geom[0]).name
        name = name.removeprefix("tyre_")
        out[name] = out.get(name, 0.0) + float(force[0])
    return out


def _one(setting: Setting, exp: Experiment, run: tuple[str, str, str, str],
         engine: bool) -> Cell:
    """One run (sensing, path, formulation, controller) on the plant ``exp`` names."""
    sensing, name, form, controller = run
    setup, code = setting.robot, setting.robot.code
    e = replace(exp, sensing=replace(exp.sensing, velocity=sensing))
    ref = paths.reference(code, setup.nominal, e, name)
    plant = SlipRecordingPlant(code, e, setup.plant) if engine else None
    t0 = time.perf_counter()
    r = loop.run(code, controller, form, ref, setup.nominal, e, plant_params=setup.plant,
                 plant=plant)
    return _cell(r, ref.scale, time.perf_counter() - t0, plant.slips if plant else None,
                 e.controller.h)


def engine_outcome(setting: Setting, exp: Experiment, path: str, formulation: str,
                   controller: str) -> tuple[str, str]:
    """One MuJoCo run's outcome for :mod:`runtime.stability.agreement`: (``slips``,
    ``unstable`` or ``ok``, a few words with its numbers)."""
    c = _one(setting, exp, (exp.sensing.velocity, path, formulation, controller), engine=True)
    if c.slip_onset is not None:
        return "slips", f"slips from {c.slip_onset:g} s, {c.status}, {_mm(c.rms)} mm RMS"
    if c.status != "ok":
        return "unstable", f"{c.status}, {_mm(c.rms)} mm RMS"
    return "ok", f"ok, {_mm(c.rms)} mm RMS, slip ≤ {c.slip_max * 1e3:.0f} mm/s"


def compare(setting: Setting, sensings: Sequence[str] = SENSINGS,
            cases: Sequence[tuple[str, float, float]] = CASES,
            progress: bool = False,
            onset_frictions: Sequence[float] = ONSET_FRICTIONS,
            verdicts: bool = False) -> Comparison:
    """Run every setting on both plants (see the module docstring); ``verdicts``: also
    :mod:`runtime.stability.agreement`'s table (slow: 20 settings of h and μ)."""
    setup, exp = setting.robot, setting.experiment
    code = setup.code
    exps = []
    for _, mu, traction in cases:
        c = exp.controller
        limit = (min(c.tau_max, traction_torque_limit(code, setup.plant, exp, traction))
                 if traction > 0 else c.tau_max)
        exps.append(replace(exp, plant=replace(exp.plant, model="mujoco", friction=mu),
                            controller=replace(c, tau_max=limit)))
    rows: list[Row] = []
    for sensing in sensings:
        for name in paths.PATHS:
            for form, info in code.runs():
                run = (sensing, name, form, info.name)
                model = _one(setting, replace(exp, plant=replace(exp.plant, model="generated")),
                             run, engine=False)
                engine = tuple(_one(setting, e, run, engine=True) for e in exps)
                rows.append(Row(sensing, name, form, info.name, model, engine))
                if progress:
                    print(f"[{len(rows)}] {sensing} {name} {form} {info.label}: model "
                          f"{model.rms * 1e3:.2f} mm, MuJoCo "
                          + ", ".join(f"{c.rms * 1e3:.1f}" for c in engine) + " mm",
                          flush=True)
    stated = static_loads(robot_layout(code, setup.plant),
                          ((exp.plant.fixed_payload, exp.plant.fixed_payload_x,
                            exp.plant.fixed_payload_y),))
    measured = engine_loads(code, exps[0], setup.plant)
    loads = {k: (v, measured.get(k, math.nan)) for k, v in stated.items()}
    found = (agreement.cases(code, setup.nominal, exp, lambda e, path, form, ctrl:
                             engine_outcome(setting, e, path, form, ctrl), progress=progress)
             if verdicts else ())
    return Comparison(setting, tuple(cases), tuple(rows),
                      tuple(e.controller.tau_max for e in exps), loads,
                      onsets(setting, onset_frictions, sensings[0]) if onset_frictions else (),
                      tuple(onset_frictions), found)


def onsets(setting: Setting, frictions: Sequence[float], sensing: str) -> tuple[Onset, ...]:
    """The slip monitor's predicted onset of slip against MuJoCo's, every controller and
    path, under ``sensing``."""
    setup, code = setting.robot, setting.robot.code
    exp = setting.experiment
    exp = replace(exp, sensing=replace(exp.sensing, velocity=sensing))
    monitor = SlipMonitor(code, robot_layout(code, setup.plant), exp)
    h = exp.controller.h
    out = []
    for name in paths.PATHS:
        ref = paths.reference(code, setup.nominal, exp, name)
        for form, info in code.runs():
            model_exp = replace(exp, plant=replace(exp.plant, model="generated"))
            plant = MonitoredPlant(GeneratedPlant(code, library_for(code), exp.plant.viscous,
                                                  exp.plant.coulomb), monitor)
            loop.run(code, info.name, form, ref, setup.nominal, model_exp,
                     plant_params=setup.plant, plant=plant)
            needed = np.array(plant.needed)
            predicted: list[float | None] = []
            measured: list[float | None] = []
            for mu in frictions:
                above = np.nonzero(needed > mu)[0]
                predicted.append(float(above[0] * h) if len(above) else None)
                e = replace(exp, plant=replace(exp.plant, model="mujoco", friction=mu))
                measured.append(_one(setting, e, (sensing, name, form, info.name),
                                     engine=True).slip_onset)
            out.append(Onset(name, form, info.name,
                             float(needed.max()) if len(needed) else math.nan,
                             tuple(predicted), tuple(measured)))
    return tuple(out)


def _mm(x: float) -> str:
    return "—" if math.isnan(x) else f"{x * 1e3:.2f}" if x < 0.1 else f"{x * 1e3:.0f}"


def _t(t: float | None) -> str:
    return "—" if t is None else f"{t:.1f}"


def _status(c: Cell) -> str:
    return "ok" if c.status == "ok" else f"**{c.status}**"


def _slip(c: Cell) -> str:
    if math.isnan(c.slip_max):
        return "—"
    onset = "no" if c.slip_onset is None else f"from {c.slip_onset:g} s"
    return f"{c.slip_max * 1e3:.0f} ({onset})"


def markdown(comp: Comparison) -> str:
    """The document (see the module docstring)."""
    s, exp = comp.setting.robot, comp.setting.experiment
    labels = {i.name: i.label for _, i in s.code.runs()}
    pl = exp.plant
    lines = [
        f"# The generated-model plant against MuJoCo: robot '{s.name}'",
        "",
        "Generated by `python -m runtime.commands.compare_plants` "
        "(`runtime/plant_comparison.py`); do not edit.",
        "",
        "Every controller runs the same closed loop (`runtime/sim/loop.py`: the generated C "
        "controller, encoders and odometry, the payload schedule) on two plants: the "
        "derived model integrated by RK4 (ideal rolling: a wheel never slips) and MuJoCo on "
        "the MJCF `wmr mjcf` writes from the robot's description (the same planar inertias, "
        "checked to 1e-6 by `tests/runtime/test_mujoco.py`; point-contact wheels, contact time "
        f"constant {pl.contact_timeconst:g} s, frictionless supports for a single axle). "
        "Errors in mm (RMS / max of the reference point's distance from the reference); "
        "outcome as `wmr reproduce` classifies it; slip: the driven wheels' largest rim "
        "speed less ground speed (mm/s), and when it first exceeds "
        f"{SLIP_THRESHOLD * 1e3:.0f} mm/s; sat: samples whose torque was clipped.",
        "",
        "Torque limits: " + ", ".join(f"{label}: {lim:.3g} N m" for (label, _, _), lim
                                      in zip(comp.cases, comp.limits, strict=True))
        + " (the traction limit is `[controller] traction_mu` = 0.1: μ N r of the lightest "
        "driven wheel at rest over the payload states, N from the one load model).",
        "",
    ]
    lines += _summary(comp)
    lines += ["", "## Every run", "", *_runs_table(comp)]
    lines += ["", "## Wheel loads at rest (N)", "",
              "The slip monitor, the traction limit and the grip verdict take each "
              "contact's normal load from one load model (`modeling.contact_loads`: the "
              "robot as one rigid assembly on equal contact springs, a support in tension "
              "lifted off). Where the split is statically indeterminate (three contacts or "
              "more off one plane's worth of equations) it depends on the springs: MuJoCo "
              "scales a contact's stiffness by its body's inverse weight, so the MJCF gives "
              "each contact geom the time constant that makes the springs equal "
              "(`modeling.mjcf_export.contact_time_constants`), and the engine carries the "
              "stated loads (tests/runtime/test_contact_loads.py: within 2 %). The contacts "
              "are the wheels and the supports the robot file states (`[[support]]`, "
              "`modeling.supports`: name, body, position in the body frame, radius); a "
              "file that states none, Drishti's included, stands on the default the "
              "exporter always used: none if the wheel contacts are not all on one line, "
              "else two frictionless spheres on the root body on the normal to the wheels' "
              "line through its midpoint, at ± max(half the wheels' span, twice the bodies' "
              "centre of mass's distance from the line), radius half the smallest wheel "
              "radius (Drishti: 0.2211 m ahead of and behind the axle midpoint, i.e. "
              "x = +0.1011 and −0.3411 m from C):", "",
              "| contact | stated | MuJoCo at rest |", "|---|---|---|"]
    for k, (stated, measured) in comp.loads.items():
        lines.append(f"| {k} | {stated:.1f} | {measured:.1f} |")
    if comp.onsets:
        mus = comp.onset_frictions
        lines += ["", "## The slip monitor against the engine", "",
                  "`runtime/sim/slip_monitor.py` takes each driven wheel's contact force from "
                  "the generated `<prefix>_wheel_contact_forces` (the multipliers of (9), "
                  "solved as (10)–(12) do, in newtons): F_x along the wheel's heading (its "
                  "rolling row; equal to (τ − τ_f − J θ̈)/r, tested) and F_y along its axle "
                  "(the axle's no-side-slip row, split between the axle's wheels in "
                  "proportion to their normal loads: an assumption, the rigid model does not "
                  "split it), and compares √(F_x² + F_y²) with μ N (friction circle; N: the "
                  "load model's, with the payload on board and the load transfer of the "
                  "acceleration ΣF/m). Against MuJoCo's contact forces on a turn from rest "
                  "(tests/runtime/test_mujoco.py, tests/runtime/test_contact_loads.py): "
                  "F_x within 0.2 % "
                  "(Drishti), the axle's F_y within 1.3 %, each wheel's normal load within "
                  "3 % once the start's transient has passed. Run on the model plant (which "
                  "cannot slip), the monitor "
                  "gives the friction coefficient each run needs (its largest |F|/N) and the "
                  "first instant it needs more than μ: the predicted onset of slip. MuJoCo "
                  "at that μ measures when a wheel's slip first exceeds "
                  f"{SLIP_THRESHOLD * 1e3:.0f} mm/s. Predicted / measured onset (s; — : "
                  f"none), sensing {comp.rows[0].sensing if comp.rows else ''}:", "",
                  "| path | formulation | controller | μ needed | "
                  + " | ".join(f"μ = {m:g}" for m in mus) + " |",
                  "|---|---|---|---|" + "---|" * len(mus)]
        for o in comp.onsets:
            cells = " | ".join(f"{_t(p)} / {_t(m)}" for p, m
                               in zip(o.predicted, o.measured, strict=True))
            lines.append(f"| {o.path} | {o.formulation} | {labels[o.controller]} | "
                         f"{o.needed_max:.3f} | {cells} |")
        pairs = [(p, m, mu, o.needed_max) for o in comp.onsets
                 for p, m, mu in zip(o.predicted, o.measured, mus, strict=True)]
        agree = sum((p is None) == (m is None) for p, m, _, _ in pairs)
        lags = [m - p for p, m, _, _ in pairs if p is not None and m is not None]
        missed = [(mu, need) for p, m, mu, need in pairs if p is not None and m is None]
        unseen = [(mu, need) for p, m, mu, need in pairs if p is None and m is not None]
        late = [(need / mu - 1, m - p) for p, m, mu, need in pairs
                if p is not None and m is not None and m - p > 2.0]
        lines += ["", f"Slip predicted and measured agree (both or neither) in {agree} of "
                  f"{len(pairs)} runs."]
        if lags:
            lines[-1] += (f" Where both slip, the engine's onset comes "
                          f"{float(np.median(lags)):.1f} s after the predicted one (median; "
                          "the slip speed takes a sample or two to build up to the "
                          "threshold)")
            lines[-1] += (f", except in {len(late)} runs where it comes "
                          f"{min(d for _, d in late):.0f}–{max(d for _, d in late):.0f} s "
                          "later: their largest need exceeds the floor's μ by at most "
                          f"{max(x for x, _ in late) * 100:.0f} %, the engine's wheels creep "
                          "under the threshold at the start and slip at a later turn."
                          if late else ".")
        if missed:
            lines[-1] += (f" Predicted but not measured in {len(missed)} runs, each one "
                          "whose largest need is within "
                          f"{max(abs(need / mu - 1) for mu, need in missed) * 100:.0f} % "
                          "of the floor's μ (the engine's wheels creep there without "
                          "reaching the threshold).")
        if unseen:
            lines[-1] += f" Measured but not predicted in {len(unseen)} runs."
    if comp.verdicts:
        lines += ["", *agreement.markdown(comp.verdicts, labels)]
    model_t = [r.model.seconds for r in comp.rows]
    engine_t = [c.seconds for r in comp.rows for c in r.engine]
    lines += ["", "## Run time", "",
              f"A run on the model plant takes {np.mean(model_t):.2f} s on average "
              f"(longest {max(model_t):.2f} s), on MuJoCo {np.mean(engine_t):.2f} s "
              f"(longest {max(engine_t):.2f} s): {np.mean(engine_t) / np.mean(model_t):.1f} "
              f"× (h = {exp.controller.h:g} s, {pl.substeps} engine steps a sample).", ""]
    return "\n".join(lines)


def _runs_table(comp: Comparison) -> list[str]:
    """Every run: the model plant's RMS / max and outcome, then each case's on MuJoCo."""
    labels = {i.name: i.label for _, i in comp.setting.robot.code.runs()}
    head = "| sensing | path | formulation | controller | model plant |"
    rule = "|---|---|---|---|---|"
    for label, _, _ in comp.cases:
        head += f" MuJoCo {label} | slip, sat |"
        rule += "---|---|"
    lines = [head, rule]
    for r in comp.rows:
        m = r.model
        line = (f"| {r.sensing} | {r.path} | {r.formulation} | {labels[r.controller]} | "
                f"{_mm(m.rms)} / {_mm(m.max)} {_status(m)} |")
        for c in r.engine:
            line += f" {_mm(c.rms)} / {_mm(c.max)} {_status(c)} | {_slip(c)}, {c.saturated} |"
        lines.append(line)
    return lines


def _case_summary(comp: Comparison, i: int) -> str:
    """One case's counts (runs ok on each plant, runs that slipped) and RMS differences."""
    label = comp.cases[i][0]
    diffs = [r.engine[i].rms - r.model.rms for r in comp.rows
             if r.model.status == "ok" and not math.isnan(r.engine[i].rms)]
    ok = sum(r.engine[i].status == "ok" for r in comp.rows)
    model_ok = sum(r.model.status == "ok" for r in comp.rows)
    slipping = sum(r.engine[i].slip_onset is not None for r in comp.rows)
    text = (f"**{label}**: {ok} of {len(comp.rows)} runs ok on MuJoCo ({model_ok} on "
            f"the model plant); a wheel slipped in {slipping}.")
    if diffs:
        text += (f" RMS MuJoCo − model over the runs ok on the model: "
                 f"{min(diffs) * 1e3:+.2f} … {max(diffs) * 1e3:+.2f} mm.")
    return text


def report_section(comp: Comparison) -> list[str]:
    """The reproduction report's section (``wmr reproduce --compare-plant mujoco``): the
    same runs on the model plant and on MuJoCo at the experiment's floor, side by side,
    with where and why they differ."""
    pl = comp.setting.experiment.plant
    model_t = [r.model.seconds for r in comp.rows]
    engine_t = [c.seconds for r in comp.rows for c in r.engine]
    return [
        "## The same runs on an independent engine (MuJoCo)", "",
        "Every run above, repeated by the same closed loop (generated C controller, "
        "encoders, odometry, payload schedule) on MuJoCo, on the MJCF `wmr mjcf` writes "
        "from the robot's description (its planar inertias are the derived model's, tested "
        "to 1e-6; point-contact wheels, friction coefficient "
        f"{pl.friction:g}, contact time constant {pl.contact_timeconst:g} s). The model "
        "plant cannot slip; the engine's wheels roll only as far as friction lets them, "
        "its contacts are soft, its Coulomb bearing friction is exact and its body may "
        "pitch on its supports: the differences below are those. Errors in mm (RMS / max), "
        "outcome as above; slip: the driven wheels' largest rim speed less ground speed "
        f"(mm/s) and when it first exceeds {SLIP_THRESHOLD * 1e3:.0f} mm/s; sat: samples "
        "whose torque was clipped.", "",
        *(f"* {_case_summary(comp, i)}" for i in range(len(comp.cases))),
        f"* Run time: {np.mean(model_t) * 1e3:.0f} ms a run on the model plant, "
        f"{np.mean(engine_t) * 1e3:.0f} ms on MuJoCo "
        f"({np.mean(engine_t) / np.mean(model_t):.1f} ×).", "",
        *_runs_table(comp), "",
        "Lower floors (μ = 0.2, 0.1, and 0.1 with the traction-aware torque limit) and the "
        "slip monitor's predicted onset of slip against the engine's: docs/MUJOCO.md "
        "(`python -m runtime.commands.compare_plants`).", "",
    ]


def _lowest_floor(comp: Comparison) -> str:
    """How many runs the lowest floor without a traction limit leaves on the path, as
    measured (the others end the run diverged or off the path: not said to be for good)."""
    plain = [(mu, i) for i, (_, mu, traction) in enumerate(comp.cases) if traction == 0]
    if not plain or not comp.rows:
        return ""
    mu, i = min(plain)
    ok = sum(r.engine[i].status == "ok" for r in comp.rows)
    return (f" (μ = {mu:g}: {ok} of {len(comp.rows)} runs end on the path, the others "
            "end the run diverged or off it)")


def _traction_slips(comp: Comparison) -> str:
    """How many runs still slip under the traction limit, as measured."""
    limited = [i for i, (_, _, traction) in enumerate(comp.cases) if traction > 0]
    if not limited or not comp.rows:
        return ""
    i = limited[-1]
    onsets = [t for r in comp.rows if (t := r.engine[i].slip_onset) is not None]
    if not onsets:
        return f" (measured: no run slips under it, {comp.cases[i][0]})"
    return (f"; it does not keep every wheel inside its friction circle: {len(onsets)} of "
            f"{len(comp.rows)} runs still slip under it ({comp.cases[i][0]}; first slip "
            f"{min(onsets):g} … {max(onsets):g} s), the limit is μ N r of a wheel at rest, "
            "and turning, load transfer and the controllers' sample-to-sample torque "
            "reversals take more of μ N than that")


def _summary(comp: Comparison) -> list[str]:
    """Where and why the plants differ, with the numbers of this run."""
    out = ["## Where they differ, and why", ""]
    out += [f"* {_case_summary(comp, i)}" for i in range(len(comp.cases))]
    out += [
        "",
        "With grip (μ = 1) the engine confirms the model: the rolling constraints hold to "
        "within the contacts' creep, and what is left is physics the derivation assumed "
        "away: soft contacts (the tyres sink, the rolling radius shrinks by the sinkage, "
        "and the odometry, which uses the nominal radius, drifts; measured on Drishti: with "
        "MuJoCo's default time constant 0.02 s it sinks 0.2 mm and its tracking error grows "
        "by about 6 mm RMS), creep under traction, exact rather than smoothed Coulomb "
        "friction, and a body that pitches on its supports under acceleration. Once a wheel "
        "slips the model plant has nothing to say: it cannot slip. Where the start-up "
        "torque exceeds μ N r (the low floors' counts above) the wheel spins, the encoders "
        "report motion the robot does not make, and a controller that answers with more "
        "torque spins it further into the torque limit: grip seldom comes back"
        + _lowest_floor(comp) + ". A torque limit under μ N r (`traction_mu`) keeps "
        "the start-up from spinning the wheels (counts above)" + _traction_slips(comp)
        + "; the limit is also all the "
        "authority the controllers have, so runs converge slowly and some may stay more "
        "than a tenth of the path's size off it (the outcome column): on such a floor the "
        "path must be slower, not the controller stronger.",
    ]
    limited = [i for i, (_, _, traction) in enumerate(comp.cases) if traction > 0]
    if limited:
        i = limited[-1]
        off = {f: [r for r in comp.rows if r.formulation == f and r.engine[i].status != "ok"]
               for f in dict.fromkeys(r.formulation for r in comp.rows)}
        counts = ", ".join(f"{len(v)} of {sum(r.formulation == f for r in comp.rows)} in the "
                           f"{f} formulation" for f, v in off.items())
        out += [
            "",
            f"Off path under the traction limit ({comp.cases[i][0]}): {counts}. That is "
            "not slip: the same limit on the model plant, which cannot slip, leaves a run as "
            "far off (measured on Drishti, TDC on the circle, sample-instant: minimal "
            "formulation 227 mm RMS and 228 mm off at the end on the model plant, 225 and "
            "226 mm on MuJoCo; paper formulation 9 mm off at the end on both). The paper's "
            "controllers in the minimal formulation feed back the wheel angles only (the PI "
            "has a tracker that corrects the pose): while the start-up saturates, the "
            "wheels lag the reference and the robot rolls a different path; the heading is "
            "a function of the wheel angles and comes back with them, the position is not "
            "(the constraints are nonholonomic), so once the wheel angles have caught up an "
            "offset remains that no error the controller sees contains. The paper "
            "formulation feeds back x, y, θ and removes it.",
        ]
    return out
