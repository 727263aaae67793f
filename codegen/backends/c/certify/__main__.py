"""``python -m codegen.backends.c.certify``: certify every generated C function of Drishti and the
trailer in float32, search for the largest error, and write the results.

    python -m codegen.backends.c.certify                 # both robots; writes the results
    python -m codegen.backends.c.certify --robot trailer --seconds 2 --no-write

Writes ``codegen/certify/results/<robot>.json`` (per function: the box, the certified bound
and the enclosure of each output, the no-overflow verdict, the largest error found and
the time; keyed by a hash of the printed program and the box, so a reader can tell a
stale result) and ``docs/FLOAT32.md``. A separate command rather than part of ``python -m
codegen``: certifying and searching take minutes (derivation ~10 s per robot, then up to
``--seconds`` of subdivision and the mpmath search per function), while ``codegen --check``
must stay under a minute.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from codegen.backends.c.certify.report import certify_and_search, render_markdown
from codegen.backends.c.certify.steps import step_certificates
from codegen.certify.stored import RESULTS_DIR
from codegen.generate import robot_target
from modeling.robot_file import model_of, robot_source
from modeling.robot_io import shipped_robot_file

ROBOTS = ("drishti", "trailer")
DOC = Path(__file__).resolve().parents[4] / "docs" / "FLOAT32.md"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m codegen.backends.c.certify",
                                     description="Certify the generated C in float32.")
    parser.add_argument("--robot", action="append", choices=ROBOTS, default=None)
    parser.add_argument("--seconds", type=float, default=4.0,
                        help="subdivision budget per function (default 4)")
    parser.add_argument("--search", type=int, default=150,
                        help="random points per function (default 150)")
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--render-only", action="store_true",
                        help="only rewrite docs/FLOAT32.md from the committed results")
    args = parser.parse_args(argv)
    if args.render_only:
        DOC.write_text(render_markdown([json.loads((RESULTS_DIR / f"{r}.json").read_text())
                                        for r in ROBOTS]))
        return 0
    results = {}
    for name in args.robot or ROBOTS:
        start = time.perf_counter()
        model, robot = model_of(robot_source(shipped_robot_file(name)))
        target = robot_target(model, robot)
        rows = []
        certs: dict[str, Any] = {}
        for row in certify_and_search(target, args.seconds, args.search, certs):
            rows.append(row)
            print(f"{name:8s} {row['function']:28s} proved={row['proved']!s:5s} "
                  f"bound={row['bound']:.3g} found={row['found']:.3g} "
                  f"ratio={row['ratio']:.3g} t={row['seconds']:.1f}s", flush=True)
        steps = []
        for st in step_certificates(target, certs, seconds=args.seconds):
            steps.append(asdict(st))
            print(f"{name:8s} step {st.controller}/{st.formulation} ({st.law}): torque bound "
                  f"{st.bound:.3g} N m of tau_max {st.tau_max:g}, proved={st.proved}",
                  flush=True)
        results[name] = {"robot": name, "prefix": target.layout.prefix,
                         "seconds": time.perf_counter() - start,
                         "functions": rows, "steps": steps}
        if not args.no_write:
            RESULTS_DIR.mkdir(exist_ok=True)
            (RESULTS_DIR / f"{name}.json").write_text(
                json.dumps(results[name], indent=1, sort_keys=True) + "\n")
    if not args.no_write and set(results) == set(ROBOTS):
        DOC.write_text(render_markdown([results[r] for r in ROBOTS]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
