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
from dataclasses import dataclass, replace
from pathlib import Path

from runtime.bindings.robots import RobotSetup, RobotSourceError, resolve
from runtime.experiment.scale import robot_scale, scaled_experiment
from runtime.experiment.settings import (
    PAPER_ROBOT,
    PLANT_MODELS,
    Experiment,
    ExperimentFileError,
    check_contact,
    load_experiment,
)

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
    mu = scaled.controller.traction_mu
    if mu > 0:  # the traction-aware torque limit
        from runtime.mujoco.layout import traction_torque_limit

        limit = traction_torque_limit(setup.code, setup.plant, scaled, mu)
        if limit < scaled.controller.tau_max:
            scaled = replace(scaled, controller=replace(scaled.controller, tau_max=limit))
            lines.append(f"controller.tau_max = {limit:.4g} (traction limit: traction_mu "
                         f"{mu:g} x the lightest driven wheel's load at rest over the payload "
                         "states x its radius)")
    return Setting(setup, scaled, tuple(lines))


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
    return robot_setting(args.robot, args.generated, exp)


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
           "add_robot_options",
           "load_setting", "output_folder", "robot_setting"]
