"""``wmr reproduce``: the command line of the one reproduce driver,
:mod:`runtime.reproduction.driver` (the paper's experiments on the setting's robot, the
experiment scaled to it). Checks every argument before any simulation runs. On the paper's
robot (:attr:`runtime.setting.robot.Setting.is_paper_robot`) it writes the figures, the
tables of :mod:`runtime.paper.reproduction_tables` and the report of
:mod:`runtime.paper.reproduction_report`, and prints the verdicts of
:mod:`runtime.paper.reproduction_verdicts`; on another, the report of
:mod:`runtime.reproduction.robot_report`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from modeling.package_paths import default_output
from runtime.commands.options import (
    Setting,
    add_experiment_option,
    add_plant_option,
    add_robot_options,
    load_setting,
    output_folder,
)
from runtime.commands.output_folder import OutputFolderError, writable_folder
from runtime.experiment.settings import (
    VELOCITY_MODELS,
    ExperimentFileError,
    check_sensing,
)
from runtime.paper.reproduction_report import Figure, report_markdown
from runtime.paper.reproduction_tables import fmt_mm, metrics_markdown, write_csv
from runtime.paper.reproduction_verdicts import claims, stability
from runtime.plant_comparison import compare, report_section
from runtime.reproduction import robot_report
from runtime.reproduction.driver import DEFAULT_SENSINGS, Reproduction, reproduce, with_sensing

DEFAULT_OUT = default_output("docs/reproduction")  # ./reproduction when installed

# --------------------------------------------------------------------------- CLI


def parse_sensings(text: str) -> tuple[str, ...]:
    """``MODEL[,MODEL]`` → the velocity models, in order, without repeats."""
    names = tuple(dict.fromkeys(s.strip() for s in text.split(",") if s.strip()))
    bad = [s for s in names if s not in VELOCITY_MODELS]
    if not names or bad:
        raise ExperimentFileError(
            f"--sensing: expected one or more of {', '.join(VELOCITY_MODELS)} separated by "
            f"commas, got {text!r}"
        )
    return names


def write_paper_outputs(rep: Reproduction, out: Path, plots: bool) -> list[Figure]:
    """The paper's robot: figures, ``metrics.md``, ``metrics.csv`` and ``REPORT.md`` into
    ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    figures: list[Figure] = []
    if plots:  # Matplotlib is imported only when the figures are drawn
        from runtime.paper import figures as figs

        figures = figs.render_all(rep, out)
    (out / "metrics.md").write_text(metrics_markdown(rep), encoding="utf-8")
    write_csv(rep, out / "metrics.csv")
    (out / "REPORT.md").write_text(report_markdown(rep, figures), encoding="utf-8")
    return figures


def print_summary(rep: Reproduction) -> None:
    for sensing in rep.sensings:
        for s in stability(rep, sensing):
            print(
                f"stability [{sensing}]: {rep.labels[s.controller]:5s} {s.path:9s} ultimate "
                f"bound {s.ultimate_bound:.3g}, measured {s.measured:.3g}"
            )
        for cl in claims(rep, sensing):
            verdict = "reproduces" if cl.holds else "does NOT reproduce"
            print(f"claim [{sensing}]: {cl.text}: {verdict} ({cl.evidence})")
    mu = rep.experiment.plant.friction
    for sensing in rep.sensings:
        for m in rep.rows(sensing):
            if m.friction_needed > mu:  # nan (not monitored) is never above
                print(f"grip [{sensing}]: {rep.labels[m.controller]:5s} {m.path:9s} "
                      f"{m.formulation:7s} needs μ = {m.friction_needed:.3g} > the floor's "
                      f"{mu:g}: slips")
    for row in rep.sweep:
        print(
            f"sweep: {row.sensing:15s} {row.estimator:8s} eps {row.eps:<4g} "
            f"{row.metrics.path:9s} RMS {fmt_mm(row.metrics.rms_error):>8s} mm "
            f"({row.ratio:.2f}x TDC) {'stable' if row.stable else 'UNSTABLE'}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr reproduce", description="Reproduce the paper's experiments, on its robot or "
        "scaled to another."
    )
    add_experiment_option(parser)
    add_plant_option(parser)
    parser.add_argument(
        "--sensing",
        default=",".join(DEFAULT_SENSINGS),
        metavar="MODEL[,MODEL]",
        help=f"velocity models to run, of {', '.join(VELOCITY_MODELS)} "
        f"(default: {','.join(DEFAULT_SENSINGS)})",
    )
    add_robot_options(parser)
    parser.add_argument(
        "--out", type=Path, default=None,
        help="output folder (default: docs/reproduction of a source checkout, ./reproduction "
        "when installed, for the paper's robot; ./reproduction/<robot> for another)",
    )  # fmt: skip
    parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    parser.add_argument(
        "--compare-plant", choices=("mujoco",), default=None,
        help="repeat every run on MuJoCo (the MJCF `wmr mjcf` writes; the experiment's "
        "contact settings) and put both plants side by side in REPORT.md",
    )
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        setting = load_setting(args)
        exp = setting.experiment
        sensings = parse_sensings(args.sensing)
        for s in sensings:
            check_sensing(with_sensing(exp, s), str(args.experiment or "--sensing"))
        out = writable_folder(output_folder(setting, args.out, DEFAULT_OUT, "reproduction"))
    except (ExperimentFileError, OutputFolderError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if exp.faults:
        print(
            f"note: {exp.source}: {len(exp.faults)} [[fault]] table(s) not used here; "
            "`wmr faults` runs them",
            file=sys.stderr,
        )
    if not setting.is_paper_robot:  # what scaling did (the identity on the paper's robot)
        print(f"robot '{setting.robot.name}' from {setting.robot.source}:", *setting.scaling,
              sep="\n  ", flush=True)
    try:
        rep = reproduce(setting, sensings, progress=True)
        t_write = time.perf_counter()
        if not setting.is_paper_robot:
            robot_report.write_outputs(rep, out, plots=not args.no_plots)
    except ValueError as exc:  # a robot the scaled experiment does not apply to
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if setting.is_paper_robot:  # the paper's extras: its tables, verdicts, report, figures
        write_paper_outputs(rep, out, plots=not args.no_plots)
        print_summary(rep)
    bad = [m for m in rep.table if m.status != "ok"]
    print(f"{len(rep.table) - len(bad)} of {len(rep.table)} runs ok"
          + (f"; not ok: {', '.join(sorted({m.status for m in bad}))}" if bad else ""))
    end = time.perf_counter()
    print(f"wrote {out}: wall time {end - start:.1f} s (simulation {rep.seconds:.1f} s, "
          f"figures and files {end - t_write:.1f} s)")
    if args.compare_plant is not None:
        _compare_plant(setting, sensings, out)
    return 0


def _compare_plant(setting: Setting, sensings: tuple[str, ...], out: Path) -> None:
    """``--compare-plant mujoco``: every run again on the model plant and on MuJoCo at the
    experiment's floor (:func:`runtime.plant_comparison.compare`), appended to
    ``REPORT.md`` side by side (:func:`runtime.plant_comparison.report_section`)."""
    friction = setting.experiment.plant.friction
    t0 = time.perf_counter()
    comp = compare(setting, sensings, ((f"μ = {friction:g}", friction, 0.0),),
                   progress=True, onset_frictions=())
    report = out / "REPORT.md"
    text = report.read_text(encoding="utf-8").rstrip("\n")
    report.write_text(text + "\n\n" + "\n".join(report_section(comp)), encoding="utf-8")
    print(f"wrote {report}: the model plant against MuJoCo, {len(comp.rows)} runs each "
          f"({time.perf_counter() - t0:.1f} s)")

