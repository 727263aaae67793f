"""A robot's generated NumPy-only modules, and what its generated ``robot.py`` declares.

``generated/python`` (the default robot, the paper's) is importable as a package for the
code written around it; ``load_robot_code(dir)`` loads any robot's ``generated/<dir>/python``
(or any folder's) and describes it from its ``robot.py``: sizes, actuated coordinates,
parameter defaults and the controllers of the registry (``CONTROLLERS``, as
:class:`ControllerInfo`), so that nothing here knows a robot or a controller.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from modeling.package_paths import SHIPPED_GENERATED
from modeling.planar_robot import PlanarSupport

GENERATED = SHIPPED_GENERATED  # the generated package Python finds (see package_paths)
ROOT = GENERATED.parent
if str(ROOT) not in sys.path:  # so that `generated` imports from that same folder
    sys.path.insert(0, str(ROOT))

# The default robot's modules, for the runtime written around the paper's robot: imported
# on first use, so that a generated/ holding some other robot fails with a sentence, not an
# ImportError deep in an unrelated command.
_DEFAULT_MODULES = ("controllers", "robot", "wmr_laws", "wmr_model", "wmr_plant")

if TYPE_CHECKING:  # the names __getattr__ provides, for the type checker and linters
    from generated.python import controllers, robot, wmr_laws, wmr_model, wmr_plant

__all__ = ["ConfigFieldInfo", "ControllerInfo", "RobotCode", "controllers", "load_robot_code",
           "robot", "wmr_laws", "wmr_model", "wmr_plant"]

Array = NDArray[np.float64]


def __getattr__(name: str) -> ModuleType:
    if name not in _DEFAULT_MODULES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        robot_mod = importlib.import_module("generated.python.robot")
        prefix = getattr(robot_mod, "PREFIX", "wmr")
    except ImportError as exc:
        raise ImportError(f"{GENERATED / 'python'}: no generated default robot ({exc}); "
                          "run `make model`") from None
    if not getattr(robot_mod, "PAPER_ROBOT", False):  # declared, not read off the prefix
        raise ImportError(
            f"{GENERATED / 'python'} holds robot '{robot_mod.NAME}' (prefix {prefix}_), not "
            "the paper's differential drive (wmr_) this command is written for; regenerate "
            "it with `make model`, or use `--robot FILE` for other robots"
        )
    module = importlib.import_module(f"generated.python.{name}")
    globals()[name] = module
    return module


@dataclass(frozen=True)
class ConfigFieldInfo:
    """One field of ``<prefix>_<ctrl>_config_t`` after ``nominal``, as the registry exports
    it: ``kind`` real, int or vector (one real per coordinate of q); ``source`` where the
    configuration builder takes its value (:mod:`runtime.bindings.config`)."""

    name: str
    kind: str
    unit: str
    source: str


@dataclass(frozen=True)
class ControllerInfo:
    """One controller of a robot's generated code, from its ``robot.py`` ``CONTROLLERS``
    (``modeling.controllers.REGISTRY``): labels, the features its step has (``tde``: Ĥ1 of
    (17); ``switching``: a switching term with boundary layer ε; ``window``: TDROC's k̂ of
    (25); ``bounds``: α, φ in the configuration; ``adaptive``: a gain adapted in the
    state), its configuration fields and the formulations it is generated for."""

    name: str
    label: str
    title: str
    equations: str
    tde: bool
    switching: bool
    window: bool
    bounds: bool
    adaptive: bool
    fields: tuple[ConfigFieldInfo, ...]
    formulations: tuple[str, ...]

    @classmethod
    def from_export(cls, entry: dict[str, Any], robot_formulations: tuple[str, ...]
                    ) -> ControllerInfo:
        forms = tuple(entry.get("formulations", robot_formulations))
        return cls(
            name=str(entry["name"]), label=str(entry["label"]), title=str(entry["title"]),
            equations=str(entry["equations"]), tde=bool(entry["tde"]),
            switching=bool(entry["switching"]), window=bool(entry["window"]),
            bounds=bool(entry["bounds"]), adaptive=bool(entry["adaptive"]),
            fields=tuple(ConfigFieldInfo(*f) for f in entry["fields"]),
            formulations=tuple(f for f in robot_formulations if f in forms),
        )

    def field_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.fields)


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
    folder: Path = GENERATED  # holds python/, c/, casadi/

    @property
    def c_dir(self) -> Path:
        return self.folder / "c"

    @property
    def paper_model(self) -> bool:
        """The paper's differential drive (lumped parameters, layout from them), as its
        ``robot.py`` declares (``PAPER_MODEL``; code generated before it: False)."""
        return bool(getattr(self.robot, "PAPER_MODEL", False))

    @property
    def is_paper_robot(self) -> bool:
        """The paper's own robot, as its ``robot.py`` declares (``PAPER_ROBOT``)."""
        return bool(getattr(self.robot, "PAPER_ROBOT", False))

    @property
    def supports(self) -> tuple[PlanarSupport, ...] | None:
        """The supports the robot file states (``SUPPORTS`` of its ``robot.py``,
        ``modeling.supports``); None: not stated (or code generated before the field),
        the default rule derives them from the layout."""
        stated = getattr(self.robot, "SUPPORTS", None)
        return None if stated is None else tuple(PlanarSupport.from_data(s) for s in stated)

    @property
    def audit_warnings(self) -> tuple[str, ...]:
        """The physics audit's warnings on the robot file this code was generated from, as
        its ``robot.py`` declares (``AUDIT_WARNINGS``; code generated before it: none)."""
        return tuple(getattr(self.robot, "AUDIT_WARNINGS", ()))

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

    @property
    def formulations(self) -> tuple[str, ...]:
        """The formulations generated for this robot (paper first where it has one)."""
        return tuple(self.robot.FORMULATIONS)

    @cached_property
    def controller_infos(self) -> tuple[ControllerInfo, ...]:
        """The controllers generated for this robot, in the registry's order."""
        return tuple(ControllerInfo.from_export(entry, self.formulations)
                     for entry in self.robot.CONTROLLERS)

    @property
    def controller_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.controller_infos)

    def controller(self, name: str) -> ControllerInfo:
        """The controller ``name``; ``ValueError`` naming those generated otherwise."""
        for info in self.controller_infos:
            if info.name == name:
                return info
        raise ValueError(f"unknown controller {name!r} for robot '{self.name}' (expected one "
                         f"of {', '.join(self.controller_names)})")

    def runs(self, formulations: tuple[str, ...] | None = None
             ) -> tuple[tuple[str, ControllerInfo], ...]:
        """(formulation, controller) for each formulation (default: all) and each controller
        generated in it: a controller not generated in a formulation is not run there."""
        forms = self.formulations if formulations is None else formulations
        return tuple((f, c) for f in forms for c in self.controller_infos
                     if f in c.formulations)

    def controller_class(self, name: str) -> Any:
        """The NumPy mirror's class of controller ``name`` (named by its label)."""
        return getattr(self.controllers, self.controller(name).label)

    def velocities(self, q: Array, eta: Array, params: dict[str, float]) -> Array:
        """q̇ = S(q) η: the driven-wheel rates, and the rates the constraints give every
        other coordinate (the generated kinematics (31))."""
        qdot = np.empty(self.nq)
        qdot[list(self.actuated)] = eta
        qdot[list(self.dependent)] = self.model.kinematics(q, eta, params)
        return qdot


@cache
def load_robot_code(output_dir: str | Path = "") -> RobotCode:
    """The generated Python of a robot: ``generated/<output_dir>`` for a name ("" = the
    default robot), or any folder holding ``python/robot.py`` for a ``Path`` (the output of
    ``python -m codegen --out DIR``). Raises ``FileNotFoundError`` naming the folder if no
    robot was generated there."""
    if isinstance(output_dir, Path):
        return _load_from_folder(output_dir.resolve() / "python")
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
        importlib.import_module(f"{package}.controllers"), robot_mod, folder.parent,
    )


def _load_from_folder(folder: Path) -> RobotCode:
    """The generated ``python/`` folder imported as a package of its own, under a name
    unique to the folder (its modules import each other relatively)."""
    if not (folder / "robot.py").is_file() or not (folder / "__init__.py").is_file():
        raise FileNotFoundError(f"{folder}: no generated robot here (python/robot.py)")
    tag = "_generated_" + hashlib.sha256(str(folder).encode()).hexdigest()[:12]
    if tag not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            tag, folder / "__init__.py", submodule_search_locations=[str(folder)])
        assert spec is not None and spec.loader is not None
        package = importlib.util.module_from_spec(spec)
        sys.modules[tag] = package
        spec.loader.exec_module(package)
    robot_mod = importlib.import_module(f"{tag}.robot")
    prefix = robot_mod.PREFIX

    def module(stem: str) -> ModuleType:
        return importlib.import_module(f"{tag}.{stem}")

    return RobotCode(robot_mod.NAME, prefix, module(f"{prefix}_model"), module(f"{prefix}_laws"),
                     module(f"{prefix}_plant"), module("controllers"), robot_mod, folder.parent)
