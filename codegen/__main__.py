"""``wmr model`` (``python -m codegen``): derive robots and generate their code.

    wmr model                    # every shipped robot (modeling/robots/): Drishti at the
                                 # root of the output, others in <out>/<name>/
    wmr model --robot my.toml    # one robot, whatever its kind, in <out>/<name>/ with
                                 # prefix <name>_ (a [lumped]/[physical] file is the
                                 # paper's model with its numbers); --robot again: several
    wmr model --check            # exit 1 with a diff if the output is stale
    wmr model --out DIR          # write to DIR

Each robot file is read once, and its name, prefix and folder come from it
(``modeling.robot_file``; Drishti's own file keeps ``wmr`` and the root). Two robots that
would write the same path (two names with one prefix, or a robot already in ``--out``
under another name) are refused with exit 2 before anything is derived or written
(``codegen.output_plan``).

Where output goes (``--out``'s default): the shipped robots regenerate the package's own
``generated/`` in a source checkout (what ``make model`` does) and ``./generated`` in the
working directory for an installed package; ``--robot`` writes to ``./generated`` in the
working directory, and refuses to write into the shipped ``generated/`` unless ``--out``
names it. Nothing is ever written into site-packages.

The generated code takes the robot's parameters at run time; the robot file only sets the
defaults written into ``<prefix>_robot.h`` / ``robot.py`` and the report.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import time
from pathlib import Path

from codegen.generate import generate_files
from codegen.output_plan import Placed, folder_collision, shared_path
from codegen.progress import to_stderr
from modeling.package_paths import SHIPPED_GENERATED, inside, source_checkout
from modeling.robot_file import (
    RobotFileError,
    RobotSource,
    model_of,
    robot_source,
    shipped_robot_files,
)


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="wmr model",
        description="Derive robots' models and controllers and generate their C, NumPy and "
        "CasADi code.",
    )
    parser.add_argument(
        "--robot",
        type=Path,
        action="append",
        default=None,
        help="a robot TOML file, again for several (default: every robot in "
        "modeling/robots/)",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="do not write; exit 1 and print a diff if generated/ is stale",
    )
    parser.add_argument(
        "--out", type=Path, default=None,
        help="output directory (default: the shipped generated/ in a source checkout, "
        "./generated in the working directory otherwise or with --robot)",
    )  # fmt: skip
    return parser.parse_args(argv)


class OutputError(ValueError):
    """An output folder this command must not write to."""


def output_folder(out: Path | None, robot: Path | None, check: bool) -> Path:
    """Where to write (or, with ``check``, what to compare): see the module docstring."""
    if out is None:
        shipped = robot is None and (check or source_checkout())
        out = SHIPPED_GENERATED if shipped else Path("generated")
        if not check and robot is not None and inside(out, SHIPPED_GENERATED):
            raise OutputError(
                f"{out.resolve()} is the shipped generated/ folder: --robot does not write "
                "there unless --out names it (e.g. --out generated); give another --out"
            )
    if not check:
        if not source_checkout() and inside(out, SHIPPED_GENERATED):
            raise OutputError(f"{out}: the installed package's generated/ is read-only by "
                              "design; give --out DIR")
        if out.exists() and not out.is_dir():
            raise OutputError(f"--out {out}: exists and is not a folder")
    return out


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


def _placed(source: RobotSource) -> Placed:
    return Placed(source.name, source.naming.output_dir, source.where)


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    robots: list[Path] | None = args.robot
    try:
        args.out = output_folder(args.out, robots[0] if robots else None, args.check)
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    paths: list[Path] = robots if robots else list(shipped_robot_files())
    try:  # each file read once; the name, prefix and folder come from it
        sources = [robot_source(path) for path in paths]
        placed = [_placed(source) for source in sources]
    except RobotFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    refusal = folder_collision(placed, args.out)
    if refusal is not None:
        print(f"error: {refusal}", file=sys.stderr)
        return 2
    files: dict[str, bytes] = {}
    produced: list[tuple[Placed, list[str]]] = []
    summary: list[str] = []
    for path, source, place in zip(paths, sources, placed, strict=True):
        start = time.perf_counter()
        progress = to_stderr(path.stem)
        try:
            with progress.step("reading the robot file (kinetic energy, constraints)"):
                model, robot = model_of(source)
        except RobotFileError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        rendered = generate_files(robot, model, progress=progress)
        produced.append((place, list(rendered)))
        files.update(rendered)
        where = args.out / model.output_dir if model.output_dir else args.out
        summary.append(f"{robot.name}: {len(rendered)} files for {where} "
                       f"({time.perf_counter() - start:.1f} s)")
    refusal = shared_path(produced, args.out)
    if refusal is not None:
        print(f"error: {refusal}", file=sys.stderr)
        return 2
    # Regenerating every robot into the shipped generated/ owns all of it (files of removed
    # robots go); otherwise only the top-level entries written are owned, so nothing else in
    # a user's --out folder is ever deleted.
    owns_all = robots is None and inside(args.out, SHIPPED_GENERATED)
    old = _existing(args.out, None if owns_all else {_top(n) for n in files})
    stale = sorted(n for n in set(files) | set(old) if files.get(n) != old.get(n))
    if args.check:
        if not stale:
            print(f"{args.out} is up to date ({len(files)} files)")
            return 0
        for name in stale:
            sys.stdout.write(_diff(name, old.get(name), files.get(name))[:20000])
        print(f"\n{len(stale)} generated file(s) in {args.out} are stale: run `wmr model` "
              "(`make model` in a source checkout)", file=sys.stderr)
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
