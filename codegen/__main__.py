"""``python -m codegen``: derive every shipped robot and regenerate ``generated/``.

    python -m codegen                    # every robot in modeling/robots/ (Drishti at the
                                         # root of generated/, others in generated/<name>/)
    python -m codegen --robot my.toml    # one robot (a [lumped]/[physical] file replaces
                                         # the default robot's numbers; a [[body]] file
                                         # goes to generated/<name>/)
    python -m codegen --check            # exit 1 with a diff if generated/ is stale
    python -m codegen --out DIR          # write elsewhere (tests, experiments)

The generated code takes the robot's parameters at run time; the robot file only sets the
defaults written into ``<prefix>_robot.h`` / ``robot.py`` and the report.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import time
from pathlib import Path

from codegen.generate import GENERATED_DIR, generate_files
from modeling.robot_file import RobotFileError, load_robot_model, shipped_robot_files


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m codegen",
        description="Derive the robots' models and controllers and regenerate generated/.",
    )
    parser.add_argument(
        "--robot",
        type=Path,
        default=None,
        help="one robot TOML file (default: every robot in modeling/robots/)",
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


def _top(name: str) -> str:
    return name.split("/", 1)[0]


def _existing(out: Path, owned: set[str] | None) -> dict[str, bytes]:
    """Files under ``out``; with ``owned``, only those whose top-level entry (a folder such
    as ``c`` or ``trailer``, or a file such as ``MODEL.md``) the regenerated robot writes."""
    if not out.is_dir():
        return {}
    found = {
        p.relative_to(out).as_posix(): p.read_bytes()
        for p in sorted(out.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }
    if owned is None:
        return found
    return {k: v for k, v in found.items() if _top(k) in owned}


def _diff(name: str, old: bytes | None, new: bytes | None) -> str:
    try:
        a = (old or b"").decode().splitlines(keepends=True)
        b = (new or b"").decode().splitlines(keepends=True)
    except UnicodeDecodeError:
        return f"Binary file {name} differs\n"
    return "".join(difflib.unified_diff(a, b, f"generated/{name}", f"regenerated/{name}"))


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    paths: list[Path | None] = [args.robot] if args.robot is not None else list(
        shipped_robot_files())
    files: dict[str, bytes] = {}
    summary: list[str] = []
    for path in paths:
        start = time.perf_counter()
        try:
            model, robot = load_robot_model(path)
        except RobotFileError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        produced = generate_files(robot, model)
        files.update(produced)
        where = f"generated/{model.output_dir}" if model.output_dir else "generated/"
        summary.append(f"{robot.name}: {len(produced)} files for {where} "
                       f"({time.perf_counter() - start:.1f} s)")
    # Regenerating every robot owns all of generated/ (files of removed robots go);
    # one robot owns only its own folders.
    old = _existing(args.out, {_top(n) for n in files} if args.robot is not None else None)
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
    for line in summary:
        print(line)
    print(f"{len(files)} files in {args.out} ({len(stale)} changed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
