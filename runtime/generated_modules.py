"""The generated NumPy-only modules, importable from anywhere.

``generated/python`` (the default robot, the paper's) is imported as a package at import
time for the runtime written around it; ``load_robot_code(dir)`` loads any robot's
``generated/<dir>/python`` and describes it from its generated ``robot.py`` (sizes,
actuated coordinates, parameter defaults), so that nothing here knows a robot.
"""

from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
if str(ROOT) not in sys.path:  # generated/ is not an installed package by design
    sys.path.insert(0, str(ROOT))

from generated.python import controllers, robot, wmr_laws, wmr_model, wmr_plant  # noqa: E402

__all__ = ["RobotCode", "controllers", "load_robot_code", "robot", "wmr_laws", "wmr_model",
           "wmr_plant"]


@dataclass(frozen=True)
class RobotCode:
    """One robot's generated Python: its modules and what its ``robot.py`` declares."""

    name: str
    prefix: str
    model: ModuleType
    laws: ModuleType
    plant: ModuleType
    controllers: ModuleType
    robot: ModuleType

    @property
    def nq(self) -> int:
        return int(self.robot.NQ)

    @property
    def nu(self) -> int:
        return int(self.robot.NU)

    @property
    def actuated(self) -> tuple[int, ...]:
        return tuple(self.robot.ACTUATED)

    @property
    def dependent(self) -> tuple[int, ...]:
        return tuple(i for i in range(self.nq) if i not in self.actuated)

    @property
    def params(self) -> dict[str, float]:
        return dict(self.robot.PARAMS)

    @property
    def plant_defaults(self) -> dict[str, float]:
        return dict(self.robot.PLANT_PARAMS)

    def controller_class(self, name: str) -> Any:
        classes = {"tdc": "TDC", "tdroc": "TDROC", "roc": "ROC", "asmc": "ASMC"}
        if name not in classes:
            raise ValueError(f"unknown controller {name!r} (expected one of {', '.join(classes)})")
        return getattr(self.controllers, classes[name])


@cache
def load_robot_code(output_dir: str = "") -> RobotCode:
    """The generated Python of the robot in ``generated/<output_dir>`` ("" = the default
    robot). Raises ``FileNotFoundError`` naming the folder if it was not generated."""
    folder = GENERATED / output_dir / "python" if output_dir else GENERATED / "python"
    if not (folder / "robot.py").is_file():
        raise FileNotFoundError(f"{folder}: no generated robot here (run `make model`)")
    package = "generated." + (f"{output_dir}.python" if output_dir else "python")
    robot_mod = importlib.import_module(f"{package}.robot")
    prefix = robot_mod.PREFIX

    def module(suffix: str) -> ModuleType:
        return importlib.import_module(f"{package}.{prefix}_{suffix}")

    return RobotCode(
        robot_mod.NAME, prefix, module("model"), module("laws"), module("plant"),
        importlib.import_module(f"{package}.controllers"), robot_mod,
    )
