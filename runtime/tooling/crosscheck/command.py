"""``python -m runtime crosscheck``: run every comparison for every robot and print the
report (``--out FILE`` also writes it).

``--robot ROBOT`` (repeatable; default: every robot found under generated/) selects the
robots, resolved as every command resolves ``--robot`` (a robot file, a generated folder or
a generated robot's name; ``--generated DIR`` where a robot file's code is). Exit status 1
if any deviation exceeds its tolerance. ``--perturb
IMPL:KEY=FACTOR`` multiplies parameter KEY of the (nominal and plant) parameters passed to
IMPL (python, c64, c32, casadi) by FACTOR, in every selected robot that has KEY: the check
must then fail (used by the tests). ``python`` is compared only with the hand-written
equations; against a robot's generated NumPy (the reference there) it is not perturbed.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from runtime.commands.output_folder import OutputFolderError, writable_file
from runtime.tooling.crosscheck.deviation import IMPLS
from runtime.tooling.crosscheck.generated_check import generated_crosscheck
from runtime.tooling.crosscheck.handwritten_check import applies_to, handwritten_crosscheck
from runtime.tooling.crosscheck.report import CrosscheckReport, RobotReport
from runtime.tooling.crosscheck.targets import Target, all_targets, resolve

__all__ = ["crosscheck", "generated_crosscheck", "handwritten_crosscheck", "main",
           "parse_perturb"]


def _keys(targets: Sequence[Target]) -> set[str]:
    return {k for t in targets for k in (*t.code.params, *t.code.plant_defaults)}


def parse_perturb(items: Sequence[str], targets: Sequence[Target]) -> dict[str, dict[str, float]]:
    keys = _keys(targets)
    out: dict[str, dict[str, float]] = {}
    for item in items:
        try:
            impl, rest = item.split(":", 1)
            key, factor = rest.split("=", 1)
        except ValueError:
            raise SystemExit(f"--perturb {item!r}: expected IMPL:KEY=FACTOR") from None
        if impl not in IMPLS or key not in keys:
            raise SystemExit(f"--perturb {item!r}: IMPL in {IMPLS}, KEY a parameter of the "
                             f"robots checked ({', '.join(sorted(keys))})")
        out.setdefault(impl, {})[key] = float(factor)
    return out


def crosscheck(
    targets: Sequence[Target] | None = None,
    seed: int = 20170316,
    quick: bool = False,
    perturb: Mapping[str, Mapping[str, float]] | None = None,
) -> CrosscheckReport:
    """Every comparison for each target (default: every generated robot)."""
    t0 = time.perf_counter()
    targets = all_targets() if targets is None else list(targets)
    pert = {impl: dict(v) for impl, v in (perturb or {}).items()}
    robots = []
    for target in targets:
        hand = handwritten_crosscheck(target, seed, quick, pert) if applies_to(target) else None
        gen = generated_crosscheck(target, seed, quick, pert)
        robots.append(RobotReport(target.name, target.label, hand, gen, target.warnings))
    return CrosscheckReport(robots, time.perf_counter() - t0, pert)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="wmr crosscheck",
        description="Compare the generated Python, C (double, float32) and CasADi code of every "
        "robot: with the hand-written equations (runtime/tooling/witness) where they exist, "
        "and C and CasADi with the generated NumPy for every robot.",
    )
    parser.add_argument(
        "--robot", action="append", default=[], metavar="ROBOT",
        help="a robot file, a generated folder or a generated robot's name (repeatable; "
        "default: all under generated/)",
    )  # fmt: skip
    parser.add_argument("--generated", type=Path, default=None, metavar="DIR",
                        help="where a robot file's generated code is")
    parser.add_argument("--seed", type=int, default=20170316)
    parser.add_argument("--quick", action="store_true", help="fewer samples and shorter runs")
    parser.add_argument(
        "--perturb", action="append", default=[], metavar="IMPL:KEY=FACTOR",
        help="scale parameter KEY passed to IMPL (python, c64, c32, casadi); the check must fail",
    )  # fmt: skip
    parser.add_argument("--out", type=Path, help="also write the report to this file")
    args = parser.parse_args(argv)
    if args.out is not None:  # before the minute of work, not after it
        try:
            writable_file(args.out)
        except OutputFolderError as exc:
            raise SystemExit(str(exc)) from None
    targets = ([resolve(r, args.generated) for r in args.robot] if args.robot
               else all_targets())
    report = crosscheck(targets, args.seed, args.quick, parse_perturb(args.perturb, targets))
    text = report.render()
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n")
    return 1 if report.failing() else 0


if __name__ == "__main__":
    sys.exit(main())
