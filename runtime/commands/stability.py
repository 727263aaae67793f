"""``wmr stability``: the command line of :mod:`runtime.stability.analysis` (whether each
generated controller is stable on a robot with the experiment's sampling, sensing and
estimator); prints the table or JSON."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace

from runtime.bindings.generated import RobotCode
from runtime.bindings.robots import RobotSourceError
from runtime.commands.options import add_experiment_option, add_robot_options, loaded_setting
from runtime.experiment.settings import (
    VELOCITY_MODELS,
    Experiment,
    ExperimentFileError,
    check_sensing,
    load_experiment,
)
from runtime.stability.analysis import (
    Analysis,
    analyse_all,
    as_json,
    not_analysed,
    table,
    tde_notes,
)
from runtime.stability.jitter import budget, delay_jitter, loop_for, measured, verdict
from runtime.stability.sampled_loop import OPERATING_POINTS, covers, setting


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr stability",
        description="Predict whether each generated controller is stable on a robot with the "
        "experiment's sampling, sensing and estimator (linearised sampled-data loop).",
    )
    add_experiment_option(parser)
    add_robot_options(parser)
    parser.add_argument(
        "--sensing", default=None, choices=VELOCITY_MODELS,
        help="override the experiment's [sensing] velocity",
    )  # fmt: skip
    parser.add_argument(
        "--plant", choices=("nominal", "payload"), default="nominal",
        help="analysed robot: as the controllers model it, or with the experiment's payload",
    )  # fmt: skip
    parser.add_argument(
        "--no-measure", action="store_true",
        help="do not simulate to measure TDROC/ASMC's k̂ (faster; their setting gain is 0)",
    )  # fmt: skip
    parser.add_argument(
        "--path", choices=OPERATING_POINTS, default="circle",
        help="linearise about the circle's steady motion, or the lawn mower's leg and turns "
        "(the worst decides)",
    )  # fmt: skip
    parser.add_argument(
        "--no-delay", action="store_true",
        help="do not search the largest tolerated delay (faster)",
    )  # fmt: skip
    parser.add_argument(
        "--no-saturation", action="store_true",
        help="do not check the torque demand and the adaptive gain's start-up (faster)",
    )  # fmt: skip
    parser.add_argument(
        "--jitter", action="store_true",
        help="also the jitter verdicts: latencies varying every sample within the "
        "experiment's [controller] jitter, and the measured timing (period_worst, "
        "latency_worst): proved / not proved (necessary condition holds) / unstable",
    )  # fmt: skip
    parser.add_argument(
        "--jitter-budget", action="store_true",
        help="also the largest proved delay jitter beside the constant-delay (necessary) "
        "boundary, per row (about a minute a row)",
    )  # fmt: skip
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args(argv)
    try:
        exp = load_experiment(args.experiment)
        if args.sensing is not None:
            exp = replace(exp, sensing=replace(exp.sensing, velocity=args.sensing))
            check_sensing(exp, "--sensing")
        setting_ = loaded_setting(args.robot, args.generated, exp)
        setup = setting_.robot
        if not covers(setup.code):
            raise RobotSourceError(
                f"{setup.source}: robot '{setup.name}': the sampled-loop analysis needs the "
                "root's pose (x, y, θ) as the first coordinates and driven wheels. Simulate "
                f"this robot with `wmr reproduce --robot {setup.source}`"
            )
    except (ExperimentFileError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    exp, code, robot = setting_.experiment, setup.code, setup.nominal
    if (args.robot or exp.robot) is not None and not args.json:
        print(f"robot '{setup.name}' from {setup.source}:", *setting_.scaling, sep="\n  ")
    refused: list[str] = []
    rows = analyse_all(code, robot, exp, args.plant, measure=not args.no_measure,
                       path=args.path, delays=not args.no_delay,
                       saturation=not args.no_saturation, refused=refused)
    if args.json:
        print(json.dumps(as_json(rows, setup.name), indent=2))
    else:
        print(
            f"robot {setup.name}, h = {exp.controller.h} s, sensing {exp.sensing.velocity}, "
            f"plant {args.plant}, ε = {exp.controller.eps}"
        )
        print(table(rows, code), *tde_notes(code, robot, exp), *not_analysed(code), *refused,
              sep="\n")
        if args.jitter or args.jitter_budget:
            print(*jitter_lines(rows, code, robot, exp, args.plant, args.jitter_budget),
                  sep="\n")
    return 0


def jitter_lines(rows: list[Analysis], code: RobotCode, robot: dict[str, float],
                 exp: Experiment, plant: str, with_budget: bool) -> list[str]:
    """The jitter verdicts of every stable row (runtime.stability.jitter), one line each."""
    c = exp.controller
    ranges = []
    if c.jitter_seconds() > 0:
        ranges.append(("[controller] jitter", delay_jitter(c.h, c.delay_seconds(),
                                                           c.jitter_seconds())))
    if c.period_worst > 0 or c.latency_worst > 0:
        ranges.append(("measured timing", measured(c.h, max(c.h, c.period_worst),
                                                   c.latency_worst)))
    out = ["", "Jitter (a common quadratic Lyapunov function over the range; "
           "runtime/stability/jitter.py):"]
    if not ranges and not with_budget:
        out.append("* no jitter stated ([controller] jitter, period_worst, latency_worst)")
    for r in rows:
        if not r.stable:
            continue
        s = setting(code, r.controller, r.formulation, robot, exp, plant)
        loop = loop_for(s)
        for label, timing in ranges:
            try:
                v = verdict(loop, r.gain_at_setting, timing)
                bound = "" if v.bound is None else f", ‖J‖_P ≤ {v.bound:.3f}"
                out.append(f"* {r.controller} {r.formulation}, {label} ({timing.describe()}): "
                           f"{v.verdict} (constant-timing radius ≤ {v.radius:.3f}{bound})")
            except ValueError as exc:
                out.append(f"* {r.controller} {r.formulation}, {label}: no verdict: {exc}")
        if with_budget:
            b = budget(s, r.gain_at_setting)
            out.append(f"* {r.controller} {r.formulation}: delay jitter proved up to "
                       f"±{b.proved * 1e3:.3g} ms, necessary boundary ±{b.necessary * 1e3:.3g} "
                       f"ms, destabilising switching found from ±{b.destabilising * 1e3:.3g} ms "
                       f"({b.seconds:.0f} s)")
    return out


if __name__ == "__main__":
    sys.exit(main())
