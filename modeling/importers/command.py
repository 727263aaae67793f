"""``wmr import``: a URDF (or xacro) or MJCF file in, a bodies-and-wheels robot file out.

    wmr import robot.urdf --out robot.toml
    wmr import robot.urdf.xacro --out robot.toml --package-path ~/ws/src --xacro-arg prefix:=
    wmr import robot.xml --out robot.toml --driven wheel_left_joint,wheel_right_joint
    wmr import robot.urdf --out robot.toml --rotor-inertia 1.2e-6 --gear-ratio 50

The output is checked as every robot file is (``modeling.description``: schema, then the
physics audit of ``modeling.audit``) before it is written; it is written to a temporary
file beside ``--out`` and renamed (with the permissions the umask gives a new file), so a
refused import writes nothing and an accepted one never leaves half a file. Errors: one
line naming the file, the element and the value, exit 2. Warnings (the importer's findings
and the audit's) are printed and kept in the file's
``[import]`` table, from which MODEL.md lists them.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from modeling.importers import import_robot
from modeling.importers.planar import Options
from modeling.robot_io import RobotFileError


def _parse(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="wmr import",
        description="Import a URDF (ROS) or MJCF (MuJoCo) robot as a bodies-and-wheels robot "
        "file, with a comment per value saying where it came from, and audit its physics.",
    )
    p.add_argument("file", type=Path, help="the .urdf, .urdf.xacro/.xacro (expanded with the "
                   "ROS xacro package) or MJCF .xml file")
    p.add_argument("--out", type=Path, required=True, help="the robot file to write (.toml)")
    p.add_argument("--driven", default="", metavar="NAME,NAME",
                   help="the driven wheels (joint, link or wheel names), overriding the "
                   "file's transmissions or actuators")
    p.add_argument("--package-path", action="append", type=Path, default=[], metavar="DIR",
                   help="a folder holding the ROS packages that $(find PKG) names (repeat "
                   "for several; default: the folders above and beside the file's)")
    p.add_argument("--xacro-arg", action="append", default=[], metavar="NAME:=VALUE",
                   help="a value for one of the xacro file's <xacro:arg>s (repeatable)")
    p.add_argument("--name", default="", help="the robot's name (default: the file's)")
    p.add_argument("--rotor-inertia", type=float, default=None, metavar="KG_M2",
                   help="each driven wheel's motor rotor inertia J_r (kg m^2, datasheet)")
    p.add_argument("--gear-ratio", type=float, default=None, metavar="N",
                   help="each driven wheel's gear ratio N (motor turns per wheel turn)")
    return p.parse_args(argv)


def _check_args(args: argparse.Namespace) -> str | None:
    if args.out.is_dir():
        return f"--out {args.out}: is a folder; give the robot file to write (robot.toml)"
    if args.out.suffix != ".toml":
        return f"--out {args.out}: a robot file ends in .toml"
    if args.rotor_inertia is not None and not args.rotor_inertia >= 0:
        return f"--rotor-inertia {args.rotor_inertia}: must be a non-negative number (kg m^2)"
    if args.gear_ratio is not None and not args.gear_ratio > 0:
        return f"--gear-ratio {args.gear_ratio}: must be a positive number"
    if args.name and not args.name.strip():
        return "--name: must not be blank"
    for folder in args.package_path:
        if not folder.is_dir():
            return f"--package-path {folder}: not a folder"
    for arg in args.xacro_arg:
        if ":=" not in arg or not arg.split(":=", 1)[0].strip():
            return f"--xacro-arg {arg}: give NAME:=VALUE"
    return None


def write_atomically(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file in the same folder, renamed; the
    file gets a new file's permissions under the umask (mkstemp's own are 0600)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    problem = _check_args(args)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    options = Options(
        driven=tuple(d for d in args.driven.split(",") if d.strip()),
        name=args.name.strip(),
        rotor_inertia=args.rotor_inertia,
        gear_ratio=args.gear_ratio,
    )
    mappings = dict(arg.split(":=", 1) for arg in args.xacro_arg)
    try:
        imported = import_robot(args.file, options, where=str(args.out),
                                package_path=args.package_path, xacro_args=mappings)
    except RobotFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        write_atomically(args.out, imported.text)
    except OSError as exc:
        print(f"error: --out {args.out}: cannot write it: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    d = imported.description
    driven = [w.name for w in d.wheels if w.driven]
    print(f"{args.file} ({imported.robot.fmt}) -> {args.out}: robot '{d.name}', "
          f"{len(d.bodies)} bod{'y' if len(d.bodies) == 1 else 'ies'}, {len(d.wheels)} wheels "
          f"({len(driven)} driven: {', '.join(driven)}), {len(d.warnings)} warning(s)")
    print(f"next: wmr model --robot {args.out} --out DIR")
    return 0


if __name__ == "__main__":
    sys.exit(main())
