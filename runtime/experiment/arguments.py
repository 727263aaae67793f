"""The robot and experiment options every command shares, resolved the same way.

``--robot`` names a robot file (lumped, physical, or bodies and wheels), a generated folder,
or a robot generated under ``generated/`` by name (:func:`runtime.bindings.robots.resolve`);
``--generated DIR`` is where a robot file's code is; ``--experiment FILE`` the experiment
(default: the paper's setting; its ``robot = "FILE"`` names the robot when ``--robot`` is
not given). The experiment is then scaled to the robot (:mod:`runtime.experiment.scale`;
the identity for the paper's robot). :func:`output_folder` is where a command writes by
default: its folder for the paper's robot, ``./<command>/<robot name>`` for another.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from runtime.bindings.robots import RobotSetup, RobotSourceError, resolve
from runtime.experiment.scale import robot_scale, scaled_experiment
from runtime.experiment.settings import PAPER_ROBOT, Experiment, load_experiment

ROBOT_HELP = ("a robot file (lumped, physical, or bodies and wheels), a generated folder, or "
              "the name of a robot generated under generated/ (default: the experiment's "
              "robot, else the paper's Drishti)")
GENERATED_HELP = ("where a robot file's generated code is (`wmr model --robot FILE --out "
                  "DIR`; default: the repository's generated/)")


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """``--robot`` and ``--generated``, as every command has them."""
    parser.add_argument("--robot", default=None, metavar="ROBOT", help=ROBOT_HELP)
    parser.add_argument("--generated", type=Path, default=None, metavar="DIR",
                        help=GENERATED_HELP)


def add_experiment_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--experiment", type=Path, default=None, metavar="FILE",
                        help="experiment TOML (default: the paper's setting, scaled to the "
                        "robot)")


@dataclass(frozen=True)
class Setting:
    """A command's robot and its experiment, scaled to it; ``scaling``: one line per scaled
    field (what :func:`runtime.experiment.scale.scaled_experiment` did)."""

    robot: RobotSetup
    experiment: Experiment
    scaling: tuple[str, ...]

    @property
    def is_paper_robot(self) -> bool:
        """The paper's own robot with its own numbers (the experiment is not scaled)."""
        return (self.robot.name == PAPER_ROBOT and self.robot.code.prefix == "wmr"
                and self.robot.nominal == self.robot.code.params)


def robot_setting(robot: str | Path | None, generated: Path | None,
                  exp: Experiment) -> Setting:
    """The robot ``--robot``/``--generated`` name (else the experiment's ``robot``, else the
    default robot) and ``exp`` scaled to it. ``RobotSourceError`` (a ``ValueError``) with a
    sentence if the robot cannot be run; ``ValueError`` if the experiment cannot be scaled
    to it."""
    named = robot if robot is not None else exp.robot
    setup = resolve(named, generated)
    scaled, lines = scaled_experiment(exp, robot_scale(setup.code, setup.nominal))
    return Setting(setup, scaled, tuple(lines))


def load_setting(args: argparse.Namespace) -> Setting:
    """:func:`robot_setting` of a command's parsed ``--robot``, ``--generated`` and
    ``--experiment`` (``ExperimentFileError`` or ``RobotSourceError``, both ``ValueError``)."""
    exp = load_experiment(getattr(args, "experiment", None))
    return robot_setting(args.robot, args.generated, exp)


def output_folder(setting: Setting, out: Path | None, paper_default: Path,
                  command: str) -> Path:
    """``--out``, else ``paper_default`` for the paper's robot, else ``./<command>/<name>``."""
    if out is not None:
        return out
    return paper_default if setting.is_paper_robot else Path(command) / setting.robot.name


__all__ = ["RobotSourceError", "Setting", "add_experiment_option", "add_robot_options",
           "load_setting", "output_folder", "robot_setting"]
