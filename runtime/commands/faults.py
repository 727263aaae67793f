"""``wmr faults``: the command line of :mod:`runtime.fault_table` (what each controller
reports under sensor and actuator faults); writes ``FAULTS.md`` and ``faults.csv``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from runtime.commands.options import (
    add_experiment_option,
    add_plant_option,
    add_robot_options,
    load_setting,
    output_folder,
)
from runtime.commands.output_folder import OutputFolderError, writable_folder
from runtime.experiment.settings import ExperimentFileError
from runtime.fault_table import DEFAULT_OUT, fault_table, write


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr faults",
        description="Inject sensor and actuator faults; write FAULTS.md and faults.csv.",
    )
    add_experiment_option(parser)
    add_plant_option(parser)
    add_robot_options(parser)
    parser.add_argument(
        "--out", type=Path, default=None,
        help="output folder (default: docs/ of a source checkout, the working directory when "
        "installed, for the paper's robot; ./faults/<robot> for another)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    try:
        setting = load_setting(args)
        out = writable_folder(output_folder(setting, args.out, DEFAULT_OUT, "faults"))
    except (ExperimentFileError, OutputFolderError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    setup = setting.robot
    if not setting.is_paper_robot:
        print(f"robot '{setup.name}' from {setup.source}:", *setting.scaling, sep="\n  ",
              flush=True)
    try:
        table = fault_table(setting.experiment, robot=setup.nominal, code=setup.code,
                            plant=None if setting.is_paper_robot else setup.plant,
                            progress=True, warnings=setup.warnings)
    except ValueError as exc:  # a robot or fault the faults cannot be simulated on
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for path in write(table, out):
        print(f"wrote {path}")
    return 0
