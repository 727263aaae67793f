"""The metrics tables of the paper's robot's reproduction
(:mod:`runtime.reproduction.driver`), one row per run: ``metrics.md``, one Markdown table
per sensing model, and ``metrics.csv``, every run in one file. The CSV keeps the columns it
always had, in the same order, with ``sensing`` and then ``friction_needed`` appended, so
readers of the older file still work. Also the formatting the report shares (:func:`fmt_mm`,
:func:`fmt_mu`, :func:`sensing_label`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable
from pathlib import Path

from runtime.reproduction.driver import Metrics, Reproduction


def fmt_mm(x: float) -> str:
    return f"{x * 1000:.2f}"


def fmt_mu(x: float, floor: float | None = None) -> str:
    """A friction coefficient the slip monitor found a run needs (— : not monitored); above
    the floor's μ (``floor``) the run is predicted to slip, and says so."""
    if math.isnan(x):
        return "—"
    if floor is not None and x > floor:
        return f"**{x:.3f} > μ: slips**"
    return f"{x:.3f}"


def sensing_label(rep: Reproduction, sensing: str, estimator: str | None = None) -> str:
    """What a table or claim holds for: sensing, estimator, ε, h and the gains."""
    c = rep.experiment.controller
    return (
        f"sensing `{sensing}`, estimator `{estimator or rep.estimator}`; ε = {c.eps:g}, "
        f"h = {c.h:g} s, K1 = K2 = {c.k1:g} I, Q = I, n = {c.n}, a = {c.a:g}"
    )


def metrics_table(rep: Reproduction, rows: Iterable[Metrics],
                  friction: float | None = None) -> list[str]:
    """The metrics of ``rows``; ``friction``: the floor's μ the μ needed is read against."""
    lines = [
        "| path | form | controller | RMS error [mm] | max error [mm] | RMS [% of scale] "
        "| RMS τ [N m] | TV(τ) [N m] | median k̂ | max k̂ | saturated steps | RMS ‖u₁₋₃‖ "
        "| μ needed |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for m in rows:
        lines.append(
            f"| {m.path} | {m.formulation} | {rep.labels[m.controller]} | {fmt_mm(m.rms_error)} "
            f"| {fmt_mm(m.max_error)} | {m.rms_percent:.2f} | {m.rms_torque:.2f} "
            f"| {m.torque_variation:.1f} | {m.median_gain:.3f} | {m.max_gain:.3f} "
            f"| {m.saturated_steps} | {m.discarded_u:.2f} "
            f"| {fmt_mu(m.friction_needed, friction)} |"
        )
    return lines


def metrics_markdown(rep: Reproduction) -> str:
    """``metrics.md``: one table per sensing model (headed ``### sensing …``)."""
    parts: list[str] = []
    for sensing in rep.sensings:
        parts += [f"### {sensing_label(rep, sensing)}", "",
                  *metrics_table(rep, rep.rows(sensing), rep.experiment.plant.friction), ""]
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
    "sensing",  # appended: the older columns keep their positions
    "friction_needed",  # the slip monitor's max |F|/N over the run (empty: not monitored)
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
                    "" if math.isnan(m.friction_needed) else f"{m.friction_needed:.4g}",
                ]
            )
