"""``python -m runtime.tooling.mutation [--only NAME ...] [--out FILE]``: apply every mutant
of :mod:`runtime.tooling.mutation.mutants` (or the named ones) to a copy of this project,
run the tests meant to catch it, and print (and with ``--out`` write) the Markdown report.
Progress, one line a mutant, goes to stderr. Exit 1 if any mutant is uncaught or stale."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from modeling.package_paths import PACKAGE_ROOT
from runtime.tooling.mutation.engine import UNCAUGHT, Result, report, run_all, stale
from runtime.tooling.mutation.mutants import MUTANTS


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m runtime.tooling.mutation",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", metavar="NAME", help="run these mutants only")
    parser.add_argument("--out", type=Path, help="also write the report to this file")
    args = parser.parse_args(argv)
    names = {m.name for m in MUTANTS}
    unknown = sorted(set(args.only or ()) - names)
    if unknown:
        print(f"mutation: no mutant named {', '.join(unknown)} (see mutants.py)",
              file=sys.stderr)
        return 2
    if args.out is not None and not args.out.parent.is_dir():
        print(f"mutation: --out {args.out}: its folder does not exist", file=sys.stderr)
        return 2
    chosen = [m for m in MUTANTS if not args.only or m.name in args.only]
    for line in stale(PACKAGE_ROOT, chosen):
        print(f"stale: {line}", file=sys.stderr)

    def progress(k: int, r: Result) -> None:
        print(f"[{k + 1}/{len(chosen)}] {r.mutant.name}: {r.verdict} ({r.seconds:.0f} s) "
              f"{r.detail}", file=sys.stderr, flush=True)

    results = run_all(PACKAGE_ROOT, chosen, progress)
    text = report(results)
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
    return 1 if any(r.verdict in (UNCAUGHT, "stale") for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
