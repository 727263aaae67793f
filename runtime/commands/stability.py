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
from runtime.commands import jitter_report
from runtime.commands.options import add_experiment_option, add_robot_options, loaded_setting
from runtime.experiment.settings import (
    PLANT_MODELS,
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
from runtime.stability.sampled_loop import (
    FORMULATIONS,
    OPERATING_POINTS,
    covers,
)


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
    parser.add_argument(
        "--jitter-replay", nargs="?", const="", default=None, metavar="PLANT",
        help="also replay the adversarial search's sequences (the worst in each stated "
        "range; with --jitter-budget, the worst inside the proved budget and the growing one "
        "at the smallest destabilising jitter) in the closed loop on PLANT (generated or "
        "mujoco; default the experiment's [plant] model): bounded or diverged; a sequence "
        "inside a proved range that diverges fails the command",
    )  # fmt: skip
    parser.add_argument(
        "--only", default=None, metavar="CONTROLLER[/FORMULATION]",
        help="analyse only this controller (registry name), or one of its formulations",
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
        only = None if args.only is None else selected(setup.code, args.only)
        if args.jitter_replay and args.jitter_replay not in PLANT_MODELS:
            raise ValueError(f"--jitter-replay: no plant {args.jitter_replay!r} (one of "
                             f"{', '.join(PLANT_MODELS)})")
    except (ExperimentFileError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    exp, code, robot = setting_.experiment, setup.code, setup.nominal
    if (args.robot or exp.robot) is not None and not args.json:
        print(f"robot '{setup.name}' from {setup.source}:", *setting_.scaling, sep="\n  ")
    refused: list[str] = []
    rows = analyse_all(code, robot, exp, args.plant, measure=not args.no_measure,
                       path=args.path, delays=not args.no_delay,
                       saturation=not args.no_saturation, refused=refused, only=only)
    replay_on = (None if args.jitter_replay is None
                 else args.jitter_replay or exp.plant.model)
    timing = args.jitter or args.jitter_budget or replay_on is not None
    rep = (jitter_report.report(rows, code, robot, exp, args.plant, args.jitter_budget,
                                replay_on) if timing else None)
    if args.json:
        out = as_json(rows, setup.name)
        out["refused"] = [*not_analysed(code), *refused]
        if rep is not None:
            out["jitter"] = jitter_report.as_json(rep)
        print(json.dumps(out, indent=2))
    else:
        print(
            f"robot {setup.name}, h = {exp.controller.h} s, sensing {exp.sensing.velocity}, "
            f"plant {args.plant}, ε = {exp.controller.eps}"
        )
        print(table(rows, code), *tde_notes(code, robot, exp), *not_analysed(code), *refused,
              sep="\n")
        if rep is not None:
            print(*jitter_report.lines(rep, args.jitter_budget), sep="\n")
    if rep is not None and rep.contradictions:
        print(f"error: {rep.contradictions} sequence(s) inside a proved jitter range diverged "
              "in the closed loop", file=sys.stderr)
        return 1
    return 0


def jitter_lines(rows: list[Analysis], code: RobotCode, robot: dict[str, float],
                 exp: Experiment, plant: str, with_budget: bool) -> list[str]:
    """The jitter verdicts of every stable row (runtime.stability.jitter), one line each."""
    return jitter_report.lines(
        jitter_report.report(rows, code, robot, exp, plant, with_budget), with_budget)


def selected(code: RobotCode, only: str) -> list[tuple[str, str]]:
    """The (controller, formulation) pairs ``--only`` names: a controller's registry name,
    or name/formulation; ValueError naming what exists otherwise."""
    name, _, form = only.partition("/")
    names = [c.name for c in code.controller_infos]
    if name not in names:
        raise ValueError(f"--only: no controller {name!r} on robot '{code.name}' "
                         f"(it has {', '.join(names)})")
    forms = [f for f in code.controller(name).formulations if f in FORMULATIONS]
    if form and form not in forms:
        raise ValueError(f"--only: {name} has no formulation {form!r} the analysis takes "
                         f"(it has {', '.join(forms)})")
    return [(name, f) for f in forms if not form or f == form]


if __name__ == "__main__":
    sys.exit(main())
