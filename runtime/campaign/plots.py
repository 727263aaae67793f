"""Stability maps: the simulated outcome of every run over (ε, y), one panel per controller,
with the boundary ε_min(y) the sampled-data analysis predicts drawn over them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from runtime.campaign.prediction import Prediction
from runtime.campaign.spec import Campaign
from runtime.campaign.summary import map_values

STYLES = ("-", "--", ":", "-.")


def stability_map(table: pa.Table, campaign: Campaign, pred: Prediction,
                  summary: dict[str, object], path: Path) -> Path:
    """Write the map to ``path`` (PNG)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    ctrls = campaign.controllers
    fig = Figure(figsize=(5.2 * len(ctrls), 4.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, len(ctrls), squeeze=False)[0])
    eps = np.array(map_values(table, campaign, campaign.map_x), dtype=float)
    ys = np.array(map_values(table, campaign, campaign.map_y), dtype=float)
    ctrl = np.array(table.column("controller").to_pylist())
    status = np.array(table.column("status").to_pylist())
    stable = np.array(table.column("stable").to_pylist(), dtype=bool)
    per = summary["controllers"]
    assert isinstance(per, dict)
    for ax, c in zip(axes, ctrls, strict=True):
        sel = ctrl == c
        ran = sel & np.isin(status, ("ok", "diverged"))
        other = sel & ~np.isin(status, ("ok", "diverged"))
        ax.scatter(eps[ran & stable], ys[ran & stable], s=10, c="tab:green", alpha=0.6,
                   label="simulated stable")
        ax.scatter(eps[ran & ~stable], ys[ran & ~stable], s=14, c="tab:red", marker="x",
                   label="simulated unstable / diverged")
        if other.any():
            ax.scatter(eps[other], ys[other], s=14, c="black", marker="s",
                       label="init refused / error")
        vels = sorted({v for _, v in pred.boundaries})
        notes = []
        for (bc, vel), b in sorted(pred.boundaries.items()):
            if bc != c:
                continue
            x = np.array([b.eps_at(y) for y in b.y])
            drawn = np.isfinite(x) & (x > 0)
            if drawn.any():
                ax.plot(np.where(drawn, x, np.nan), b.y, color="tab:blue",
                        ls=STYLES[vels.index(vel) % len(STYLES)], lw=2,
                        label=f"predicted ε_min ({vel})")
            if (x == 0).any():
                notes.append(f"{vel}: predicted stable at every ε")
            if np.isinf(x).any():
                notes.append(f"{vel}: predicted unstable at some {campaign.map_y} for every ε")
        if notes:
            ax.text(0.02, 0.02, "\n".join(notes), transform=ax.transAxes, fontsize=7,
                    va="bottom", color="tab:blue")
        agr = per[c]["agreement"]
        title = c.upper()
        if agr is not None and agr["runs"]:
            title += f": {100 * agr['fraction']:.0f} % of {agr['runs']} runs agree"
        elif pred.unavailable:
            title += ": predicted boundary not available"
        ax.set_title(title, fontsize=10)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("ε (boundary layer)")
        ax.set_ylabel(campaign.map_y)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"Stability map: {table.num_rows} runs, {campaign.path} "
                 f"{campaign.duration:g} s (points: simulated with every drawn parameter; "
                 "line: sampled-data analysis, nominal robot)", fontsize=10)
    fig.savefig(path, metadata={"Software": None})
    return path
