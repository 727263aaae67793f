"""``wmr stability``: the command line of :mod:`runtime.stability.analysis` (whether each
generated controller is stable on a robot with the experiment's sampling, sensing and
estimator); prints the table or JSON."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace

from runtime.bindings.robots import RobotSourceError
from runtime.commands.options import add_experiment_option, add_robot_options, loaded_setting
from runtime.experiment.settings import (
    VELOCITY_MODELS,
    ExperimentFileError,
    check_sensing,
    load_experiment,
)
from runtime.stability.analysis import analyse_all, as_json, not_analysed, table, tde_notes
from runtime.stability.sampled_loop import OPERATING_POINTS, covers


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
    return 0


if __name__ == "__main__":
    sys.exit(main())
