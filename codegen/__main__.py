"""``python -m codegen``: derive the model and regenerate everything in ``generated/``.

    python -m codegen                    # Drishti (modeling/robots/drishti.toml)
    python -m codegen --robot my.toml    # another robot
    python -m codegen --check            # exit 1 with a diff if generated/ is stale
    python -m codegen --out DIR          # write elsewhere (tests, experiments)

The generated code takes the robot's parameters at run time; the robot file only sets the
defaults written into ``wmr_robot.h`` / ``robot.py`` and the report.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import time
from pathlib import Path

from codegen.generate import GENERATED_DIR, generate_files
from modeling.robot_file import RobotFileError, load_robot


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m codegen",
        description="Derive the WMR model and controllers and regenerate generated/.",
    )
    parser.add_argument(
        "--robot",
        type=Path,
        default=None,
        help="robot TOML file (default: the packaged drishti.toml)",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="do not write; exit 1 and print a diff if generated/ is stale",
    )
    parser.add_argument(
        "--out", type=Path, default=GENERATED_DIR, help="output directory (default: generated/)"
    )
    return parser.parse_args(argv)


def _existing(out: Path) -> dict[str, bytes]:
    if not out.is_dir():
        return {}
    return {
        p.relative_to(out).as_posix(): p.read_bytes()
        for p in sorted(out.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }


def _diff(name: str, old: bytes | None, new: bytes | None) -> str:
    try:
        a = (old or b"").decode().splitlines(keepends=True)
        b = (new or b"").decode().splitlines(keepends=True)
    except UnicodeDecodeError:
        return f"Binary file {name} differs\n"
    return "".join(difflib.unified_diff(a, b, f"generated/{name}", f"regenerated/{name}"))


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    start = time.perf_counter()
    try:
        robot = load_robot(args.robot)
    except RobotFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    files = generate_files(robot)
    elapsed = time.perf_counter() - start
    old = _existing(args.out)
    stale = sorted(n for n in set(files) | set(old) if files.get(n) != old.get(n))
    if args.check:
        if not stale:
            print(f"generated/ is up to date ({len(files)} files)")
            return 0
        for name in stale:
            sys.stdout.write(_diff(name, old.get(name), files.get(name))[:20000])
        print(f"\n{len(stale)} generated file(s) are stale: run `make model`", file=sys.stderr)
        return 1
    for name in stale:
        path = args.out / name
        if name not in files:
            path.unlink()
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(files[name])
    print(f"{robot.name}: {len(files)} files in {args.out} ({len(stale)} changed), {elapsed:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
