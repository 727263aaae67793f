"""``wmr mjcf``: a robot file out as a MuJoCo model (MJCF).

    wmr mjcf --robot robot.toml --out robot.xml
    wmr mjcf --robot robot.toml --out robot.xml --friction 0.2 --tyre-width 0.03

The robot file is read and audited as every robot file is (``[lumped]``/``[physical]``:
``modeling.robot_file.load_robot``; bodies and wheels: ``modeling.description``), its
numbers become a :class:`modeling.planar_robot.PlanarRobot` and
:func:`modeling.mjcf_export.mjcf` writes it, with the contact settings given (the
defaults of an experiment's ``[plant]``). The MuJoCo plant of ``wmr reproduce --plant
mujoco`` runs the same MJCF with the experiment's settings and payload bodies. Errors: one
line naming the file or option, exit 2, nothing written.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from modeling.contact_loads import LOAD_MODEL, describe_loads, support_loads
from modeling.mjcf_export import ContactSettings, mjcf
from modeling.planar_robot import PlanarRobot, from_description, from_lumped
from modeling.robot_io import (
    DEFAULT_ROBOT,
    RobotFileError,
    describes_bodies,
    read_robot_file,
    shipped_robot_file,
)


def planar_robot(path: Path) -> PlanarRobot:
    """The robot a robot file describes, in numbers (``RobotFileError`` naming the file
    and field if it is refused)."""
    source = read_robot_file(path)  # read once; each reader below takes what was read
    if describes_bodies(source.data):
        from modeling.description.files import description_of

        return from_description(description_of(source.data, source.where))
    from modeling.robot_file import load_robot

    robot = load_robot(source)
    return from_lumped(robot.name, robot.plant_values(), robot.supports)


def _parse(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="wmr mjcf",
        description="Write a robot file as a MuJoCo model (MJCF) whose planar dynamics are "
        "the derived model's: bodies, hitches, wheels on hinges, wheel-ground contact, "
        "torque motors on the driven wheels.",
    )
    p.add_argument("--robot", type=Path, default=None, metavar="FILE.toml",
                   help="a robot file (lumped, physical, or bodies and wheels; default: the "
                   "paper's Drishti)")
    p.add_argument("--out", type=Path, required=True, metavar="FILE.xml",
                   help="the MJCF file to write")
    p.add_argument("--friction", type=float, default=1.0, metavar="MU",
                   help="wheel-ground friction coefficient (default 1)")
    p.add_argument("--tyre-width", type=float, default=0.0, metavar="M",
                   help="0: point-contact wheels (spheres, default); else capsules this wide")
    p.add_argument("--contact-timeconst", type=float, default=0.005, metavar="S",
                   help="contact softness: MuJoCo's solref time constant (default 0.005 s)")
    p.add_argument("--timestep", type=float, default=0.001, metavar="S",
                   help="integration step (default 0.001 s)")
    p.add_argument("--tau-max", type=float, default=math.inf, metavar="NM",
                   help="the driven wheels' torque limit (default: none)")
    return p.parse_args(argv)


def _check(args: argparse.Namespace) -> str | None:
    if args.out.suffix != ".xml":
        return f"--out {args.out}: an MJCF file ends in .xml"
    if args.out.is_dir():
        return f"--out {args.out}: is a folder; give the MJCF file to write (robot.xml)"
    for label, value, low in (("--friction", args.friction, 0.0),
                              ("--tyre-width", args.tyre_width, 0.0)):
        if not (math.isfinite(value) and value >= low):
            return f"{label} {value}: must be a finite number >= {low:g}"
    for label, value in (("--contact-timeconst", args.contact_timeconst),
                         ("--timestep", args.timestep), ("--tau-max", args.tau_max)):
        if not value > 0 or math.isnan(value):
            return f"{label} {value}: must be positive"
    if args.contact_timeconst < 2 * args.timestep:
        return (f"--contact-timeconst {args.contact_timeconst}: must be at least two steps, "
                f"2 x --timestep = {2 * args.timestep:g} s")
    return None


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    problem = _check(args)
    if problem is not None:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    path = args.robot if args.robot is not None else shipped_robot_file(DEFAULT_ROBOT)
    try:
        robot = planar_robot(path)
        contact = ContactSettings(friction=args.friction, tyre_width=args.tyre_width,
                                  contact_timeconst=args.contact_timeconst,
                                  timestep=args.timestep, tau_max=args.tau_max)
        text = mjcf(robot, contact)
    except (RobotFileError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"error: --out {args.out}: cannot write: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: robot '{robot.name}', {len(robot.bodies)} bodies, "
          f"{len(robot.wheels)} wheels, friction {args.friction:g}")
    print(f"normal loads at rest (N; {LOAD_MODEL}): {describe_loads(support_loads(robot))}")
    return 0
