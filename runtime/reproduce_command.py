"""``python -m runtime reproduce``: the command line of :mod:`runtime.paper.reproduce` (the paper's
experiments on Drishti) and of :mod:`runtime.robot_reproduce` (``--robot FILE``: the
experiment scaled to any robot). Checks every argument before any simulation runs, then
writes the figures, the tables of :mod:`runtime.paper.reproduction_tables` and the report
of :mod:`runtime.paper.reproduction_report`, and prints the verdicts of
:mod:`runtime.paper.reproduction_verdicts`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from runtime.experiment import (
    VELOCITY_MODELS,
    Experiment,
    ExperimentFileError,
    check_sensing,
    load_experiment,
)
from runtime.output_folder import OutputFolderError, writable_folder
from runtime.paper.reproduce import (
    DEFAULT_OUT,
    DEFAULT_SENSINGS,
    LABELS,
    Figure,
    Reproduction,
    reproduce,
    with_sensing,
)
from runtime.paper.reproduction_report import report_markdown
from runtime.paper.reproduction_tables import fmt_mm, metrics_markdown, write_csv
from runtime.paper.reproduction_verdicts import claims, stability

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


def write_outputs(rep: Reproduction, out: Path, plots: bool) -> list[Figure]:
    """Figures, ``metrics.md``, ``metrics.csv`` and ``REPORT.md`` into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    figures: list[Figure] = []
    if plots:
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
                f"stability [{sensing}]: {LABELS[s.controller]:5s} {s.path:9s} ultimate "
                f"bound {s.ultimate_bound:.3g}, measured {s.measured:.3g}"
            )
        for cl in claims(rep, sensing):
            verdict = "reproduces" if cl.holds else "does NOT reproduce"
            print(f"claim [{sensing}]: {cl.text}: {verdict} ({cl.evidence})")
    for row in rep.sweep:
        print(
            f"sweep: {row.sensing:15s} {row.estimator:8s} eps {row.eps:<4g} "
            f"{row.metrics.path:9s} RMS {fmt_mm(row.metrics.rms_error):>8s} mm "
            f"({row.ratio:.2f}x TDC) {'stable' if row.stable else 'UNSTABLE'}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr reproduce", description="Reproduce the paper's experiments."
    )
    parser.add_argument(
        "--experiment",
        type=Path,
        default=None,
        help="experiment TOML (default: the paper's setting)",
    )
    parser.add_argument(
        "--sensing",
        default=",".join(DEFAULT_SENSINGS),
        metavar="MODEL[,MODEL]",
        help=f"velocity models to run, of {', '.join(VELOCITY_MODELS)} "
        f"(default: {','.join(DEFAULT_SENSINGS)})",
    )
    parser.add_argument(
        "--robot",
        type=Path,
        default=None,
        metavar="FILE",
        help="run the experiment, scaled to it, on this robot file (lumped, physical or "
        "bodies and wheels; default: the experiment's robot, else the paper's Drishti)",
    )
    parser.add_argument(
        "--generated",
        type=Path,
        default=None,
        metavar="DIR",
        help="where the robot's generated code is (default: the repository's generated/)",
    )
    parser.add_argument(
        "--out", type=Path, default=None,
        help="output folder (default: docs/reproduction of a source checkout, ./reproduction "
        "when installed; ./reproduction/<robot> with --robot)",
    )  # fmt: skip
    parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        exp = load_experiment(args.experiment)
        sensings = parse_sensings(args.sensing)
        for s in sensings:
            check_sensing(with_sensing(exp, s), str(args.experiment or "--sensing"))
    except ExperimentFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if exp.faults:
        print(
            f"note: {exp.source}: {len(exp.faults)} [[fault]] table(s) not used here; "
            "`python -m runtime faults` runs them",
            file=sys.stderr,
        )
    robot_file = args.robot or (Path(exp.robot) if exp.robot else None)
    if robot_file is not None or args.generated is not None:
        return _main_robot(robot_file, args, exp, sensings, start)
    try:
        args.out = writable_folder(args.out or DEFAULT_OUT)
    except OutputFolderError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    rep = reproduce(exp, progress=True, sensings=sensings)
    t_plot = time.perf_counter()
    write_outputs(rep, args.out, plots=not args.no_plots)
    end = time.perf_counter()
    print_summary(rep)
    print(
        f"wrote {args.out}: wall time {end - start:.1f} s (simulation {rep.seconds:.1f} s, "
        f"figures and files {end - t_plot:.1f} s)"
    )
    return 0


def _main_robot(
    robot_file: Path | None,
    args: argparse.Namespace,
    exp: Experiment,
    sensings: tuple[str, ...],
    start: float,
) -> int:
    """``--robot FILE``: the experiment scaled to that robot (:mod:`runtime.robot_reproduce`)."""
    from runtime.robot_reproduce import reproduce_robot, write_outputs
    from runtime.robot_source import RobotSourceError, resolve

    if robot_file is None:
        print("error: --generated needs --robot FILE (the robot to run)", file=sys.stderr)
        return 2
    try:
        setup = resolve(robot_file, args.generated)
    except RobotSourceError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        out = writable_folder(args.out or Path("reproduction") / setup.name)
    except OutputFolderError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        rep = reproduce_robot(setup, exp, sensings, progress=True)
    except ValueError as exc:  # a robot the scaled experiment does not apply to
        print(f"error: {exc}", file=sys.stderr)
        return 2
    write_outputs(rep, out, plots=not args.no_plots)
    print(f"wrote {out}: wall time {time.perf_counter() - start:.1f} s "
          f"(simulation {rep.seconds:.1f} s)")
    return 0

