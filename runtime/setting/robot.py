"""The robot a command runs and its experiment scaled to it, resolved the same way for
every command.

The robot is a robot file (lumped, physical, or bodies and wheels), a generated folder, or a
robot generated under ``generated/`` by name (:func:`runtime.bindings.robots.resolve`); when
none is named, the experiment's ``robot = "FILE"``, else the paper's. The experiment is then
scaled to the robot (:mod:`runtime.setting.scale`; the identity for the paper's robot) and
its torque limit kept under the traction limit (:mod:`runtime.setting.layout`). The command
line's options that name them are :mod:`runtime.commands.options`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from runtime.bindings.robots import RobotSetup, RobotSourceError, resolve
from runtime.experiment.settings import PAPER_ROBOT, Experiment
from runtime.setting.layout import traction_torque_limit
from runtime.setting.scale import robot_scale, scaled_experiment


@dataclass(frozen=True)
class Setting:
    """A command's robot and its experiment, scaled to it; ``scaling``: one line per scaled
    field (what :func:`runtime.setting.scale.scaled_experiment` did)."""

    robot: RobotSetup
    experiment: Experiment
    scaling: tuple[str, ...]

    @property
    def is_paper_robot(self) -> bool:
        """The paper's own robot with its own numbers (the experiment is not scaled)."""
        return (self.robot.name == PAPER_ROBOT and self.robot.code.is_paper_robot
                and self.robot.nominal == self.robot.code.params)


def robot_setting(robot: str | Path | None, generated: Path | None,
                  exp: Experiment) -> Setting:
    """The robot ``robot``/``generated`` name (else the experiment's ``robot``, else the
    default robot) and ``exp`` scaled to it. ``RobotSourceError`` (a ``ValueError``) with a
    sentence if the robot cannot be run; ``ValueError`` if the experiment cannot be scaled
    to it."""
    named = robot if robot is not None else exp.robot
    setup = resolve(named, generated)
    scaled, lines = scaled_experiment(exp, robot_scale(setup.code, setup.nominal))
    mu = scaled.controller.traction_mu
    if mu > 0:  # the traction-aware torque limit
        limit = traction_torque_limit(setup.code, setup.plant, scaled, mu)
        if limit < scaled.controller.tau_max:
            scaled = replace(scaled, controller=replace(scaled.controller, tau_max=limit))
            lines.append(f"controller.tau_max = {limit:.4g} (traction limit: traction_mu "
                         f"{mu:g} x the lightest driven wheel's load at rest over the payload "
                         "states x its radius)")
    return Setting(setup, scaled, tuple(lines))


__all__ = ["RobotSourceError", "Setting", "robot_setting"]
