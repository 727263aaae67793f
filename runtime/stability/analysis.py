"""Sampled-data stability of the generated controllers on a given robot, sampling and sensing.

:mod:`runtime.stability.sampled_loop` builds the sampled closed loop's one-sample map and its
pencil J(g) = J₀ + g J₁ in the boundary-layer gain g (the model, the frame and the
conditions a verdict holds for are stated there). This module turns it into verdicts: the
largest stable g per controller and formulation, the spectral radius at the experiment's
setting (k̂ measured in closed loop, :mod:`runtime.sim.loop`, for the adaptive and
windowed gains of TDROC and ASMC, ρ/ε for ROC), TDROC's predicted stable range
ε > k̂ / g_max, and the tables ``wmr stability`` prints (:mod:`runtime.commands.stability`).
The controllers, their labels and which
gain each has come from the robot's generated code (``CONTROLLERS``).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from runtime.bindings.generated import RobotCode
from runtime.bindings.uncertainty import tde_alpha
from runtime.experiment.settings import ACCEL_CODES, Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.sim.memo import Memo, key_of
from runtime.stability.sampled_loop import (
    EPS_SOURCE,
    FORMULATIONS,
    ClosedLoop,
    LoopSetting,
    NotLinearisable,
    Pencil,
    delay_radius,
    max_delay,
    operating_rates,
    pencil,
    refusal,
    roc_gain,
    setting,
)

__all__ = ["FORMULATIONS", "Analysis", "ClosedLoop", "LoopSetting", "Pencil", "analyse",
           "analyse_all", "pencil", "setting"]


@dataclass(frozen=True)
class Analysis:
    """One row of the report (the JSON keys controller … stable are fixed; the same keys
    for every robot)."""

    controller: str
    formulation: str
    sensing: str
    max_stable_gain: float  # largest stable boundary-layer gain g = k/ε
    spectral_radius: float  # at the experiment's setting (g_setting)
    stable: bool
    estimator: str
    h: float
    plant: str
    gain_at_setting: float  # g the setting gives: 0 (TDC), k̂/ε measured, ρ/ε (ROC)
    gain_source: str
    radius_without_switching: float  # g = 0
    eps: float
    eps_min: float | None  # TDROC: ε > k̂ / g_max predicted stable (k̂ measured)
    measured_khat: float | None
    reason: str = ""  # why the verdict is "not stable" (empty when stable)
    operating_point: str = "circle"  # the steady motion that decided the verdict
    delay: float = 0.0  # s: the experiment's delay from a sample to its torque
    jitter: float = 0.0  # s: the bound on each sample's deviation from it
    max_delay: float | None = None  # s: largest constant delay stable at the setting's gain
    saturation: str = "not checked"  # the torque, grip and wind-up verdict (saturation.py)
    saturation_reason: str = ""
    # The row's one word: unstable (the linear verdict), else slips / winds up / saturates
    # (the saturation verdict), else stable; "stable" is never the word of a loop predicted
    # to lose grip.
    verdict: str = ""


def measured_gain(
    code: RobotCode, controller: str, formulation: str, robot: dict[str, float],
    exp: Experiment
) -> float:
    """Median switching gain over the experiment's closed-loop circle (the analysis'
    operating point) at the experiment's setting. The configuration checks are skipped: the
    loop's stability is what is analysed here, and the TDE condition over the uncertainty
    box is reported apart (:func:`tde_notes`). The same arguments in one process: the same
    gain, simulated once (`wmr freeze` asks for it on every run of a configuration)."""
    key = key_of(code, robot, controller, formulation, replace(exp, source=""))
    return _gain_memo.get(key, lambda: _measured_gain(code, controller, formulation, robot, exp))


# Gains already measured in this process, keyed as the references' memo keys its circle
# (the experiment's ``source``, its file's name as typed, is read by no simulation).
_gain_memo: Memo[float] = Memo(32)


def _measured_gain(code: RobotCode, controller: str, formulation: str,
                   robot: dict[str, float], exp: Experiment) -> float:
    ref = paths.circle(code, robot, exp)
    r = loop.run(code, controller, formulation, ref, robot, exp,
                 plant=plant_for(code, exp, robot))
    if r.init_status != 0:
        raise ValueError(r.stop_reason)
    late = r.t >= min(5.0, 0.5 * r.t[-1])
    return float(np.median(r.gain[late]))


def setting_gain(
    code: RobotCode,
    controller: str,
    formulation: str,
    robot: dict[str, float],
    exp: Experiment,
    measure: bool,
) -> tuple[float, str, float | None]:
    """(g at the experiment's setting, where it comes from, the measured k̂ or None)."""
    eps = exp.controller.eps
    info = code.controller(controller)
    if not info.switching:
        return 0.0, f"{info.label} has no switching term", None
    if info.bounds:
        try:
            return (roc_gain(code, formulation, robot, exp),
                    f"{info.label}'s ρ at zero error / ε", None)
        except ValueError as exc:  # ROC's bounds do not exist over the uncertainty box
            return math.nan, f"no {info.label} gain: {exc}", None
    if not measure:
        return 0.0, "not measured", None
    try:
        khat = measured_gain(code, controller, formulation, robot, exp)
    except ValueError as exc:  # the toolchain refuses to configure it: nothing to measure
        return 0.0, f"not measured: the configuration is refused ({exc})", None
    return khat / eps, "median k̂ of the closed-loop circle / ε", khat


def analyse(
    code: RobotCode,
    controller: str,
    formulation: str,
    robot: dict[str, float],
    exp: Experiment,
    plant: str = "nominal",
    measure: bool = True,
    path: str = "circle",
    delays: bool = False,
    saturation: bool = False,
) -> Analysis:
    """Stability of one controller and formulation at the experiment's setting, about each
    steady motion of ``path`` (the worst decides); ``delays``: also the largest tolerated
    delay; ``saturation``: also the torque and wind-up verdict
    (:mod:`runtime.stability.saturation`)."""
    points = [(label, setting(code, controller, formulation, robot, exp, plant, rates))
              for label, rates in operating_rates(code, robot, exp, path)]
    pens = [(label, s, pencil(s)) for label, s in points]
    g_max = min(p.max_stable_gain() for _, _, p in pens)
    r0 = max(p.radius(0.0) for _, _, p in pens)
    # Nothing to measure where the loop diverges before any switching gain (and the
    # toolchain refuses to build that configuration).
    g, source, khat = setting_gain(code, controller, formulation, robot, exp,
                                   measure and r0 < 1.0)
    jitter = exp.controller.jitter_seconds()
    if math.isfinite(g):
        radii = [(delay_radius(s, g, jitter), label) for label, s, _ in pens]
        radius, worst = max(radii)
        radius0 = max(delay_radius(s, 0.0, jitter) for _, s, _ in pens)
    else:  # nan: no configuration exists
        radius, worst, radius0 = math.inf, pens[0][0], max(p.radius(0.0) for _, _, p in pens)
    eps_min = khat / g_max if khat is not None and g_max > 0 else None
    tolerated = (min(max_delay(s, g) for _, s, _ in pens) if delays and math.isfinite(g)
                 else None)
    verdict = ("", "")
    if saturation:
        from runtime.stability.saturation import saturation_verdict

        sat = saturation_verdict(code, controller, formulation, robot, exp, "payload",
                                 simulate=measure)
        verdict = (sat.verdict, sat.reason)
    return Analysis(
        controller=controller,
        formulation=formulation,
        sensing=exp.sensing.velocity,
        max_stable_gain=g_max,
        spectral_radius=radius,
        stable=radius < 1.0,
        estimator=points[0][1].estimator,
        h=exp.controller.h,
        plant=plant,
        gain_at_setting=g,
        gain_source=source,
        radius_without_switching=radius0,
        eps=exp.controller.eps,
        eps_min=eps_min,
        measured_khat=khat,
        reason=reason(radius, radius0, g, g_max, source, exp),
        operating_point=worst,
        delay=exp.controller.delay_seconds(),
        jitter=jitter,
        max_delay=tolerated,
        saturation=verdict[0] or "not checked",
        saturation_reason=verdict[1],
        verdict=overall(radius < 1.0, verdict[0]),
    )


def overall(stable: bool, saturation: str) -> str:
    """The row's one word (see :attr:`Analysis.verdict`)."""
    if not stable:
        return "unstable"
    for word in ("slips", "winds up", "saturates"):
        if saturation.startswith(word):
            return word
    return "stable"


def reason(radius: float, radius0: float, g: float, g_max: float, source: str,
           exp: Experiment) -> str:
    """Why a row is not stable, in one line (empty if it is)."""
    if radius < 1.0:
        return ""
    if math.isnan(g):
        return f"refused: {source.removeprefix('no ROC gain: ')}"
    c = exp.controller
    late = (f", delay {c.delay_seconds():g} s ± {c.jitter_seconds():g} s"
            if c.delay_seconds() or c.jitter_seconds() else "")
    where = f"h = {c.h:g} s, {exp.sensing.velocity} rates{late}"
    if radius0 >= 1.0:
        return (f"unstable before any switching gain (spectral radius {radius0:.3f} per "
                f"sample; {where})")
    return (f"switching gain k/ε = {g:.3g} beyond the largest stable {g_max:.3g} "
            f"(spectral radius {radius:.3f}; {where}): raise ε")


@dataclass(frozen=True)
class ConfigurationVerdict:
    """The sampled-data verdict for one filled controller configuration (``wmr freeze``):
    the pencil of its robot, sampling, sensing and estimator at its own gains."""

    controller: str
    formulation: str
    stable: bool
    spectral_radius: float
    gain: float  # boundary-layer gain g = k/ε at the configuration
    gain_source: str
    h: float
    sensing: str
    estimator: str

    def describe(self) -> str:
        return (f"{self.controller}/{self.formulation} "
                f"{'stable' if self.stable else 'UNSTABLE'}: spectral radius "
                f"{self.spectral_radius:.3f} at k/ε = {self.gain:.3g} ({self.gain_source}); "
                f"h = {self.h:g} s, {self.sensing} rates, {self.estimator} estimator")


ESTIMATOR_NAMES = {code: name for name, code in ACCEL_CODES.items()}


def configured_experiment(code: RobotCode, controller: str, exp: Experiment,
                          config: Any) -> Experiment:
    """``exp`` with what a filled configuration holds: every field whose declared source
    (robot.py's ``CONTROLLERS``) is ``experiment.controller.<name>`` (h, quantisation,
    τ_max, the switching fields, the PI's gains; K1, K2 when uniform over the
    coordinates): the setting the configuration runs at (``wmr freeze``'s verdicts,
    sampled-data and grip, are at it)."""
    changes: dict[str, Any] = {}
    for f in code.controller(controller).fields:
        name = f.source.removeprefix("experiment.controller.")
        if name == f.source or not hasattr(exp.controller, name):
            continue
        current = getattr(exp.controller, name)
        if f.kind == "vector":
            values = {float(x) for x in list(getattr(config, f.name))[:code.nq]}
            if len(values) == 1 and isinstance(current, float):
                changes[name] = values.pop()
        else:
            changes[name] = type(current)(getattr(config, f.name))
    return replace(exp, controller=replace(exp.controller, **changes))


def configuration_verdict(
    code: RobotCode, controller: str, formulation: str, nominal: dict[str, float],
    exp: Experiment, config: Any,
) -> ConfigurationVerdict:
    """Stability of ``config`` (a filled ``<prefix>_<controller>_config_t``) on the robot
    whose parameters are ``nominal`` (plant = model, as ``wmr stability`` with the nominal
    plant), with the experiment's sensing: the generated law linearised with this
    configuration's fields, at the switching gain it gives, by its declared kind (the
    registry's ``Gain``): none, k̂ held / ε (a window gain held), φ/(1 − α)/ε (bounds, at
    zero error), else k̂ measured on the closed-loop circle / ε. Every field is read by
    its declared source (robot.py's ``CONTROLLERS``), never by its name."""
    info = code.controller(controller)
    values: dict[str, Any] = {}
    by_source: dict[str, Any] = {}
    for f in info.fields:
        v = getattr(config, f.name)
        v = tuple(float(x) for x in list(v)[:code.nq]) if f.kind == "vector" else v
        values[f.name] = v
        by_source[f.source] = v
    h = float(by_source["experiment.controller.h"])
    exp = replace(exp, controller=replace(exp.controller, h=h))
    loop_setting = replace(setting(code, controller, formulation, nominal, exp),
                           config=tuple(values.items()))
    if "accel_estimator" in by_source:  # the TDE's estimator, for the report
        loop_setting = replace(loop_setting,
                               estimator=ESTIMATOR_NAMES[int(by_source["accel_estimator"])])
    pen = pencil(loop_setting)
    eps = float(by_source.get(EPS_SOURCE, 1.0))
    if not info.switching:
        g, source = 0.0, f"{info.label} has no switching term"
    elif info.bounds:
        alpha, phi = (float(by_source[k]) for k in ("roc_bounds.alpha", "roc_bounds.phi"))
        g = phi / (1.0 - alpha) / eps
        source = f"{info.label}'s ρ at zero error / ε"
    elif info.window and int(by_source.get("hold_gain", 0)):
        g, source = float(by_source["held_gain"]) / eps, "k̂ held / ε"
    elif pen.radius(0.0) >= 1.0:
        g, source = 0.0, "not measured: unstable without switching"
    else:
        g = measured_gain(code, controller, formulation, nominal, exp) / eps
        source = "median k̂ of the closed-loop circle / ε (measured with the experiment's gains)"
    radius = delay_radius(loop_setting, g, exp.controller.jitter_seconds())
    return ConfigurationVerdict(
        controller=controller, formulation=formulation, stable=radius < 1.0,
        spectral_radius=radius, gain=g, gain_source=source, h=h,
        sensing=exp.sensing.velocity, estimator=loop_setting.estimator)


def analyse_all(
    code: RobotCode, robot: dict[str, float], exp: Experiment, plant: str = "nominal",
    measure: bool = True, path: str = "circle", delays: bool = False,
    saturation: bool = False, refused: list[str] | None = None,
    only: Collection[tuple[str, str]] | None = None,
) -> list[Analysis]:
    """Every controller of the robot's code in every formulation it is generated in (or
    the (controller, formulation) pairs ``only`` names), each linearised from its own
    generated law; one the analysis cannot take is left out, its reason appended to
    ``refused`` (if given; :func:`not_analysed` for the command)."""
    rows = []
    for c in code.controller_infos:
        if refusal(c):
            continue
        for f in c.formulations:
            if f not in FORMULATIONS or (only is not None and (c.name, f) not in only):
                continue
            try:
                rows.append(analyse(code, c.name, f, robot, exp, plant, measure, path, delays,
                                    saturation))
            except NotLinearisable as exc:
                if refused is not None:
                    refused.append(f"* {c.label} {f}: no sampled-data verdict: {exc}")
    return rows


def not_analysed(code: RobotCode) -> list[str]:
    """A note for each controller the analysis refuses from its declarations alone."""
    return [f"* {c.label} ({c.title}): no sampled-data verdict: {refusal(c)}"
            for c in code.controller_infos if refusal(c)]


def tde_notes(code: RobotCode, robot: dict[str, float], exp: Experiment) -> list[str]:
    """The TDE condition ‖M⁻¹ M̂ − I‖ < 1 of (17) over the experiment's uncertainty box, per
    formulation, where it fails (TDC and TDROC assume it; the toolchain refuses to configure
    them there, and a robot at the box's failing corner may diverge)."""
    box = exp.controller.uncertainty
    notes = []
    for form in code.formulations:
        try:
            alpha = tde_alpha(code, robot, box, formulation=form)[0]
        except ValueError as exc:  # the box holds robots with no positive-definite M
            notes.append(f"* TDE condition, {form} formulation: {exc}")
            continue
        if not alpha < 1.0:
            notes.append(
                f"* TDE condition, {form} formulation: ‖M⁻¹M̂ − I‖ reaches {alpha:.3g} ≥ 1 over "
                f"the ±{box:.0%} box, so TDC and TDROC are refused there; the rows above are "
                "the nominal robot's"
            )
    return notes


def _json_number(x: float | None) -> float | str | None:
    if x is None or math.isfinite(x):
        return x
    return "nan" if math.isnan(x) else "inf"


def as_json(rows: Sequence[Analysis], robot_name: str) -> dict[str, Any]:
    return {
        "robot": robot_name,
        "controllers": [
            {k: _json_number(v) if isinstance(v, float) else v for k, v in asdict(r).items()}
            for r in rows
        ],
    }


def _delay_text(x: float | None) -> str:
    if x is None:
        return ""
    return "≥ 2 h" if math.isinf(x) else f"{x * 1e3:.3g} ms"


def _stable_text(r: Analysis) -> str:
    """The stable column: yes, **no**, or, where the loop is linearly stable but predicted
    to lose grip, **no: slips** (never "yes" there)."""
    if not r.stable:
        return "**no**"
    return "**no: slips**" if r.verdict == "slips" else "yes"


def table(rows: Sequence[Analysis], code: RobotCode) -> str:
    """The Markdown table of :func:`analyse_all`'s rows (labels from the robot's code), the
    reason of every row not stable and every saturation verdict below it."""
    label = {c.name: c.label for c in code.controller_infos}
    lines = [
        "| controller | form | sensing | estimator | max stable k/ε | g at setting "
        "| spectral radius | stable | ε > (predicted) | max delay | saturation |",
        "|---|---|---|---|---:|---:|---:|---|---:|---:|---|",
    ]
    for r in rows:
        eps_min = "" if r.eps_min is None else f"{r.eps_min:.3g}"
        lines.append(
            f"| {label[r.controller]} | {r.formulation} | {r.sensing} | {r.estimator} "
            f"| {r.max_stable_gain:.4g} | {r.gain_at_setting:.4g} | {r.spectral_radius:.4f} "
            f"| {_stable_text(r)} | {eps_min} | {_delay_text(r.max_delay)} "
            f"| {r.saturation} |"
        )
    notes = [f"* {label[r.controller]} {r.formulation}: {r.gain_source}" for r in rows
             if r.gain_source.startswith(("not measured:", "no ROC gain"))]
    notes += [f"* {label[r.controller]} {r.formulation} not stable: {r.reason}" for r in rows
              if r.reason]
    notes += [f"* {label[r.controller]} {r.formulation} {r.saturation}: {r.saturation_reason}"
              for r in rows if r.saturation_reason]
    return "\n".join(lines + (["", *notes] if notes else [])) + "\n"
