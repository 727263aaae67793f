"""``python -m runtime.tooling.misra.check``: the generated C under cppcheck's MISRA C:2012
addon (Debian's ``cppcheck``), one precision at a time, against the deviations documented in
``docs/STATIC_CHECKS.md``.

Each precision is its own cppcheck configuration (``-D<PREFIX>_FLOAT32`` or ``-U``): checked
together, cppcheck's cross-translation-unit pass sizes a buffer in one configuration and
indexes it in the other, a false out-of-bounds report. Each precision is checked in one
configuration, the one with no other macro defined (``--max-configs=1``): given only ``-U``
flags cppcheck would enumerate every ``#ifdef`` combination (the compiler's, libm's trig,
one formulation) in double, 4x the float32 run's time for the same findings, and the float32
run (given a ``-D``) never did. The platform is ``unix32`` (32-bit
``int``/``long``/pointers, as on the Cortex-M4). ``example_main.c`` is a demonstration, not
firmware, and is not checked.

The addon reports rule numbers only (the rule texts are licensed with the standard);
``docs/STATIC_CHECKS.md`` names each deviated rule, its category and why the generated code keeps
it. Exit status 1 when a rule is found that the document does not list, or the document
lists one that is no longer found.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from modeling.package_paths import PACKAGE_ROOT, SHIPPED_GENERATED
from runtime.bindings.robots import generated_robots
from runtime.freeze.header import frozen_macro, header_name
from runtime.tooling.firmware.build import CONTROLLERS

DOC = PACKAGE_ROOT / "docs" / "STATIC_CHECKS.md"
ADDON = "misra"
# | 12.1 | advisory | 280 | ... a row of the MISRA deviations table in docs/STATIC_CHECKS.md
_DOC_ROW = re.compile(r"^\| (\d+\.\d+) \| (required|advisory|mandatory) \| (\d+) \|", re.M)


class MisraUnavailable(RuntimeError):
    """cppcheck, or its MISRA addon, is not installed."""


@dataclass(frozen=True)
class Finding:
    file: str
    line: int
    rule: str  # "12.1"; cppcheck's own checks keep their id, e.g. "ctuArrayIndex"
    message: str


def robot_sources(folder: Path) -> tuple[str, list[Path]]:
    """(C prefix, the firmware sources) of a generated robot's ``c/`` folder."""
    sources = sorted(p for p in folder.glob("*.c") if p.name != "example_main.c")
    if not sources:
        raise FileNotFoundError(f"{folder}: no generated C here")
    prefix = sources[0].name.split("_", 1)[0]
    return prefix, sources


def run_cppcheck(folder: Path, float32: bool, frozen: Path | None = None) -> list[Finding]:
    """Every finding of cppcheck (MISRA addon, style and warning checks) on ``folder``;
    with ``frozen`` (a ``<prefix>_<ctrl>_frozen.h`` written by ``wmr freeze``), in the build
    that compiles that configuration in."""
    if shutil.which("cppcheck") is None:
        raise MisraUnavailable("cppcheck not found (apt-get install cppcheck)")
    prefix, sources = robot_sources(folder)
    macro = f"{prefix.upper()}_FLOAT32"
    # The run-time configuration: builds with a configuration compiled in (wmr freeze) need
    # a header of the user's, so cppcheck must not guess them.
    frozen_undefs = [
        f"-D{frozen_macro(prefix, c)}"  # that controller's frozen build
        if frozen is not None and frozen.name == header_name(prefix, c)
        else f"-U{frozen_macro(prefix, c)}"
        for c in CONTROLLERS
    ] + ([f"-I{frozen.parent}"] if frozen is not None else [])
    with tempfile.TemporaryDirectory() as build:
        done = subprocess.run(
            ["cppcheck", f"--addon={ADDON}", "--std=c99", "--platform=unix32",
             "--max-configs=1", "--suppress=toomanyconfigs",
             "--enable=style,warning,portability", "--quiet", "--inline-suppr",
             f"-D{macro}" if float32 else f"-U{macro}", *frozen_undefs, f"-I{folder}",
             f"--cppcheck-build-dir={build}", "--template={file}:{line}:{id}:{message}",
             *map(str, sources)],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
    if "Failed to load addon" in done.stderr or "Bailing out" in done.stderr:
        raise MisraUnavailable(done.stderr.strip().splitlines()[-1])
    findings = []
    for line in done.stderr.splitlines():
        parts = line.split(":", 3)
        if len(parts) == 4 and parts[1].isdigit():
            rule = parts[2].removeprefix("misra-c2012-")
            findings.append(Finding(Path(parts[0]).name, int(parts[1]), rule, parts[3]))
    return findings


@dataclass(frozen=True)
class Deviation:
    rule: str
    category: str
    findings: int  # in Drishti's code, per precision


def documented_rules(doc: Path = DOC) -> dict[str, Deviation]:
    """Rule → its row of the MISRA deviations table in ``docs/STATIC_CHECKS.md``."""
    text = doc.read_text(encoding="utf-8")
    return {m.group(1): Deviation(m.group(1), m.group(2), int(m.group(3)))
            for m in _DOC_ROW.finditer(text)}


def robot_folders() -> list[Path]:
    """The ``c/`` folders of every shipped robot."""
    return [folder / "c" for folder in generated_robots(SHIPPED_GENERATED)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m runtime.tooling.misra.check",
        description="The generated C under cppcheck's MISRA C:2012 addon, against "
        "docs/STATIC_CHECKS.md.",
    )
    parser.add_argument("folders", nargs="*", type=Path,
                        help="generated c/ folders (default: every shipped robot's)")
    args = parser.parse_args(argv)
    found: Counter[str] = Counter()
    try:
        for folder in args.folders or robot_folders():
            for float32 in (False, True):
                hits = run_cppcheck(folder, float32)
                found.update(f.rule for f in hits)
                label = f"{folder} ({'float32' if float32 else 'double'})"
                print(f"{label}: {len(hits)} findings, rules "
                      + ", ".join(f"{r} ×{n}" for r, n in
                                  sorted(Counter(f.rule for f in hits).items())))
    except (MisraUnavailable, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        documented = documented_rules()
    except OSError as exc:
        print(f"error: {DOC}: cannot read the documented deviations ({exc.strerror})",
              file=sys.stderr)
        return 2
    undocumented = sorted(set(found) - set(documented))
    stale = sorted(set(documented) - set(found))
    for rule in undocumented:
        print(f"rule {rule}: found {found[rule]} times, not a documented deviation",
              file=sys.stderr)
    for rule in stale:
        print(f"rule {rule}: documented as a deviation but no longer found", file=sys.stderr)
    return 1 if undocumented or stale else 0


if __name__ == "__main__":
    sys.exit(main())
