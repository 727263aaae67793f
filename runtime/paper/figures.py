"""Figures of the reproduction, each a counterpart of a figure of Roy et al. (2017), Section 5.

=========================================  ============================================
file                                       paper
=========================================  ============================================
``fig03_mass.png``                         Figure 3 (system mass variation)
``tracking.png``                           Figures 4 and 11 (circle, lawn-mower tracking)
``fig05_06_circle_xy_error.png``           Figures 5 and 6 (x_c, y_c error, circle)
``fig07_08_circle_switching.png``          Figures 7 and 8 (right/left switching, circle)
``fig09_10_lawnmower_reference.png``       Figures 9 and 10 (desired path, wheel rates)
``fig12_lawnmower_path_error.png``         Figure 12 (path error, lawn mower)
``fig13_14_lawnmower_switching.png``       Figures 13 and 14 (switching, lawn mower)
``torques.png``                            none: τ_r, τ_l per controller
``tdroc_sensing.png``                      none: TDROC stable / unstable by estimator
=========================================  ============================================

``tracking.png`` keeps its old name because README.md embeds it.

The paper's figures are drawn for the first sensing model of the reproduction (default
``sample-instant``), paper formulation. Rendering uses Matplotlib's object API (no pyplot,
no global backend) with the Agg canvas, a fixed dpi and ``metadata={"Software": None}``,
so the PNG bytes depend only on the data: two renders of the same reproduction are equal.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure as MplFigure
from matplotlib.ticker import MaxNLocator
from numpy.typing import NDArray

from runtime.paper import printed_paths
from runtime.paper.reproduction_report import Figure
from runtime.reproduction.driver import Reproduction
from runtime.sim.loop import Run
from runtime.sim.payload import plant_params_at
from runtime.sim.reference import Reference

DPI = 100
Bounds = tuple[float, float, float, float]  # inset (x0, y0, width, height), axes fraction
RC: dict[Any, Any] = {
    "font.size": 8.5,
    "axes.titlesize": 9,
    "legend.fontsize": 7.5,
    "figure.titlesize": 10.5,
    "lines.linewidth": 1.0,
    "axes.grid": True,
    "grid.alpha": 0.3,
}
# Units of the switching term Δu_a = k̂ s / max(‖s‖, ε) of (24)/(25), hence of k̂.
GAIN_UNIT = {
    "paper": "mixed: m/s² on the x_c, y_c rows, rad/s² on the θ, θ_r, θ_l rows",
    "minimal": "rad/s² (wheel rows only)",
}
LINTHRESH = 1e-3  # rad/s²: TDROC's switching term stays near 1e-3 inside its boundary layer
PRINTED_STYLE: dict[str, Any] = {"color": "0.6", "ls": ":", "lw": 1.4}
REF_STYLE: dict[str, Any] = {"color": "k", "ls": "--", "lw": 1.2}


def save(fig: MplFigure, path: Path) -> None:
    """Write a PNG whose bytes depend only on the drawing: Agg, fixed dpi, no metadata."""
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=DPI, format="png", metadata={"Software": None})


def new_figure(title: str, figsize: tuple[float, float]) -> MplFigure:
    fig = MplFigure(figsize=figsize, layout="constrained")
    fig.suptitle(title)
    return fig


def setting(rep: Reproduction, sensing: str) -> str:
    """The words every caption ends with: what the runs were."""
    c = rep.experiment.controller
    return (
        f"Simulated, paper formulation, sensing `{sensing}`, estimator `{rep.estimator}`, "
        f"h = {c.h} s, K1 = K2 = {c.k1:g} I, Q = I, ε = {c.eps}, n = {c.n}, a = {c.a}."
    )


def main_run(rep: Reproduction, ctrl: str, path: str, sensing: str | None = None) -> Run:
    return rep.runs[(sensing or rep.sensings[0], ctrl, "paper", path)]


# --------------------------------------------------------------------------- helpers


def zoom_window(
    rep: Reproduction, sensing: str, path: str, t_zoom: float
) -> tuple[NDArray[np.float64], float]:
    """Centre (the reference at t_zoom) and half-width of a square that holds every
    controller's position at that time (at least 6 mm, at most 0.3 m)."""
    ref = rep.refs[path]
    k = int(np.argmin(np.abs(ref.t - t_zoom)))
    centre = ref.q[k, :2]
    spread = 0.0
    for c in rep.controllers():
        q = main_run(rep, c, path, sensing).q
        spread = max(spread, float(np.linalg.norm(q[min(k, len(q) - 1), :2] - centre)))
    return centre, float(np.clip(1.6 * spread, 0.006, 0.3))


def add_zoom(
    ax: Axes,
    bounds: Bounds,
    centre: NDArray[np.float64],
    half: float,
    draw: Callable[[Axes], None],
) -> Axes:
    """A zoomed inset (``ax.inset_axes``) of the square ``centre ± half``."""
    ins = ax.inset_axes(bounds)
    draw(ins)
    ins.set_xlim(centre[0] - half, centre[0] + half)
    ins.set_ylim(centre[1] - half, centre[1] + half)
    ins.set_aspect("equal", adjustable="box")
    ins.tick_params(labelsize=6)
    ins.xaxis.set_major_locator(MaxNLocator(3))
    ins.yaxis.set_major_locator(MaxNLocator(4))
    ins.set_title(f"zoom: {2000 * half:.0f} mm wide", fontsize=6.5)
    ax.indicate_inset_zoom(ins, edgecolor="0.3")
    return ins


def add_value_zoom(
    rep: Reproduction,
    ax: Axes,
    bounds: Bounds,
    series: Sequence[tuple[Run, NDArray[np.float64]]],
    t_from: float,
) -> Axes:
    """An inset of the curves after ``t_from``, y-limits fitted to ``series`` (the ones
    that overlap at the main axes' scale)."""
    ins = ax.inset_axes(bounds)
    lo, hi = 0.0, 0.0
    for r, y in series:
        late = r.t >= t_from
        ins.plot(r.t[late], y[late], color=rep.colors[r.controller], lw=0.9)
        lo, hi = min(lo, float(y[late].min())), max(hi, float(y[late].max()))
    pad = 0.1 * (hi - lo) + 1e-6
    ins.set_xlim(t_from, float(series[0][0].t[-1]))
    ins.set_ylim(lo - pad, hi + pad)
    ins.tick_params(labelsize=6)
    ins.set_title("zoom: " + ", ".join(rep.labels[r.controller] for r, _ in series), fontsize=6.5)
    ax.indicate_inset_zoom(ins, edgecolor="0.3")
    return ins


def percent_axis(ax: Axes, scale_m: float, label: str) -> None:
    """A right-hand axis in % of ``scale_m`` for an axis in mm (the paper plots %)."""
    factor = 100.0 / (1000.0 * scale_m)

    def to_percent(y: Any) -> Any:
        return np.asarray(y) * factor

    def to_mm(p: Any) -> Any:
        return np.asarray(p) / factor

    sec = ax.secondary_yaxis("right", functions=(to_percent, to_mm))
    sec.set_ylabel(label)


def lawnmower_paper_scale(ref: Reference) -> float:
    """The paper's scale of Figure 12's percentages, "the maximum path ... that comprises
    the individual maximum position information in x_dc and y_dc", read as
    ‖(max |x_dc|, max |y_dc|)‖ of our reference."""
    return float(np.hypot(np.abs(ref.q[:, 0]).max(), np.abs(ref.q[:, 1]).max()))


# --------------------------------------------------------------------------- figures


def fig_mass(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """Paper Figure 3: system mass variation (our payload schedule and what it does to I
    and K)."""
    r = main_run(rep, "tdc", "lawnmower", sensing)
    exp = rep.experiment_for(sensing)
    base = {**rep.code.plant_defaults, **rep.robot}
    true = [plant_params_at(rep.code, exp, float(t), base) for t in r.t]
    params = np.array([[p[k] for k in ("m", "I", "K", "K_lat")] for p in true])
    title = "Paper Figure 3 (System mass variation): true mass, inertia and first moments"
    fig = new_figure(title, (9, 5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.step(r.t, params[:, 0], where="post", color="k")
    ax1.axhline(rep.robot["m"], color="tab:orange", ls="--", label="controllers' nominal m")
    ax1.set_ylabel("m [kg]")
    ax1.legend(loc="upper left", bbox_to_anchor=(1.08, 1.0))
    ax2.step(r.t, params[:, 1], where="post", color="tab:blue", label="I [kg m²]")
    ax2.axhline(rep.robot["I"], color="tab:blue", ls="--", lw=0.8, label="nominal I")
    ax2.set_ylabel("I [kg m²]")
    twin = ax2.twinx()
    twin.grid(False)
    twin.step(r.t, params[:, 2], where="post", color="tab:green", label="K [kg m]")
    twin.step(r.t, params[:, 3], where="post", color="tab:red", label="K_lat [kg m]")
    twin.set_ylabel("K, K_lat [kg m]")
    lines = ax2.get_legend_handles_labels()
    lines2 = twin.get_legend_handles_labels()
    ax2.legend(
        lines[0] + lines2[0], lines[1] + lines2[1], loc="upper left", bbox_to_anchor=(1.08, 1.0)
    )
    ax2.set_xlabel("t [s]")
    pl = exp.plant
    path = out / "fig03_mass.png"
    save(fig, path)
    caption = (
        f"**Paper Figure 3 (System mass variation).** True parameters of the simulated robot: "
        f"the bare robot ({rep.robot['m']:g} kg, the controllers' nominal model) plus the "
        f"{pl.fixed_payload:g} kg rangefinder at ({pl.fixed_payload_x:g}, "
        f"{pl.fixed_payload_y:g}) m, plus {pl.extra_payload:g} kg at ({pl.extra_payload_x:g}, "
        f"{pl.extra_payload_y:g}) m (ahead of C, to the left) on from t = "
        f"{pl.extra_on_at:g} s for {pl.extra_period / 2:g} s of every {pl.extra_period:g} s. "
        "The paper places its 3 kg 'rather randomly'; ours is this fixed schedule. The "
        "off-axis load also changes I, K and adds a lateral first moment K_lat that no "
        "controller's model has."
    )
    return Figure(path, title, caption)


def draw_tracking(ax: Axes, rep: Reproduction, path: str, sensing: str, printed: bool) -> None:
    ref = rep.refs[path]
    if printed:
        fn = (printed_paths.printed_circle if path == "circle"
              else printed_paths.printed_lawnmower)
        pts = fn(ref.t)
        ax.plot(pts[:, 0], pts[:, 1], **PRINTED_STYLE, label="printed reference (inconsistent)")
    ax.plot(ref.q[:, 0], ref.q[:, 1], **REF_STYLE, label="reference (ours, consistent)")
    for c in rep.controllers():
        r = main_run(rep, c, path, sensing)
        ax.plot(r.q[:, 0], r.q[:, 1], color=rep.colors[c], lw=1.0, label=rep.labels[c])


def fig_tracking(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """Paper Figures 4 and 11: circular and lawn-mower path tracking, with zoomed insets
    where the controllers' paths overlap the reference."""
    title = "Paper Figure 4 (Circular path tracking) and Figure 11 (Lawn mower path tracking)"
    fig = new_figure(title, (12, 6))
    axes = fig.subplots(1, 2)
    # (fraction of the run at which to zoom, inset bounds in axes coordinates: empty areas)
    zooms: dict[str, tuple[float, Bounds]] = {
        "circle": (0.55, (0.66, 0.03, 0.32, 0.30)),
        "lawnmower": (0.45, (0.60, 0.57, 0.38, 0.36)),
    }
    for ax, path in zip(axes, rep.refs, strict=True):
        draw_tracking(ax, rep, path, sensing, printed=True)
        frac, bounds = zooms.get(path, (0.5, (0.55, 0.05, 0.4, 0.4)))
        t_zoom = frac * float(rep.refs[path].t[-1])
        centre, half = zoom_window(rep, sensing, path, t_zoom)
        draw = partial(draw_tracking, rep=rep, path=path, sensing=sensing, printed=False)
        add_zoom(ax, bounds, centre, half, draw)
        ax.set_title(f"{path}: (x_c, y_c) of the true pose; zoom at t = {t_zoom:.0f} s")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
    axes[0].legend(loc="lower left")
    path_out = out / "tracking.png"
    save(fig, path_out)
    caption = (
        "**Paper Figure 4 (Circular path tracking comparison) and Figure 11 (Lawn mower path "
        "tracking performance comparison).** The controllers' true (x_c, y_c) against our "
        "consistent reference (dashed) and the paper's printed one (dotted grey, which no "
        "robot obeying (6)–(8) can follow; see 'The reference paths'). At this scale all "
        "four overlap the reference; the insets zoom on one instant. " + setting(rep, sensing)
    )
    return Figure(path_out, title, caption)


def fig_circle_xy(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """Paper Figures 5 and 6: x_c and y_c position error on the circle, in mm and in % of
    the circle's diameter (the paper's percentage)."""
    title = "Paper Figure 5 (x_c position error) and Figure 6 (y_c position error), circle"
    fig = new_figure(title, (10, 6.5))
    axes = fig.subplots(2, 1, sharex=True)
    ref = rep.refs["circle"]
    diameter = 2 * rep.refs["circle"].scale
    for row, (ax, name) in enumerate(zip(axes, ("x_c", "y_c"), strict=True)):
        series = []
        for c in rep.controllers():
            r = main_run(rep, c, "circle", sensing)
            e = 1000 * (ref.q[: len(r.t), row] - r.q[:, row])
            ax.plot(r.t, e, color=rep.colors[c], label=rep.labels[c])
            if c in ("tdc", "tdroc"):
                series.append((r, e))
        ax.set_ylabel(f"{name},d − {name} [mm]")
        percent_axis(ax, diameter, "% of the diameter 2R1")
        ax.set_title(f"Paper Figure {5 + row}: {name} position error")
        add_value_zoom(rep, ax, (0.55, 0.58, 0.42, 0.38), series, 0.5 * float(ref.t[-1]))
    axes[0].legend(loc="lower left", ncol=4)
    axes[1].set_xlabel("t [s]")
    path = out / "fig05_06_circle_xy_error.png"
    save(fig, path)
    caption = (
        "**Paper Figure 5 (x_c position error comparison) and Figure 6 (y_c position error "
        "comparison)**, circle. Error of the true pose in mm (left axis) and, as the paper "
        f"plots it, in % of the circle's diameter 2R1 = {diameter:g} m (right axis). Insets: "
        "TDC and TDROC over the second half, which overlap at the main scale. "
        + setting(rep, sensing)
    )
    return Figure(path, title, caption)


def draw_switching(ax: Axes, rep: Reproduction, path: str, sensing: str, wheel: int) -> None:
    for c in rep.switching():
        r = main_run(rep, c, path, sensing)
        ax.plot(
            r.t, r.wheel_switching[:, wheel], color=rep.colors[c], lw=0.8,
            label=f"{rep.labels[c]}: Δu_a",
        )
        ax.plot(
            r.t,
            r.gain,
            color=rep.colors[c],
            lw=0.8,
            ls="--",
            alpha=0.7,
            label=f"{rep.labels[c]}: k̂ (bound on |Δu_a|)",
        )
    ax.set_yscale("symlog", linthresh=LINTHRESH)


def fig_switching(rep: Reproduction, out: Path, sensing: str, path: str) -> Figure:
    """Paper Figures 7 and 8 (circle) or 13 and 14 (lawn mower): the switching term of
    (24)/(25) on the right and left wheel rows, with k̂ dashed."""
    nums = (7, 8) if path == "circle" else (13, 14)
    title = (
        f"Paper Figure {nums[0]} (right wheel) and Figure {nums[1]} (left wheel): "
        f"switching gain comparison, {'circular' if path == 'circle' else 'lawn mower'} path"
    )
    fig = new_figure(title, (10, 6.5))
    axes = fig.subplots(2, 1, sharex=True)
    for row, (ax, wheel) in enumerate(zip(axes, ("right", "left"), strict=True)):
        draw_switching(ax, rep, path, sensing, row)
        sym = "θ_r" if row == 0 else "θ_l"
        ax.set_title(f"Paper Figure {nums[row]}: {wheel} wheel")
        ax.set_ylabel(f"Δu_a on the {sym} row [rad/s²]\nk̂ [switching-term units]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=6)
    axes[1].set_xlabel("t [s]")
    name = f"fig{nums[0]:02d}_{nums[1]:02d}_{path}_switching.png"
    out_path = out / name
    save(fig, out_path)
    caption = (
        f"**Paper Figures {nums[0]} and {nums[1]} (right and left wheel switching gain "
        f"comparison, {'circular' if path == 'circle' else 'lawn mower'} path).** Solid: the "
        "wheel rows of the switching term Δu_a = k̂ s / max(‖s‖, ε) of (24)/(25) "
        "(`runtime/sim/loop.py`, `Run.wheel_switching`; ASMC with the gain before each "
        "step's adaptation), in rad/s². Dashed: the gain k̂ itself, which bounds |Δu_a| on "
        f"every row; its unit is the switching term's ({GAIN_UNIT['paper']} in the paper "
        f"formulation; {GAIN_UNIT['minimal']} in the minimal one). Symmetric-log scale, "
        f"linear below {LINTHRESH:g}. TDC has no switching term. " + setting(rep, sensing)
    )
    return Figure(out_path, title, caption)


def fig_lawnmower_reference(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """Paper Figures 9 and 10: the desired lawn-mower path and desired wheel velocities,
    ours (consistent) beside the printed ones."""
    ref = rep.refs["lawnmower"]
    title = "Paper Figure 9 (Desired lawn mower path) and Figure 10 (Desired wheel velocities)"
    fig = new_figure(title, (12, 5))
    ax1, ax2 = fig.subplots(1, 2, width_ratios=(1, 1.3))
    pts = printed_paths.printed_lawnmower(ref.t)
    ax1.plot(pts[:, 0], pts[:, 1], **PRINTED_STYLE, label="printed x_dc, y_dc")
    ax1.plot(ref.q[:, 0], ref.q[:, 1], **REF_STYLE, label="ours (from the wheel rates)")
    ax1.plot(*ref.q[0, :2], "ko", ms=4)
    ax1.set_title("Paper Figure 9: desired path")
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.legend(loc="upper right")
    printed = printed_paths.printed_wheel_rates(ref.t)
    for i, (wheel, color) in enumerate((("right", "tab:red"), ("left", "tab:blue"))):
        ax2.plot(
            ref.t,
            printed[:, i],
            color=color,
            ls=":",
            lw=1.2,
            label=f"printed θ̇_{wheel[0]} (square wave)",
        )
        ax2.plot(ref.t, ref.qdot[:, 3 + i], color=color, lw=1.2, label=f"ours θ̇_d{wheel[0]}")
    ax2.set_title("Paper Figure 10: desired wheel velocities")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("wheel rate [rad/s]")
    ax2.legend(loc="lower right", ncol=2)
    path = out / "fig09_10_lawnmower_reference.png"
    save(fig, path)
    caption = (
        "**Paper Figure 9 (Desired lawn mower path) and Figure 10 (Desired wheel "
        "velocities).** Dotted: the printed x_dc = 0.1t + 0.3 sin(0.4t), "
        "y_dc = 1.2 + 1.2 cos(0.2t − T) and the printed square-wave wheel rates (their "
        f"Fourier series summed to the limit; a = {printed_paths.LAWN_A:g}, "
        f"b = {printed_paths.LAWN_B:g} rad/s, T = {printed_paths.LAWN_T:g} s), which describe two "
        "different motions. Solid/dashed: ours, straight legs with both wheels at a and "
        "U-turns with one wheel at b, integrated through (31), so path and rates agree. "
        "Starts at the origin (dot)."
    )
    return Figure(path, title, caption)


def fig_path_error(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """Paper Figure 12: Euclidean path error on the lawn mower, in mm and in % of the
    paper's scale."""
    ref = rep.refs["lawnmower"]
    scale = lawnmower_paper_scale(ref)
    title = "Paper Figure 12 (Path error comparison), lawn mower"
    fig = new_figure(title, (10, 4.5))
    ax = fig.subplots()
    series = []
    for c in rep.controllers():
        r = main_run(rep, c, "lawnmower", sensing)
        e = 1000 * r.position_error
        ax.plot(r.t, e, color=rep.colors[c], label=rep.labels[c])
        if c in ("tdc", "tdroc"):
            series.append((r, e))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖(x_c, y_c) − (x_dc, y_dc)‖ [mm]")
    percent_axis(ax, scale, f"% of {scale:.2f} m")
    add_value_zoom(rep, ax, (0.45, 0.55, 0.45, 0.4), series, 0.5 * float(ref.t[-1]))
    ax.legend(loc="upper left", ncol=4)
    path = out / "fig12_lawnmower_path_error.png"
    save(fig, path)
    caption = (
        "**Paper Figure 12 (Path error comparison for various controllers)**, lawn mower. "
        "Euclidean position error of the true pose in mm (left axis) and in % (right axis) "
        "of the paper's scale, 'the maximum path ... that comprises the individual maximum "
        f"position information in x_dc and y_dc', read as ‖(max|x_dc|, max|y_dc|)‖ = "
        f"{scale:.2f} m of our reference. Inset: TDC and TDROC over the second half. "
        + setting(rep, sensing)
    )
    return Figure(path, title, caption)


def fig_torques(rep: Reproduction, out: Path, sensing: str) -> Figure:
    """τ_r and τ_l per controller and path (no counterpart in the paper)."""
    title = "Wheel torques τ_r, τ_l per controller (no counterpart in the paper)"
    fig = new_figure(title, (12, 8.5))
    controllers = rep.controllers()
    axes = fig.subplots(len(controllers), len(rep.refs), sharex="col", sharey="row")
    for col, path in enumerate(rep.refs):
        for row, c in enumerate(controllers):
            ax = axes[row, col]
            r = main_run(rep, c, path, sensing)
            ax.plot(r.t, r.tau[:, 0], color="tab:red", lw=0.8, label="τ_r (right)")
            ax.plot(r.t, r.tau[:, 1], color="tab:blue", lw=0.8, label="τ_l (left)")
            ax.set_title(f"{rep.labels[c]}, {path}: {r.saturated} saturated steps")
            if col == 0:
                ax.set_ylabel("τ [N m]")
        axes[-1, col].set_xlabel("t [s]")
    axes[0, 0].legend(loc="upper right", ncol=2)
    path_out = out / "torques.png"
    save(fig, path_out)
    caption = (
        "**Wheel torques** (no counterpart in the paper): τ = Bᵀu as applied (after the "
        f"±{rep.experiment.controller.tau_max:g} N m saturation), right wheel red, left "
        "blue, one row per controller; rows share their y-axis. The spikes on the lawn "
        "mower are the wheel-rate switches of its U-turns. " + setting(rep, sensing)
    )
    return Figure(path_out, title, caption)


def sensing_runs(rep: Reproduction, path: str) -> list[tuple[str, str, Run]]:
    """TDROC at the experiment's ε for each (sensing, estimator) of the sweep."""
    eps = rep.experiment.controller.eps
    return [
        (s, est, rep.sweep_runs[(s, est, eps, path)])
        for s, est in rep.sweep_sets()
        if (s, est, eps, path) in rep.sweep_runs
    ]


def fig_sensing(rep: Reproduction, out: Path) -> Figure | None:
    """TDROC stable (default sensing, matched estimator) beside TDROC unstable
    (encoder-average rates with the backward estimator): position error and τ_r."""
    contrast = rep.contrast()
    if contrast is None:
        return None
    c = rep.experiment.controller
    title = (
        f"TDROC, ε = {c.eps}, h = {c.h} s: stable with the matched estimator, UNSTABLE with "
        "encoder-average rates + backward estimator (no counterpart in the paper)"
    )
    fig = new_figure(title, (12, 7))
    axes = fig.subplots(2, len(rep.refs), sharex="col")
    styles = {"matched": "-", "backward": "-", "central": "-."}
    palette = ["tab:red", "tab:orange", "k", "tab:brown", "tab:pink"]
    for col, path in enumerate(rep.refs):
        ax_e, ax_t = axes[0, col], axes[1, col]
        tdc = main_run(rep, "tdc", path)
        ax_e.semilogy(
            tdc.t,
            np.maximum(1000 * tdc.position_error, 1e-3),
            color="tab:blue",
            ls="--",
            label=f"TDC, {rep.sensings[0]}/{rep.estimator}",
        )
        for i, (s, est, r) in enumerate(sensing_runs(rep, path)):
            unstable = (s, est) == contrast
            label = f"TDROC, {s}/{est}" + (" (unstable)" if unstable else "")
            color = palette[i % len(palette)]
            lw = 1.4 if unstable else 1.0
            ax_e.semilogy(
                r.t,
                np.maximum(1000 * r.position_error, 1e-3),
                color=color,
                ls=styles.get(est, "-"),
                lw=lw,
                label=label,
            )
            if i == 0 or unstable:
                ax_t.plot(r.t, r.tau[:, 0], color=color, lw=0.7, label=f"τ_r, {label}")
        ax_t.axhline(c.tau_max, color="0.5", ls=":", lw=0.8)
        ax_t.axhline(-c.tau_max, color="0.5", ls=":", lw=0.8, label="±τ_max")
        ax_e.set_title(f"{path}: position error (log scale)")
        ax_e.set_ylabel("‖(x_c, y_c) − (x_dc, y_dc)‖ [mm]")
        ax_t.set_title(f"{path}: right-wheel torque τ_r")
        ax_t.set_ylabel("τ_r [N m]")
        ax_t.set_xlabel("t [s]")
    axes[0, 0].legend(loc="lower right")
    axes[1, 0].legend(loc="lower right")
    path_out = out / "tdroc_sensing.png"
    save(fig, path_out)
    caption = (
        f"**TDROC stable and unstable** (no counterpart in the paper). TDROC at the paper's "
        f"ε = {c.eps} (h = {c.h} s, K1 = K2 = {c.k1:g} I, Q = I, n = {c.n}, a = {c.a}, paper "
        "formulation) under each sensing/estimator pair of the sweep, and TDC under the "
        f"default `{rep.sensings[0]}`/`{rep.estimator}` for scale. With `encoder-average` "
        "rates and the `backward` estimator (black, the pairing used before the matched "
        "estimator existed) the loop diverges and τ saturates; with the `matched` estimator "
        "the same controller is stable under both sensings."
    )
    return Figure(path_out, title, caption)


def render_all(rep: Reproduction, out: Path) -> list[Figure]:
    """Every figure into ``out``, in the paper's order; the paper's figures for the first
    sensing model."""
    sensing = rep.sensings[0]
    builders: list[Callable[[], Figure | None]] = [
        lambda: fig_mass(rep, out, sensing),
        lambda: fig_tracking(rep, out, sensing),
        lambda: fig_circle_xy(rep, out, sensing),
        lambda: fig_switching(rep, out, sensing, "circle"),
        lambda: fig_lawnmower_reference(rep, out, sensing),
        lambda: fig_path_error(rep, out, sensing),
        lambda: fig_switching(rep, out, sensing, "lawnmower"),
        lambda: fig_torques(rep, out, sensing),
        lambda: fig_sensing(rep, out),
    ]
    figures: list[Figure] = []
    with rc_context(RC):
        for build in builders:
            fig = build()
            if fig is not None:
                figures.append(fig)
    return figures


def png_text_chunks(data: bytes) -> dict[str, Any]:
    """The tEXt/iTXt/zTXt chunks of a PNG (for the test that no metadata varies)."""
    chunks: dict[str, Any] = {}
    pos = 8
    while pos < len(data):
        length = int.from_bytes(data[pos : pos + 4], "big")
        kind = data[pos + 4 : pos + 8].decode("ascii")
        body = data[pos + 8 : pos + 8 + length]
        if kind in ("tEXt", "iTXt", "zTXt"):
            key, _, value = body.partition(b"\0")
            chunks[key.decode("latin-1")] = value
        pos += 12 + length
    return chunks
