"""The robot and experiment options every command shares, resolved the same way.

``--robot`` names a robot file (lumped, physical, or bodies and wheels), a generated folder,
or a robot generated under ``generated/`` by name (:func:`runtime.bindings.robots.resolve`);
``--generated DIR`` is where a robot file's code is; ``--experiment FILE`` the experiment
(default: the paper's setting; its ``robot = "FILE"`` names the robot when ``--robot`` is
not given); ``--plant MODEL`` the plant. :func:`load_setting` resolves them into a
:class:`runtime.setting.robot.Setting` (the experiment scaled to the robot).
:func:`output_folder` is where a command writes by default: its folder for the paper's
robot, ``./<command>/<robot name>`` for another. :func:`print_audit` prints the physics
audit's warnings on the robot file, as every command that runs a robot does (issue 47: the
warnings travel with the robot, not only with `wmr model`).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from modeling import audit
from runtime.bindings.robots import RobotSetup
from runtime.experiment.settings import (
    PLANT_MODELS,
    Experiment,
    ExperimentFileError,
    check_contact,
    load_experiment,
)
from runtime.setting.robot import RobotSourceError, Setting, robot_setting

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


def add_plant_option(parser: argparse.ArgumentParser) -> None:
    """``--plant MODEL``: the experiment's ``[plant] model`` for this run (the generated
    model, or the MuJoCo engine on the robot's MJCF)."""
    parser.add_argument("--plant", dest="plant_model", default=None,
                        metavar="|".join(PLANT_MODELS),
                        help="the plant the robot runs on (default: the experiment's [plant] "
                        "model, else generated; mujoco: the MuJoCo engine on the MJCF `wmr "
                        "mjcf` writes, with the experiment's contact settings)")


def load_setting(args: argparse.Namespace) -> Setting:
    """:func:`robot_setting` of a command's parsed ``--robot``, ``--generated`` and
    ``--experiment`` (``ExperimentFileError`` or ``RobotSourceError``, both ``ValueError``)."""
    exp = load_experiment(getattr(args, "experiment", None))
    model = getattr(args, "plant_model", None)
    if model is not None:
        if model not in PLANT_MODELS:
            raise ExperimentFileError(f"--plant {model!r}: expected one of "
                                      f"{', '.join(PLANT_MODELS)}")
        exp = replace(exp, plant=replace(exp.plant, model=model))
        check_contact(exp, "--plant")
    return loaded_setting(args.robot, args.generated, exp)


def loaded_setting(robot: str | Path | None, generated: Path | None,
                   exp: Experiment) -> Setting:
    """:func:`robot_setting`, its robot file's audit warnings printed (:func:`print_audit`)."""
    setting = robot_setting(robot, generated, exp)
    print_audit(setting.robot)
    return setting


def print_audit(setup: RobotSetup) -> None:
    """The physics audit's warnings on the robot file (``RobotSetup.warnings``: a lumped
    file's own, else those its generated ``robot.py`` declares), on stderr as ``wmr model``
    prints them (``warning: ROBOT: ...``, once per process: through ``modeling.audit``,
    which has already printed a lumped file's when the runtime read it)."""
    audit.report(setup.source, setup.warnings)


def output_folder(setting: Setting, out: Path | None, paper_default: Path,
                  command: str) -> Path:
    """``--out``, else ``paper_default`` for the paper's robot, else ``./<command>/<name>``;
    a plant other than the generated model writes into a subfolder named after it (the
    committed results stay the generated model's)."""
    if out is not None:
        return out
    folder = paper_default if setting.is_paper_robot else Path(command) / setting.robot.name
    model = setting.experiment.plant.model
    return folder if model == "generated" else folder / model


__all__ = ["RobotSourceError", "Setting", "add_experiment_option", "add_plant_option",
           "add_robot_options", "load_setting", "loaded_setting", "output_folder",
           "print_audit", "robot_setting"]
