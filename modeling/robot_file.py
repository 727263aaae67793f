"""Robot description files (TOML): the lumped parameters of the model, or the physical
ones from which ``modeling.robots.drishti.model.lumped_relations`` derives them.

Two forms are accepted::

    name = "drishti"
    [lumped]                      # the paper's parameters, used directly
    m = 36.0  I = 5.72  K = 0.34  Iw = 0.07  r = 0.096  b = 0.414  d = 0.12

    name = "my-robot"
    [physical]                    # platform + two wheels (modeling.robots.drishti.model)
    m_P = 30.0  I_P = 2.0  x_P = 0.0  y_P = 0.0  m_w = 3.0  Iw = 0.07  Im = 0.04
    r = 0.096  b = 0.414  d = 0.12

Every error names the file and the offending field; nothing is half-loaded.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from modeling.robot_model import RobotModel

LUMPED_FIELDS: dict[str, str] = {
    "m": "total mass [kg]",
    "I": "yaw inertia about C [kg m^2]",
    "K": "first moment of mass behind C [kg m]",
    "Iw": "wheel spin inertia [kg m^2]",
    "r": "wheel radius [m]",
    "b": "track width [m]",
    "d": "distance of C ahead of the axle midpoint [m]",
}
PHYSICAL_FIELDS: dict[str, str] = {
    "m_P": "platform mass [kg]",
    "I_P": "platform yaw inertia about its centre of mass [kg m^2]",
    "x_P": "platform centre of mass ahead of the axle midpoint [m]",
    "y_P": "platform centre of mass left of the axis [m]",
    "m_w": "wheel mass [kg]",
    "Iw": "wheel spin inertia [kg m^2]",
    "Im": "wheel inertia about a vertical diameter [kg m^2]",
    "r": "wheel radius [m]",
    "b": "track width [m]",
    "d": "distance of C ahead of the axle midpoint [m]",
}
# Must be > 0; K (a first moment) and the offsets may have either sign; d ≥ 0 by the
# paper's convention (C ahead of the axle), and d = 0 is allowed (C on the axle).
POSITIVE = {"m", "I", "Iw", "r", "b", "m_P", "I_P", "m_w"}
NON_NEGATIVE = {"d", "Im"}


class RobotFileError(ValueError):
    """A robot file that cannot describe a robot; the message names the field."""


@dataclass(frozen=True)
class Robot:
    """A robot's lumped parameters (keys m, I, K, Iw, r, b, d) and, when the file gave
    them, its physical parameters and the lateral first moment K_lat they imply."""

    name: str
    lumped: dict[str, float]
    physical: dict[str, float] | None = None
    K_lat: float = 0.0
    source: str = "<built-in>"
    digest: str = ""  # text_digest of the file it was read from ("" if none)

    def plant_values(self) -> dict[str, float]:
        """The numbers the file gives the simulated robot: the lumped parameters and the
        lateral first moment its physical parameters imply (the plant-only K_lat)."""
        return {**self.lumped, "K_lat": self.K_lat}


DEFAULT_ROBOT = "drishti"


def _number(where: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotFileError(f"{where}: field '{key}' must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise RobotFileError(f"{where}: field '{key}' must be finite, got {value!r}")
    if key in POSITIVE and x <= 0:
        raise RobotFileError(f"{where}: field '{key}' must be positive, got {value!r}")
    if key in NON_NEGATIVE and x < 0:
        raise RobotFileError(f"{where}: field '{key}' must be non-negative, got {value!r}")
    return x


def _table(where: str, section: str, data: Any, fields: dict[str, str]) -> dict[str, float]:
    if not isinstance(data, dict):
        raise RobotFileError(f"{where}: [{section}] must be a table")
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field '{unknown[0]}' in [{section}] (expected: {', '.join(fields)})"
        )
    missing = [k for k in fields if k not in data]
    if missing:
        raise RobotFileError(
            f"{where}: missing field '{missing[0]}' in [{section}] ({fields[missing[0]]})"
        )
    return {k: _checked(where, section, k, data[k]) for k in fields}


def _checked(where: str, section: str, key: str, value: Any) -> float:
    try:
        return _number(where, key, value)
    except RobotFileError as exc:
        raise RobotFileError(
            str(exc).replace(f"field '{key}'", f"field '{section}.{key}'")
        ) from None


def lumped_from_physical(phys: dict[str, float]) -> tuple[dict[str, float], float]:
    """m, I, K (and K_lat) from the physical parameters via the derived lumped relations
    (SymPy is imported here, not at module level: a [lumped] file is read without it)."""
    import sympy as sp

    from modeling.robots.drishti import model as wmr

    rel = wmr.lumped_relations(wmr.physical_bodies())
    values = {
        wmr.m_P: phys["m_P"],
        wmr.I_P: phys["I_P"],
        wmr.x_P: phys["x_P"],
        wmr.y_P: phys["y_P"],
        wmr.m_w: phys["m_w"],
        wmr.I_m: phys["Im"],
        wmr.b: phys["b"],
        wmr.d: phys["d"],
    }
    ev = {str(k): float(sp.N(v.subs(values))) for k, v in rel.items()}
    lumped = {
        "m": ev["m"],
        "I": ev["I"],
        "K": ev["K"],
        "Iw": phys["Iw"],
        "r": phys["r"],
        "b": phys["b"],
        "d": phys["d"],
    }
    return lumped, ev["K_lat"]


def check_lumped(where: str, p: dict[str, float], k_lat: float = 0.0) -> None:
    """The kinetic energy must be positive definite: m > 0 and I > (K² + K_lat²)/m."""
    if p["I"] <= (p["K"] ** 2 + k_lat**2) / p["m"]:
        raise RobotFileError(
            f"{where}: field 'I' = {p['I']} must exceed (K² + K_lat²)/m = "
            f"{(p['K'] ** 2 + k_lat**2) / p['m']:.6g}: otherwise the kinetic energy is not "
            "positive definite (I is the inertia about C, at least the centre-of-mass term)"
        )


def text_digest(text: str) -> str:
    """SHA-256 of a robot file's text (as read, UTF-8): generated ``robot.py`` records it,
    and the runtime refuses code generated from another version of the file."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def parse_robot(text: str, where: str = "<string>") -> Robot:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{where}: not valid TOML: {exc}") from None
    unknown = sorted(set(data) - {"name", "lumped", "physical"})
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field '{unknown[0]}' (expected name and [lumped] or [physical])"
        )
    name = data.get("name", Path(where).stem)
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{where}: field 'name' must be a non-empty string")
    if ("lumped" in data) == ("physical" in data):
        raise RobotFileError(f"{where}: give exactly one of the tables [lumped] or [physical]")
    if "lumped" in data:
        lumped = _table(where, "lumped", data["lumped"], LUMPED_FIELDS)
        check_lumped(where, lumped)
        return Robot(name, lumped, source=where, digest=text_digest(text))
    phys = _table(where, "physical", data["physical"], PHYSICAL_FIELDS)
    lumped, k_lat = lumped_from_physical(phys)
    check_lumped(where, lumped, k_lat)
    return Robot(name, lumped, phys, k_lat, source=where, digest=text_digest(text))


def load_robot(path: str | Path | None = None) -> Robot:
    """Load a robot file; ``None`` loads the packaged default, Drishti."""
    if path is None:
        where = f"robots/{DEFAULT_ROBOT}/{DEFAULT_ROBOT}.toml"
        return parse_robot(resources.files("modeling").joinpath(where).read_text(),
                           f"modeling/{where}")
    return parse_robot(read_robot_text(path), str(path))


def read_robot_text(path: str | Path) -> str:
    """A robot file's text; ``RobotFileError`` naming the file if it cannot be read."""
    p = Path(path)
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotFileError(f"{p}: robot file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotFileError(f"{p}: cannot read robot file: {exc}") from None


# ---------------------------------------------------------------------------------------
# Any robot file: the lumped/physical form of the paper's robot, or bodies and wheels
# ---------------------------------------------------------------------------------------
ROBOTS_DIR = Path(__file__).resolve().parent / "robots"


def shipped_robot_file(name: str) -> Path:
    """The robot file of a shipped robot: ``modeling/robots/<name>/<name>.toml``."""
    return ROBOTS_DIR / name / f"{name}.toml"


def describes_bodies(data: Mapping[str, Any]) -> bool:
    """Whether a parsed robot file describes bodies, joints and wheels (``[[body]]``)."""
    return "body" in data


def is_description(path: str | Path) -> bool:
    """Whether a robot file describes bodies, joints and wheels (``[[body]]`` tables)."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False  # load_robot reports the error with the file's name
    return describes_bodies(data)


def load_robot_model(path: str | Path | None = None) -> tuple[RobotModel, Robot]:
    """The generic model of a robot file and its parameter values.

    A file with ``[[body]]`` tables is derived by ``modeling.description`` (run-time
    parameters: base inertial parameters and wheel radii); a ``[lumped]``/``[physical]``
    file is the paper's differential drive with those numbers. ``Robot.lumped`` holds the
    values of the model's ``params``. Raises ``RobotFileError`` naming the problem.
    """
    from modeling.robot_model import described_model

    if path is not None and Path(path).resolve() == shipped_robot_file(DEFAULT_ROBOT):
        path = None  # the packaged default: its source reads modeling/robots/drishti/...
    if path is not None and is_description(path):
        model = described_model(str(Path(path).resolve()), source_label(path))
        digest = text_digest(Path(path).read_text(encoding="utf-8"))
        return model, Robot(model.name, model.param_values(), source=model.source,
                            digest=digest)
    from modeling.robots.drishti import model as wmr

    robot = load_robot(path)
    return wmr.robot_model(), robot


def source_label(path: str | Path) -> str:
    """A robot file's name for generated preambles: relative to the repository when it is
    inside it (generated output must not depend on where the clone lives)."""
    p = Path(path).resolve()
    try:
        return p.relative_to(ROBOTS_DIR.parent.parent).as_posix()
    except ValueError:
        return Path(path).as_posix()


def shipped_robot_files() -> list[Path]:
    """The robots ``make model`` generates: every ``modeling/robots/<name>/<name>.toml``,
    the default (Drishti) first."""
    files = [shipped_robot_file(d.name) for d in ROBOTS_DIR.iterdir() if d.is_dir()]
    return sorted((f for f in files if f.is_file()),
                  key=lambda p: (p.stem != DEFAULT_ROBOT, p.stem))
