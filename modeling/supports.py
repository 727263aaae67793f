"""Where a robot stands: its supports, a stated field of every kind of robot file.

A support is a frictionless contact (a caster or a skid: a normal load, no traction) the
robot stands on besides its wheels. The one load model (``modeling.contact_loads``), the
MJCF exporter (``modeling.mjcf_export``) and the reports take every contact point from
here (:func:`robot_supports`); the generated ``robot.py`` carries a file's stated
supports as ``SUPPORTS`` to the runtime. Numbers only: no SymPy.

TOML (``[lumped]``, ``[physical]`` and ``[[body]]`` files alike)::

    [[support]]                  # any number of them; a file states all or none
    name = "caster"              # unique among the robot's wheels and supports
    body = "platform"            # optional, default the root body (a [lumped]/[physical]
                                 # robot's one body is "platform", frame origin C)
    position = [0.35, 0.0]       # m, where it touches the ground, in the body's frame
    radius = 0.048               # optional, m, > 0 (default: half the smallest wheel radius)

``support = []`` states that the robot has none (its wheels must then stand it up).

**Default** (a file with no ``support`` field, as every file written before the field):
the supports the exporter has always added, :func:`default_supports`: none when the
wheel contacts are not all on one line; else two, on the root body, on the normal to the
wheels' line through its midpoint, at ± max(half the wheels' span, twice the centre of
mass's distance from the line) (the bodies' masses; wheels and payloads left out), radius
half the smallest wheel radius, ``support_front`` (ahead of the line, or left of it) and
``support_rear``. Drishti: ±0.2211 m from the axle midpoint, i.e. at x = +0.1011 and
−0.3411 m from C.

**Checks** (:func:`check_supports`, one line naming the file and field; the load model
adds the last one): every field's type and sign; names unique; a known body; a position
*within reason*: at most :data:`REACH` times the robot's size (the largest distance
between its wheel contacts, body origins and centres of mass) from the nearest of
those points (a support metres from a half-metre robot is a unit slip, mm for m); the
contacts (wheels and supports) not all on one line (the load split is singular: the
robot falls over sideways); and at rest the robot does not tip over its contacts
(``modeling.contact_loads.checked_supports``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from modeling.planar_robot import PlanarRobot, PlanarSupport, Point, body_origins
from modeling.robot_io import RobotFileError

SUPPORT_FIELDS = {"name": "a string", "body": "a body's name",
                  "position": "a pair [x, y] in m", "radius": "m, > 0"}
REQUIRED = ("name", "position")
REACH = 5.0  # a support farther than this many robot sizes is refused (a unit slip)
LINE_TOLERANCE = 1e-6  # of the span: contacts this close to one line are on it


def supports_of(data: Mapping[str, Any], where: str, bodies: tuple[str, ...],
                radius: float) -> tuple[PlanarSupport, ...] | None:
    """The ``[[support]]`` entries of a robot file's TOML (None: the field is absent, the
    default applies); ``bodies``: the robot's body names, the first the root;
    ``radius``: the default radius. ``RobotFileError`` names the file and the field."""
    if "support" not in data:
        return None
    items = data["support"]
    if not isinstance(items, list):
        raise RobotFileError(f"{where}: field 'support' must be an array of tables "
                             "([[support]])")
    out = []
    for i, item in enumerate(items):
        label = f"support[{i}]"
        if not isinstance(item, dict):
            raise RobotFileError(f"{where}: field '{label}' must be a table ([[support]])")
        unknown = sorted(set(item) - set(SUPPORT_FIELDS))
        if unknown:
            raise RobotFileError(f"{where}: unknown field '{label}.{unknown[0]}' "
                                 f"(expected: {', '.join(SUPPORT_FIELDS)})")
        missing = [k for k in REQUIRED if k not in item]
        if missing:
            raise RobotFileError(f"{where}: missing field '{label}.{missing[0]}' "
                                 f"({SUPPORT_FIELDS[missing[0]]})")
        name, body = item["name"], item.get("body", bodies[0])
        for key, value in (("name", name), ("body", body)):
            if not isinstance(value, str) or not value:
                raise RobotFileError(f"{where}: field '{label}.{key}' must be a non-empty "
                                     f"string, got {value!r}")
        if body not in bodies:
            raise RobotFileError(f"{where}: field '{label}.body' names unknown body "
                                 f"'{body}' (the robot's bodies: {', '.join(bodies)})")
        pos = item["position"]
        if not (isinstance(pos, list) and len(pos) == 2 and all(map(_finite, pos))):
            raise RobotFileError(f"{where}: field '{label}.position' must be a pair [x, y] "
                                 f"of finite numbers (m), got {pos!r}")
        r = item.get("radius", radius)
        if not (_finite(r) and r > 0):
            raise RobotFileError(f"{where}: field '{label}.radius' must be a positive "
                                 f"number (m), got {r!r}")
        out.append(PlanarSupport(name, body, (float(pos[0]), float(pos[1])), float(r)))
    return tuple(out)


def _finite(value: Any) -> bool:
    return (not isinstance(value, bool) and isinstance(value, int | float)
            and math.isfinite(value))


def default_radius(radii: list[float]) -> float:
    """A support's radius unless stated: half the smallest wheel radius."""
    return min(radii) / 2 if radii else 0.05


def wheel_points(robot: PlanarRobot) -> dict[str, Point]:
    """Every wheel's contact point (root frame, hitches straight)."""
    origins = body_origins(robot)
    return {w.name: (origins[w.body][0] + w.position[0], origins[w.body][1] + w.position[1])
            for w in robot.wheels}


def _line(points: list[Point]) -> tuple[Point, Point, float, float] | None:
    """(a, b, span, distance of the farthest point off the line a–b) over ``points``:
    a, b the two farthest apart; None if they coincide."""
    a, b = max(((p, q) for p in points for q in points), key=lambda pq: math.dist(*pq))
    span = math.dist(a, b)
    if span == 0:
        return None
    nx, ny = -(b[1] - a[1]) / span, (b[0] - a[0]) / span
    off = max(abs((p[0] - a[0]) * nx + (p[1] - a[1]) * ny) for p in points)
    return a, b, span, off


def default_supports(robot: PlanarRobot) -> tuple[PlanarSupport, ...]:
    """The supports of a robot file that states none (see the module docstring)."""
    line = _line(list(wheel_points(robot).values()))
    if line is None:
        raise ValueError(f"robot '{robot.name}': all its wheels touch the ground at one point")
    a, b, span, off = line
    if off > LINE_TOLERANCE * span:
        return ()
    nx, ny = -(b[1] - a[1]) / span, (b[0] - a[0]) / span
    mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
    origins = body_origins(robot)
    total = sum(body.mass for body in robot.bodies)
    cx = sum(body.mass * (origins[body.name][0] + body.com[0]) for body in robot.bodies) / total
    cy = sum(body.mass * (origins[body.name][1] + body.com[1]) for body in robot.bodies) / total
    reach = max(span / 2, 2 * abs((cx - mid[0]) * nx + (cy - mid[1]) * ny))
    radius = default_radius([w.radius for w in robot.wheels])
    out = []
    for s in (1.0, -1.0):
        x, y = mid[0] + s * reach * nx, mid[1] + s * reach * ny
        name = "support_front" if x > 0 or (x == 0 and y > 0) else "support_rear"
        out.append(PlanarSupport(name, robot.root.name, (x, y), radius))
    return tuple(out)


def robot_supports(robot: PlanarRobot) -> tuple[PlanarSupport, ...]:
    """The robot's supports: its file's stated ones, else :func:`default_supports`."""
    return robot.supports if robot.supports is not None else default_supports(robot)


def support_points(robot: PlanarRobot) -> dict[str, Point]:
    """Every support's ground point in the root frame (hitches straight), by name."""
    origins = body_origins(robot)
    return {s.name: (origins[s.body][0] + s.position[0], origins[s.body][1] + s.position[1])
            for s in robot_supports(robot)}


def check_supports(robot: PlanarRobot, where: str) -> None:
    """``RobotFileError`` (one line naming ``where`` and the field) if the robot's supports
    are not within reason or leave every contact on one line (see the module docstring)."""
    stated = robot.supports or ()
    taken = {w.name: "a wheel" for w in robot.wheels} | {b.name: "a body"
                                                          for b in robot.bodies}
    for i, s in enumerate(stated):
        if s.name in taken or s.name in ("ground",):
            raise RobotFileError(f"{where}: field 'support[{i}].name': '{s.name}' already "
                                 f"names {taken.get(s.name, 'the ground')}")
        taken[s.name] = "a support"
    origins = body_origins(robot)
    wheels = wheel_points(robot)
    anchors = [*wheels.values(), *origins.values(),
               *((origins[b.name][0] + b.com[0], origins[b.name][1] + b.com[1])
                 for b in robot.bodies)]
    size = max(math.dist(p, q) for p in anchors for q in anchors)
    size = max(size, max((w.radius for w in robot.wheels), default=0.0))
    points = support_points(robot) if stated else {}
    for i, s in enumerate(stated):
        far = min(math.dist(points[s.name], p) for p in anchors)
        if far > REACH * size:
            raise RobotFileError(
                f"{where}: field 'support[{i}].position' = [{s.position[0]:g}, "
                f"{s.position[1]:g}] puts '{s.name}' {far:.3g} m from the robot, more than "
                f"{REACH:g} x its size ({size:.3g} m): a unit slip? (m, body frame)")
    contacts = {**wheels, **support_points(robot)}
    line = _line(list(contacts.values()))
    if line is None or line[3] <= LINE_TOLERANCE * line[2]:
        label = "support" if robot.supports is not None else "wheel"
        raise RobotFileError(
            f"{where}: field '{label}': every contact ({', '.join(contacts)}) is on one "
            "line: the robot cannot stand (the load split is singular); state a "
            "[[support]] off that line")
