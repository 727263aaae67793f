"""``python -m runtime crosscheck``: run every comparison and print the report.

Exit status 1 if any deviation exceeds its tolerance. ``--perturb IMPL:KEY=FACTOR``
multiplies parameter KEY of the (nominal) parameters passed to IMPL (python, c64, c32,
casadi) by FACTOR: the check must then fail (used by the tests).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import numpy as np

from runtime.handwritten import controllers as hc
from runtime.handwritten import model as hw
from runtime.tooling.crosscheck.controller_checks import check_controllers
from runtime.tooling.crosscheck.deviation import IMPLS
from runtime.tooling.crosscheck.inputs import Sequence_, closed_loop, model_samples, random_sequence
from runtime.tooling.crosscheck.model_checks import check_models, self_checks
from runtime.tooling.crosscheck.report import Report


def parse_perturb(items: Sequence[str]) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for item in items:
        try:
            impl, rest = item.split(":", 1)
            key, factor = rest.split("=", 1)
        except ValueError:
            raise SystemExit(f"--perturb {item!r}: expected IMPL:KEY=FACTOR") from None
        if impl not in IMPLS or key not in hw.PARAM_KEYS:
            raise SystemExit(f"--perturb {item!r}: IMPL in {IMPLS}, KEY in {hw.PARAM_KEYS}")
        out.setdefault(impl, {})[key] = float(factor)
    return out


def crosscheck(
    seed: int = 20170316, quick: bool = False, perturb: dict[str, dict[str, float]] | None = None
) -> Report:
    """Run every comparison; ``quick``: fewer samples and shorter sequences."""
    perturb = perturb or {}
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    n_samples = 40 if quick else 200
    loop_seconds, rand_steps = (3.0, 15) if quick else (6.0, 40)
    samples = model_samples(rng, n_samples)
    checks = self_checks(samples)
    model_rows = check_models(samples, perturb)
    sequences: list[tuple[hc.Kind, Sequence_]] = []
    for kind in hc.KINDS:
        for form in hc.FORMULATIONS:
            sequences.append((kind, closed_loop(kind, form, loop_seconds)))
            for near in (True, False):
                sequences.append((kind, random_sequence(rng, kind, form, near, rand_steps)))
    ctrl_rows, cover = check_controllers(sequences, perturb)
    return Report(
        checks, model_rows, ctrl_rows, cover, n_samples, len(sequences),
        sum(len(s.q) for _, s in sequences), time.perf_counter() - t0, perturb,
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m runtime crosscheck",
        description="Compare the generated Python, C (double, float32) and CasADi code with "
        "the hand-written equations (runtime/handwritten).",
    )
    parser.add_argument("--seed", type=int, default=20170316)
    parser.add_argument("--quick", action="store_true", help="fewer samples and shorter runs")
    parser.add_argument(
        "--perturb", action="append", default=[], metavar="IMPL:KEY=FACTOR",
        help="scale parameter KEY passed to IMPL (python, c64, c32, casadi); the check must fail",
    )  # fmt: skip
    args = parser.parse_args(argv)
    report = crosscheck(args.seed, args.quick, parse_perturb(args.perturb))
    print(report.render())
    return 1 if report.failing() else 0
if __name__ == "__main__":
    sys.exit(main())
