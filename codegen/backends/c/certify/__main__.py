"""``python -m codegen.backends.c.certify``: certify every generated C function of Drishti and the
trailer in float32, search for the largest error, and write the results.

    python -m codegen.backends.c.certify                 # both robots; writes the results
    python -m codegen.backends.c.certify --robot trailer --seconds 2 --no-write
    python -m codegen.backends.c.certify --only minimal_tde,tdroc/minimal   # those alone
    python -m codegen.backends.c.certify --only stale      # what the printing changed

Writes ``codegen/certify/results/<robot>.json`` (per function: the box, the certified bound
and the enclosure of each output, the no-overflow verdict, the largest error found and
the time; keyed by a hash of the printed program and the box, so a reader can tell a
stale result) and ``docs/FLOAT32.md``. A separate command rather than part of ``python -m
codegen``: certifying and searching take minutes (derivation ~10 s per robot, then up to
``--seconds`` of subdivision and the mpmath search per function), while ``codegen --check``
must stay under a minute. ``--only`` re-certifies the named functions and steps (and the
steps that read them) and keeps every other stored entry as it is (:mod:`.only`).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from codegen.backends.c.certify.only import (
    Plan,
    Refused,
    merged,
    plan_only,
    split_names,
    step_inputs,
)
from codegen.backends.c.certify.report import certify_and_search, render_markdown
from codegen.backends.c.certify.steps import step_certificates
from codegen.certify.stored import RESULTS_DIR
from codegen.generate import robot_target
from modeling.robot_file import model_of, robot_source
from modeling.robot_io import shipped_robot_file

ROBOTS = ("drishti", "trailer")
DOC = Path(__file__).resolve().parents[4] / "docs" / "FLOAT32.md"


def _stored(robot: str) -> dict[str, Any] | None:
    path = RESULTS_DIR / f"{robot}.json"
    return dict(json.loads(path.read_text())) if path.exists() else None


def _render() -> None:
    stored = [_stored(r) for r in ROBOTS]
    if all(stored):
        DOC.write_text(render_markdown([s for s in stored if s]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m codegen.backends.c.certify",
                                     description="Certify the generated C in float32.")
    parser.add_argument("--robot", action="append", choices=ROBOTS, default=None)
    parser.add_argument("--seconds", type=float, default=4.0,
                        help="subdivision budget per function (default 4)")
    parser.add_argument("--search", type=int, default=150,
                        help="random points per function (default 150)")
    parser.add_argument("--only", action="append", default=None, metavar="NAME[,NAME...]",
                        help="re-certify only these functions and controller steps "
                             "(tdroc/minimal, or tdroc for each formulation; 'stale': every "
                             "function whose stored result is stale), and the steps that "
                             "read them; keep the others' stored results")
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--render-only", action="store_true",
                        help="only rewrite docs/FLOAT32.md from the committed results")
    args = parser.parse_args(argv)
    if args.render_only:
        _render()
        return 0
    robots = args.robot or list(ROBOTS)
    targets = {}
    for name in robots:
        model, robot = model_of(robot_source(shipped_robot_file(name)))
        targets[name] = (robot_target(model, robot), time.perf_counter())
    plans: dict[str, Plan | None] = dict.fromkeys(robots)
    if args.only is not None:
        # every name checked and every stored result it needs found before anything runs
        names = split_names(args.only)
        try:
            for name in robots:
                plans[name] = plan_only(name, targets[name][0], _stored(name), names)
        except Refused as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        unknown = [n for n in names
                   if not any(n in p.known for p in plans.values() if p is not None)]
        if not names or unknown:
            print(f"error: --only: {', '.join(unknown) or 'no name'} is not a function or "
                  f"controller step of {' or '.join(robots)}", file=sys.stderr)
            return 2
        if not any(plans.values()):  # "stale" with every stored result current
            print("nothing to re-certify: every stored result named is current")
            return 0
    for name in robots:
        target, start = targets[name]
        plan = plans[name]
        if plan is not None and not plan:
            continue
        rows = []
        certs: dict[str, Any] = {}
        for row in certify_and_search(target, args.seconds, args.search, certs,
                                      only=plan.functions if plan is not None else None,
                                      derived=plan.derived if plan is not None else None):
            rows.append(row)
            print(f"{name:8s} {row['function']:28s} proved={row['proved']!s:5s} "
                  f"bound={row['bound']:.3g} found={row['found']:.3g} "
                  f"ratio={row['ratio']:.3g} t={row['seconds']:.1f}s", flush=True)
        if plan is not None:
            step_inputs(target, plan, certs)
        steps = []
        for st in step_certificates(target, certs, seconds=args.seconds,
                                    only=plan.steps if plan is not None else None):
            steps.append(asdict(st))
            print(f"{name:8s} step {st.controller}/{st.formulation} ({st.law}): torque bound "
                  f"{st.bound:.3g} N m of tau_max {st.tau_max:g}, proved={st.proved}",
                  flush=True)
        stored = _stored(name)
        result = ({"robot": name, "prefix": target.layout.prefix,
                   "seconds": time.perf_counter() - start, "functions": rows, "steps": steps}
                  if plan is None or stored is None else merged(stored, rows, steps))
        if not args.no_write:
            RESULTS_DIR.mkdir(exist_ok=True)
            (RESULTS_DIR / f"{name}.json").write_text(
                json.dumps(result, indent=1, sort_keys=True) + "\n")
    if not args.no_write:
        _render()
    return 0


if __name__ == "__main__":
    sys.exit(main())
