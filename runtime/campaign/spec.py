"""Campaign files (TOML): what is drawn, how, and what the runs are; every field checked.

    seed = 0                       campaign seed (run i draws from SeedSequence(seed, (i,)))
    runs = 1000                    number of runs (``--runs`` overrides)
    controllers = ["tdc", ...]     run i uses controllers[i % len(controllers)] (default:
                                   every controller generated for the robot in the
                                   formulation, from its generated robot.py)
    formulation = "minimal"        "paper" or "minimal" (one the robot has)
    path = "circle"                "circle" or "lawnmower"
    duration = 30.0                s of path per run
    chunk = 25                     runs per Dask task
    experiment = "FILE.toml"       base experiment (relative to the campaign file; default:
                                   the paper's setting), scaled to the robot
    diverged_error = 0.5           m: a run whose position error exceeds it has diverged
    chatter_limit = 0.8            RMS(Δτ)/RMS(τ) over the second half above which a run is
                                   a sampled-data limit cycle (unstable), see runner

    [vary."controller.eps"]        one table per drawn parameter, named section.field of the
    min = 0.005                    experiment (controller, plant, sensing) or robot.KEY (the
    max = 0.5                      simulated robot's parameter; the controllers keep the
    log = true                     nominal value). One of: spread = s (base × (1 ± s),
                                   uniform), min/max (uniform, log-uniform with log = true),
                                   choices = [...]; step = d rounds to multiples of d.

    [map]                          the stability map: x must be controller.eps, y one of
    x = "controller.eps"           controller.h/k1/k2/q_pos/q_vel; grid = points of y where
    y = "controller.h"             the boundary is predicted
    grid = 7

Unknown keys, wrong types and out-of-range values are rejected with one line naming the field,
as :mod:`runtime.experiment.settings` does for experiment files.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from runtime.experiment.physical import (
    SECTION as PHYSICAL_SECTION,
)
from runtime.experiment.physical import (
    PhysicalUncertainty,
    PhysicalUncertaintyError,
    parse_physical,
)
from runtime.experiment.settings import (
    ControllerSettings,
    Experiment,
    ExperimentFileError,
    PathSettings,
    PlantSettings,
    SensingSettings,
    check_number,
    load_experiment,
    parse_experiment,
)

FORMULATIONS = ("paper", "minimal")
PATHS = ("circle", "lawnmower")
SECTIONS: dict[str, type] = {
    "controller": ControllerSettings,
    "plant": PlantSettings,
    "sensing": SensingSettings,
}
MAP_Y = ("controller.h", "controller.k1", "controller.k2", "controller.q_pos",
         "controller.q_vel")
MAX_RUNS = 100_000_000

Value = float | int | str


class CampaignSpecError(ValueError):
    """A campaign file that cannot be run; the message names the field."""


@dataclass(frozen=True)
class Distribution:
    """How one parameter is drawn (see the module docstring)."""

    spread: float | None = None
    low: float | None = None
    high: float | None = None
    log: bool = False
    choices: tuple[Value, ...] = ()
    step: float | None = None

    def bounds(self, base: float) -> tuple[float, float]:
        """The smallest and largest value a draw can give around ``base``."""
        if self.spread is not None:
            return base * (1 - self.spread), base * (1 + self.spread)
        if self.choices:
            nums = [float(c) for c in self.choices if not isinstance(c, str)]
            return (min(nums), max(nums)) if nums else (math.nan, math.nan)
        assert self.low is not None and self.high is not None
        return self.low, self.high

    def as_dict(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class Campaign:
    """A checked campaign: the base experiment, what is drawn, and the run settings."""

    seed: int = 0
    runs: int = 1000
    controllers: tuple[str, ...] = ()  # () until resolved for a robot: all in the formulation
    formulation: str = "minimal"
    path: str = "circle"
    duration: float = 30.0
    chunk: int = 25
    diverged_error: float = 0.5
    chatter_limit: float = 0.8
    vary: tuple[tuple[str, Distribution], ...] = ()
    map_x: str = "controller.eps"
    map_y: str = "controller.h"
    map_grid: int = 7
    experiment: Experiment = field(default_factory=Experiment)
    robot: str | None = None  # --robot (a file or folder, absolute path), None: Drishti
    robot_sha256: str | None = None
    generated: str | None = None  # --generated (absolute path)
    source: str = "<default campaign>"

    def identity(self) -> dict[str, Any]:
        """Everything a run's result depends on (not ``runs``, ``chunk`` or where the file
        was): two campaigns with the same identity give the same run i."""
        exp = asdict(self.experiment)
        exp.pop("source")
        exp.pop("robot")
        if not exp["physical"]["entries"]:
            exp.pop("physical")  # digests of campaigns without it unchanged
        return {
            "seed": self.seed,
            "controllers": list(self.controllers),
            "formulation": self.formulation,
            "path": self.path,
            "duration": self.duration,
            "diverged_error": self.diverged_error,
            "chatter_limit": self.chatter_limit,
            "vary": {name: d.as_dict() for name, d in self.vary},
            "experiment": exp,
            "robot_sha256": self.robot_sha256,
        }

    def digest(self) -> str:
        text = json.dumps(self.identity(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def to_payload(self) -> dict[str, Any]:
        """A JSON-able form that :func:`from_payload` turns back into this campaign (what is
        sent to the workers and recorded in the output folder)."""
        data = self.identity()
        data.update(runs=self.runs, chunk=self.chunk, map_x=self.map_x, map_y=self.map_y,
                    map_grid=self.map_grid, robot=self.robot, generated=self.generated,
                    source=self.source)
        return data


def from_payload(data: dict[str, Any]) -> Campaign:
    """The inverse of :meth:`Campaign.to_payload`."""
    e = data["experiment"]
    exp = Experiment(
        controller=ControllerSettings(**e["controller"]),
        plant=PlantSettings(**e["plant"]),
        sensing=SensingSettings(**e["sensing"]),
        paths=PathSettings(**e["paths"]),
        physical=PhysicalUncertainty.from_data(e.get("physical")),
    )
    vary = tuple(
        (name, Distribution(**{**d, "choices": tuple(d["choices"])}))
        for name, d in data["vary"].items()
    )
    return Campaign(
        seed=data["seed"], runs=data["runs"], controllers=tuple(data["controllers"]),
        formulation=data["formulation"], path=data["path"], duration=data["duration"],
        chunk=data["chunk"], diverged_error=data["diverged_error"],
        chatter_limit=data["chatter_limit"], vary=vary, map_x=data["map_x"],
        map_y=data["map_y"], map_grid=data["map_grid"], experiment=exp, robot=data["robot"],
        robot_sha256=data["robot_sha256"], generated=data.get("generated"),
        source=data["source"],
    )  # fmt: skip


# ----------------------------------------------------------------------------- checking


def _number(where: str, label: str, value: Any, *, integer: bool = False,
            positive: bool = False, low: float | None = None,
            high: float | None = None) -> float:
    return check_number(where, label, value, integer=integer, positive=positive, low=low,
                        high=high, error=CampaignSpecError)


def field_type(name: str) -> str:
    """'int', 'float' or 'str': the type of a drawn parameter ``section.field``/``robot.K``."""
    section, _, key = name.partition(".")
    if section in ("robot", "physical"):
        return "float"
    types = {f.name: f.type for f in fields(SECTIONS[section])}
    return {"int": "int", "str": "str"}.get(str(types[key]), "float")


def _distribution(where: str, name: str, data: Any, robot_keys: tuple[str, ...],
                  physical_keys: tuple[str, ...] = ()) -> Distribution:
    label = f'vary."{name}"'
    section, _, key = name.partition(".")
    if section == "physical":
        if key not in physical_keys:
            have = ", ".join("physical." + k for k in physical_keys) or "none: a [lumped] robot"
            raise CampaignSpecError(f"{where}: unknown parameter '{label}' (the robot's "
                                    f"physical quantities are {have})")
    elif section == "robot":
        if key not in robot_keys:
            raise CampaignSpecError(f"{where}: unknown parameter '{label}' (the robot's are "
                                    f"{', '.join('robot.' + k for k in robot_keys)})")
    elif section not in SECTIONS or key not in {f.name for f in fields(SECTIONS[section])}:
        known = [f"{s}.{f.name}" for s, c in SECTIONS.items() for f in fields(c)]
        raise CampaignSpecError(f"{where}: unknown parameter '{label}' (expected robot.KEY or "
                                f"one of {', '.join(known)})")
    if not isinstance(data, dict):
        raise CampaignSpecError(f"{where}: '{label}' must be a table (spread, min/max, choices)")
    allowed = {"spread", "min", "max", "log", "choices", "step"}
    for k in data:
        if k not in allowed:
            raise CampaignSpecError(f"{where}: unknown field '{label}.{k}' (expected one of "
                                    f"{', '.join(sorted(allowed))})")
    kinds = [k for k in ("spread", "min", "choices") if k in data]
    if ("min" in data) != ("max" in data):
        raise CampaignSpecError(f"{where}: '{label}' needs both min and max")
    if len(kinds) != 1:
        raise CampaignSpecError(f"{where}: '{label}' needs exactly one of spread, min/max, "
                                "choices")
    kind = field_type(name)
    if kind == "str" and "choices" not in data:
        raise CampaignSpecError(f"{where}: '{label}' is a name: draw it with choices = [...]")
    log = data.get("log", False)
    if not isinstance(log, bool):
        raise CampaignSpecError(f"{where}: field '{label}.log' must be true or false")
    if log and "min" not in data:
        raise CampaignSpecError(f"{where}: field '{label}.log' applies to min/max only")
    step = data.get("step")
    if step is not None:
        step = _number(where, f"{label}.step", step, positive=True)
    if "choices" in data:
        choices = data["choices"]
        if not isinstance(choices, list) or not choices:
            raise CampaignSpecError(f"{where}: field '{label}.choices' must be a non-empty list")
        for c in choices:
            if kind == "str" and not isinstance(c, str):
                raise CampaignSpecError(f"{where}: field '{label}.choices' must hold names, "
                                        f"got {c!r}")
            if kind != "str":
                _number(where, f"{label}.choices", c, integer=kind == "int")
        return Distribution(choices=tuple(choices), step=step)
    if "spread" in data:
        s = _number(where, f"{label}.spread", data["spread"], positive=True)
        if s >= 1:
            raise CampaignSpecError(f"{where}: field '{label}.spread' must be below 1, got {s}")
        return Distribution(spread=s, step=step)
    lo = _number(where, f"{label}.min", data["min"])
    hi = _number(where, f"{label}.max", data["max"])
    if not lo < hi:
        raise CampaignSpecError(f"{where}: '{label}' needs min < max, got {lo:g} and {hi:g}")
    if log and lo <= 0:
        raise CampaignSpecError(f"{where}: '{label}' with log = true needs min > 0, got {lo:g}")
    return Distribution(low=lo, high=hi, log=log, step=step)


def _toml_value(v: Any) -> str:
    return json.dumps(v) if isinstance(v, str) else repr(v)


def experiment_text(exp: Experiment) -> str:
    """An experiment as TOML (every field of its sections), for re-checking."""
    parts = []
    for section in ("controller", "plant", "sensing", "paths"):
        parts.append(f"[{section}]")
        for k, v in asdict(getattr(exp, section)).items():
            parts.append(f"{k} = {_toml_value(v)}")
    return "\n".join(parts) + "\n"


def with_values(exp: Experiment, values: dict[str, Value]) -> Experiment:
    """``exp`` with experiment fields ``section.field`` set (robot.* keys ignored)."""
    changed: dict[str, dict[str, Value]] = {}
    for name, v in values.items():
        section, _, key = name.partition(".")
        if section in SECTIONS:
            changed.setdefault(section, {})[key] = v
    return replace(exp, **{s: replace(getattr(exp, s), **kv) for s, kv in changed.items()})


def check_ranges(where: str, vary: tuple[tuple[str, Distribution], ...], exp: Experiment,
                 robot: dict[str, float]) -> None:
    """Each drawn parameter's extreme values must make a valid experiment (the rules of
    :mod:`runtime.experiment.settings`) or a positive robot parameter."""
    for name, dist in vary:
        section, _, key = name.partition(".")
        label = f'vary."{name}"'
        if section == "physical":
            continue  # a physical range is checked where the robot resolves it
        if section == "robot":
            lo, hi = dist.bounds(robot[key])
            if robot[key] > 0 and not lo > 0:  # a mass or inertia (a first moment may be < 0)
                raise CampaignSpecError(f"{where}: '{label}' can draw {lo:g}; a positive "
                                        "robot parameter must stay positive")
            continue
        if dist.choices:
            extremes: list[Value] = list(dist.choices)
        else:
            lo, hi = dist.bounds(float(getattr(getattr(exp, section), key)))
            extremes = [lo, hi]
            if field_type(name) == "int":
                extremes = [round(lo), round(hi)]
        for v in extremes:
            try:
                parse_experiment(experiment_text(with_values(exp, {name: v})), "<draw>")
            except ExperimentFileError as exc:
                reason = str(exc).removeprefix("<draw>: ")
                raise CampaignSpecError(f"{where}: '{label}' can draw {v!r}, which is not a "
                                        f"valid experiment: {reason}") from None


# ----------------------------------------------------------------------------- parsing

_TOP = {"seed", "runs", "controllers", "formulation", "path", "duration", "chunk", "experiment",
        "diverged_error", "chatter_limit", "vary", "map", PHYSICAL_SECTION}
# A robot's physical box from a declaration (runtime.bindings.physical_bounds.box_of).
PhysicalBox = Callable[[PhysicalUncertainty], dict[str, tuple[float, float]]]


def generated_controllers(formulation: str) -> tuple[str, ...]:
    """The default robot's controllers generated in ``formulation`` (its robot.py)."""
    from runtime.bindings.generated import load_robot_code

    return tuple(c.name for _, c in load_robot_code("").runs((formulation,)))


def parse_campaign(text: str, where: str, robot: dict[str, float],
                   base_dir: Path | None = None,
                   available: Callable[[str], Sequence[str]] = generated_controllers,
                   physical_box: PhysicalBox | None = None) -> Campaign:
    """A campaign from TOML text; ``robot`` is the nominal robot (its keys are the
    ``robot.*`` parameters one may draw), ``available(formulation)`` the controllers
    generated for it in a formulation (default: the paper robot's). The robot itself is
    attached by the caller."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CampaignSpecError(f"{where}: not valid TOML: {exc}") from None
    for k in data:
        if k not in _TOP:
            raise CampaignSpecError(f"{where}: unknown field '{k}' (expected one of "
                                    f"{', '.join(sorted(_TOP))})")
    c = Campaign()
    seed = int(_number(where, "seed", data.get("seed", c.seed), integer=True, low=0))
    runs = int(_number(where, "runs", data.get("runs", c.runs), integer=True, low=1,
                       high=MAX_RUNS))
    chunk = int(_number(where, "chunk", data.get("chunk", c.chunk), integer=True, low=1,
                        high=10_000))
    duration = _number(where, "duration", data.get("duration", c.duration), positive=True)
    diverged = _number(where, "diverged_error", data.get("diverged_error", c.diverged_error),
                       positive=True)
    chatter = _number(where, "chatter_limit", data.get("chatter_limit", c.chatter_limit),
                      positive=True)
    for key, allowed in (("formulation", FORMULATIONS), ("path", PATHS)):
        value = data.get(key, getattr(c, key))
        if value not in allowed:
            raise CampaignSpecError(f"{where}: field '{key}' must be one of "
                                    f"{', '.join(allowed)}, got {value!r}")
    names = tuple(available(data.get("formulation", c.formulation)))
    controllers = data.get("controllers", list(names))
    if (not isinstance(controllers, list) or not controllers
            or any(x not in names for x in controllers)
            or len(set(controllers)) != len(controllers)):
        raise CampaignSpecError(f"{where}: field 'controllers' must be a list of distinct names "
                                f"of {', '.join(names)} (the controllers generated in the "
                                f"{data.get('formulation', c.formulation)} formulation), got "
                                f"{controllers!r}")
    exp = Experiment()
    if "experiment" in data:
        if not isinstance(data["experiment"], str) or not data["experiment"].strip():
            raise CampaignSpecError(f"{where}: field 'experiment' must be the path of an "
                                    "experiment file")
        path = (base_dir or Path(".")) / data["experiment"]
        try:
            exp = load_experiment(path)
        except ExperimentFileError as exc:
            raise CampaignSpecError(f"{where}: field 'experiment': {exc}") from None
    vary_data = data.get("vary", {})
    if not isinstance(vary_data, dict):
        raise CampaignSpecError(f"{where}: [vary] must be a table of parameter tables")
    physical_keys = tuple(physical_box(PhysicalUncertainty())) if physical_box else ()
    vary_list = [(name, _distribution(where, name, d, tuple(robot), physical_keys))
                 for name, d in vary_data.items()]
    if PHYSICAL_SECTION in data or exp.physical:
        # the declaration is ROC's box and, for every quantity it gives a range, the draws
        try:
            decl = (parse_physical(data[PHYSICAL_SECTION], where) if PHYSICAL_SECTION in data
                    else exp.physical)
            if physical_box is None:
                raise PhysicalUncertaintyError(f"{where}: [{PHYSICAL_SECTION}] needs a "
                                               "bodies-and-wheels robot")
            box = physical_box(decl)
        except PhysicalUncertaintyError as exc:
            raise CampaignSpecError(str(exc) if str(exc).startswith(where)
                                    else f"{where}: {exc}") from None
        exp = replace(exp, physical=decl)
        drawn = {n for n, _ in vary_list}
        vary_list += [(f"physical.{k}", Distribution(low=lo, high=hi))
                      for k, (lo, hi) in box.items()
                      if hi > lo and f"physical.{k}" not in drawn]
    if any(n.startswith("physical.") for n, _ in vary_list) and any(
            n.startswith("robot.") for n, _ in vary_list):
        raise CampaignSpecError(f"{where}: draw either the robot's physical quantities "
                                "(physical.*) or its model parameters (robot.*), not both")
    vary = tuple(sorted(vary_list))
    map_data = data.get("map", {})
    if not isinstance(map_data, dict):
        raise CampaignSpecError(f"{where}: [map] must be a table")
    for k in map_data:
        if k not in ("x", "y", "grid"):
            raise CampaignSpecError(f"{where}: unknown field 'map.{k}' (expected x, y, grid)")
    map_x = map_data.get("x", c.map_x)
    if map_x != "controller.eps":
        raise CampaignSpecError(f"{where}: field 'map.x' must be \"controller.eps\" (the "
                                f"analysis predicts a boundary in ε), got {map_x!r}")
    map_y = map_data.get("y", c.map_y)
    if map_y not in MAP_Y:
        raise CampaignSpecError(f"{where}: field 'map.y' must be one of {', '.join(MAP_Y)}, "
                                f"got {map_y!r}")
    grid = int(_number(where, "map.grid", map_data.get("grid", c.map_grid), integer=True,
                       low=2, high=100))
    check_ranges(where, vary, exp, robot)
    return Campaign(seed=seed, runs=runs, controllers=tuple(controllers),
                    formulation=data.get("formulation", c.formulation),
                    path=data.get("path", c.path), duration=duration, chunk=chunk,
                    diverged_error=diverged, chatter_limit=chatter, vary=vary, map_x=map_x,
                    map_y=map_y, map_grid=grid, experiment=exp, source=where)


def load_campaign(path: Path, robot: dict[str, float],
                  available: Callable[[str], Sequence[str]] = generated_controllers,
                  physical_box: PhysicalBox | None = None) -> Campaign:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CampaignSpecError(f"{path}: campaign file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CampaignSpecError(f"{path}: cannot read campaign file: {exc}") from None
    return parse_campaign(text, str(path), robot, path.parent, available, physical_box)


def default_campaign(robot: dict[str, float], inertial: tuple[str, ...], track: float,
                     exp: Experiment | None = None,
                     controllers: Sequence[str] | None = None) -> Campaign:
    """The paper's setting with every parameter drawn within ±30 %: the simulated robot's
    inertial parameters, payload masses, friction, gains, h (in steps of 5 ms) and ε; the
    payloads anywhere in a square of ±0.36 track (Drishti: ±0.15 m) about C; wheel rates
    sensed at the sample instant or averaged over the sample."""
    spread = Distribution(spread=0.3)
    box = 0.36 * track
    pos = Distribution(low=-box, high=box)
    vary: dict[str, Distribution] = {f"robot.{k}": spread for k in inertial if robot[k] != 0}
    vary.update({f"plant.{k}": spread for k in ("viscous", "coulomb", "fixed_payload",
                                                "extra_payload")})
    vary.update({f"plant.{k}": pos for k in ("fixed_payload_x", "fixed_payload_y",
                                            "extra_payload_x", "extra_payload_y")})
    vary.update({"controller.k1": spread, "controller.k2": spread, "controller.eps": spread,
                 "controller.h": Distribution(spread=0.3, step=0.005),
                 "sensing.velocity": Distribution(choices=("sample-instant", "encoder-average"))})
    base = exp or Experiment()
    items = tuple(sorted(vary.items()))
    check_ranges("<default campaign>", items, base, robot)
    names = tuple(controllers) if controllers is not None else generated_controllers(
        Campaign().formulation)
    return Campaign(vary=items, experiment=base, controllers=names)
