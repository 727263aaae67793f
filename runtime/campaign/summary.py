"""What the user reads of a campaign: per controller, the outcomes, the failure rate,
percentiles and the worst case, and how often the predicted stability boundary agrees with
the simulated outcome (``summary.md``, ``summary.json``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from modeling import audit
from runtime.campaign.prediction import Prediction
from runtime.campaign.spec import Campaign
from runtime.sim.outcome import OFF_PATH_FRACTION

PERCENTILES = (50, 90, 99)


@dataclass(frozen=True)
class Agreement:
    runs: int  # runs with a simulated outcome and a prediction
    agree: int
    stable_predicted_unstable_simulated: int
    unstable_predicted_stable_simulated: int

    @property
    def fraction(self) -> float:
        return self.agree / self.runs if self.runs else math.nan


def map_values(table: pa.Table, campaign: Campaign, name: str) -> list[Any]:
    """Each run's value of a parameter: drawn (``p.NAME``) or the base experiment's."""
    col = f"p.{name}"
    if col in table.column_names:
        return table.column(col).to_pylist()
    section, _, key = name.partition(".")
    return [getattr(getattr(campaign.experiment, section), key)] * table.num_rows


def predicted(table: pa.Table, campaign: Campaign, pred: Prediction) -> list[bool | None]:
    """Per run: the analysis' verdict at its (ε, y, sensing), None where there is none."""
    if pred.unavailable:
        return [None] * table.num_rows
    eps = map_values(table, campaign, campaign.map_x)
    ys = map_values(table, campaign, campaign.map_y)
    vel = map_values(table, campaign, "sensing.velocity")
    ctrl = table.column("controller").to_pylist()
    out: list[bool | None] = []
    for e, y, v, c in zip(eps, ys, vel, ctrl, strict=True):
        b = pred.boundaries.get((c, v))
        out.append(None if b is None or e is None or y is None
                   else b.predicts_stable(float(e), float(y)))
    return out


def agreement(status: list[str], stable: list[bool], verdict: list[bool | None]) -> Agreement:
    n = agree = spu = ups = 0
    for s, sim, p in zip(status, stable, verdict, strict=True):
        if p is None or s not in ("ok", "diverged"):
            continue
        n += 1
        agree += sim == p
        spu += p and not sim
        ups += (not p) and sim
    return Agreement(n, agree, spu, ups)


def _stats(values: list[float]) -> dict[str, float]:
    v = np.array([x for x in values if x is not None and math.isfinite(x)])
    if not len(v):
        return {f"p{p}": math.nan for p in PERCENTILES} | {"max": math.nan}
    return {f"p{p}": float(np.percentile(v, p)) for p in PERCENTILES} | {"max": float(v.max())}


def summarise(table: pa.Table, campaign: Campaign, pred: Prediction) -> dict[str, Any]:
    """The summary as a JSON-able dict."""
    d = table.to_pydict()
    verdict = predicted(table, campaign, pred)
    params = [c for c in table.column_names if c.startswith("p.")]
    per: dict[str, Any] = {}
    for ctrl in campaign.controllers:
        rows = [i for i, c in enumerate(d["controller"]) if c == ctrl]
        status = [d["status"][i] for i in rows]
        counts = {s: status.count(s) for s in ("ok", "diverged", "init_refused", "error")}
        ok = [i for i in rows if d["status"][i] == "ok"]
        ran = [i for i in rows if d["status"][i] in ("ok", "diverged")
               and math.isfinite(d["max_error"][i])]
        worst = max(ran, key=lambda i: d["max_error"][i], default=None)
        agr = agreement(status, [d["stable"][i] for i in rows], [verdict[i] for i in rows])
        errors = sorted({d["error"][i] for i in rows if d["status"][i] == "error"})
        per[ctrl] = {
            "runs": len(rows),
            **counts,
            "failure_rate": (len(rows) - counts["ok"]) / len(rows) if rows else math.nan,
            "unstable_rate": (sum(not d["stable"][i] for i in rows) / len(rows)
                              if rows else math.nan),
            "rms_error_m": _stats([d["rms_error"][i] for i in ok]),
            "max_error_m": _stats([d["max_error"][i] for i in ok]),
            "max_torque_Nm": _stats([d["max_torque"][i] for i in ok]),
            "worst": None if worst is None else {
                "index": d["index"][worst], "status": d["status"][worst],
                "max_error_m": d["max_error"][worst],
                "parameters": {p.removeprefix("p."): d[p][worst] for p in params},
            },
            "agreement": None if pred.unavailable else {
                "runs": agr.runs, "agree": agr.agree, "fraction": agr.fraction,
                "predicted_stable_simulated_unstable": agr.stable_predicted_unstable_simulated,
                "predicted_unstable_simulated_stable": agr.unstable_predicted_stable_simulated,
            },
            "errors": errors[:5],
        }  # fmt: skip
    total = agreement(d["status"], d["stable"], verdict)
    return {
        "runs": table.num_rows,
        "controllers": per,
        "agreement": None if pred.unavailable else {
            "runs": total.runs, "agree": total.agree, "fraction": total.fraction},
        "grip": pred.grip,
        "prediction": pred.unavailable or (
            f"ε_min(y) from runtime.stability.analysis over {campaign.map_y}, nominal robot, no "
            "payload or friction, other parameters at their base values"),
    }  # fmt: skip


def _mm(x: float) -> str:
    return "–" if not math.isfinite(x) else f"{1000 * x:.2f}"


def physical_lines(campaign: Campaign) -> list[str]:
    """What the physical draws became on this campaign's plant (none: no line)."""
    drawn = [name.removeprefix("physical.") for name, _ in campaign.vary
             if name.startswith("physical.")]
    if not drawn:
        return []
    plant = campaign.experiment.plant.model
    how = ("as the bodies of the exported MJCF (masses, yaw inertias, centres of mass; a "
           "payload merged into the root body)" if plant == "mujoco" else
           "through the generated map plant_params_from_physical to the model's base "
           "parameters")
    declared = campaign.experiment.physical
    box = f" ROC's bounds over [physical_uncertainty]: {declared.describe()}." if declared else ""
    return [f"Physical draws ({', '.join(drawn)}) on the {plant} plant, {how}; run i draws "
            f"the same robot on either plant (seed, i).{box}"]


def markdown(summary: dict[str, Any], campaign: Campaign, where: str, plots: list[str],
             warnings: Sequence[str] = ()) -> str:
    """``summary.md``; ``warnings``: the physics audit's on the campaign's robot file
    (``modeling.audit``), written after the opening lines."""
    lines = [
        f"# Campaign summary: {summary['runs']} runs",
        "",
        f"Spec: {campaign.source}; robot: {campaign.robot or 'Drishti (the paper)'}; "
        f"{campaign.path} of {campaign.duration:g} s, {campaign.formulation} formulation, "
        f"seed {campaign.seed}; run on {where}.",
        f"Drawn: {', '.join(name for name, _ in campaign.vary) or 'nothing'}.",
        *physical_lines(campaign),
        "",
        *audit.section(warnings),
        "Outcome: ok; diverged (a step failed, the plant became non-finite, the position error "
        f"exceeded {campaign.diverged_error:g} m, or the final or RMS error exceeded "
        f"{100 * OFF_PATH_FRACTION:g} % of the path's size); init refused (the C init's "
        "status); error. Simulated "
        f"unstable: not ok, or chatter RMS(Δτ)/RMS(τ) ≥ {campaign.chatter_limit:g} in the "
        "second half (a sampled-data limit cycle of the switching term, or encoder "
        "quantisation amplified into the torque as strongly, which the prediction leaves out).",
        "",
        "| controller | runs | ok | diverged | init refused | error | failure rate "
        "| unstable | RMS error p50 / p90 / p99 / max [mm] | worst max error [mm] (run) "
        "| max torque p99 [N m] |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|---|---:|",
    ]
    for ctrl, s in summary["controllers"].items():
        r = s["rms_error_m"]
        worst = s["worst"]
        w = "–" if worst is None else f"{_mm(worst['max_error_m'])} (#{worst['index']})"
        lines.append(
            f"| {ctrl.upper()} | {s['runs']} | {s['ok']} | {s['diverged']} | "
            f"{s['init_refused']} | {s['error']} | {100 * s['failure_rate']:.1f} % | "
            f"{100 * s['unstable_rate']:.1f} % | {_mm(r['p50'])} / {_mm(r['p90'])} / "
            f"{_mm(r['p99'])} / {_mm(r['max'])} | {w} | {s['max_torque_Nm']['p99']:.3g} |")
    lines += ["", "## Predicted stability boundary against the simulated outcomes", ""]
    if summary["agreement"] is None:
        lines.append(f"Predicted boundary not available: {summary['prediction']}.")
    else:
        a = summary["agreement"]
        lines.append(
            f"Agreement: {a['agree']} of {a['runs']} runs ({100 * a['fraction']:.1f} %) are on "
            f"the side of the predicted boundary ε_min({campaign.map_y}) their simulated "
            f"outcome says. Prediction: {summary['prediction']}; the simulated runs have every "
            "drawn parameter, the payload and friction.")
        lines.append("")
        lines.append("| controller | runs compared | agree | predicted stable, simulated "
                     "unstable | predicted unstable, simulated stable |")
        lines.append("|---|---:|---:|---:|---:|")
        for ctrl, s in summary["controllers"].items():
            g = s["agreement"]
            frac = "–" if not g["runs"] else f"{100 * g['fraction']:.1f} %"
            lines.append(f"| {ctrl.upper()} | {g['runs']} | {frac} | "
                         f"{g['predicted_stable_simulated_unstable']} | "
                         f"{g['predicted_unstable_simulated_stable']} |")
    for p in plots:
        lines += ["", f"![stability map]({p})"]
    if summary.get("grip"):
        lines += ["", "## Grip at the base setting", "",
                  "`wmr stability`'s saturation and grip verdict "
                  "(runtime.stability.saturation, simulated) for each controller at the "
                  "campaign's base experiment and nominal robot; the drawn runs vary around "
                  "it.", ""]
        lines += [f"- {c.upper()}: {g['line']}" for c, g in summary["grip"].items()]
    errs = {c: s["errors"] for c, s in summary["controllers"].items() if s["errors"]}
    if errs:
        lines += ["", "## Errors (first distinct messages)", ""]
        for c, msgs in errs.items():
            lines += [f"- {c.upper()}: {m}" for m in msgs]
    return "\n".join(lines) + "\n"
