"""The jitter budget table (issue 46) → the marked section of ``docs/STABILITY.md``.

For each robot (every shipped robot, ``modeling.robot_io.shipped_robot_files``, and
tests/robots/small_robot.toml) and every controller and formulation the analysis takes, at
the experiment's setting (sample-instant rates, the setting's switching gain, the paper's
experiment scaled to the robot): the delay jitter proved
(:func:`runtime.stability.jitter.budget`: latencies in [D − J, D + J] every sample, a
common quadratic Lyapunov function, the gaps between grid points covered by the derived
bound of :mod:`runtime.stability.gap`), the necessary boundary (every constant latency
stable), the smallest jitter at which the adversarial search (periodic patterns of the
extreme latencies, greedy norm growth) found a growing sequence, and the time of one
budget. Run: ``python -m runtime.tooling.bench.jitter_note [--robots a,b] [--out FILE]``
(several minutes per robot on one core); with ``--print`` the rows go to stdout only;
``--merge LOG ...`` puts the rows printed into those files (several runs, e.g. one per
robot in parallel; pass every run's file at once) into the table in place of the rows with
the same robot, controller and formulation, and marks every row no file has as stale.
"""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import replace
from pathlib import Path

from modeling.robot_io import DEFAULT_ROBOT, shipped_robot_files
from runtime.experiment.settings import Experiment
from runtime.setting.robot import robot_setting
from runtime.stability.analysis import setting_gain
from runtime.stability.jitter import Budget, budget
from runtime.stability.sampled_loop import NotLinearisable, refusal, setting

ROOT = Path(__file__).resolve().parents[3]
ROBOTS: dict[str, tuple[str | None, str | None]] = {
    **{p.stem: (None if p.stem == DEFAULT_ROBOT else str(p), None)
       for p in shipped_robot_files()},
    "small_robot": (str(ROOT / "tests" / "robots" / "small_robot.toml"), None),
}
BEGIN, END = "<!-- jitter budget: begin -->", "<!-- jitter budget: end -->"


def ms(x: float) -> str:
    return "∞" if math.isinf(x) else f"{x * 1e3:.3g} ms"


def rows(name: str, only: set[str] | None = None, forms: set[str] | None = None,
         search_only: bool = False) -> list[str]:
    robot, generated = ROBOTS[name]
    base = Experiment()
    base = replace(base, sensing=replace(base.sensing, velocity="sample-instant"))
    st = robot_setting(robot, Path(generated) if generated else None, base)
    code, nominal, exp = st.robot.code, st.robot.nominal, st.experiment
    out = []
    for info in code.controller_infos:
        if only is not None and info.name not in only:
            continue
        for form in info.formulations:
            if forms is not None and form not in forms:
                continue
            where = f"| {name} | {info.label} | {form} "
            if refusal(info):
                out.append(where + f"| | | | | refused: {refusal(info)} |")
                print(out[-1], flush=True)
                continue
            try:
                s = setting(code, info.name, form, nominal, exp)
                g, _, _ = setting_gain(code, info.name, form, nominal, exp, True)
                if not math.isfinite(g):
                    out.append(where + "| | | | | no configuration (ROC's bounds) |")
                    print(out[-1], flush=True)
                    continue
                b = budget(s, g, search_only)
            except (NotLinearisable, ValueError) as exc:
                out.append(where + "| | | | | " + str(exc).replace("|", "/") + " |")
                print(out[-1], flush=True)
                continue
            out.append(where + f"| {ms(b.proved)} | {ms(b.necessary)} | "
                       f"{ms(b.destabilising)} | {b.seconds:.1f} s | {note(b, s.h)} |")
            print(out[-1], flush=True)
    return out


def note(b: Budget, h: float) -> str:
    """What a row says beyond its numbers: where the switching destabilises, and why the
    next jitter tried is not proved."""
    if b.necessary <= 0.0:
        return "unstable at the setting: no jitter tolerated"
    found = ("no growing sequence found up to the model's limit (latency < h)"
             if b.destabilising >= 0.999 * h - 1e-12 else
             "switching destabilises below the constant-delay boundary"
             if b.destabilising < b.necessary else "")
    why = f"above the budget: {b.reason}" if b.reason else ""
    return "; ".join(x for x in (found, why) if x).replace("|", "/")


def key(row: str) -> tuple[str, ...]:
    return tuple(c.strip() for c in row.strip().strip("|").split("|")[:3])


STALE = " (not recomputed since the derived gap bound: the earlier estimate)"


def stale(row: str) -> str:
    """A row kept from the table, marked as computed before the derived gap bound."""
    return row if STALE in row else row.rstrip().removesuffix("|").rstrip() + STALE + " |"


def merge(table: list[str], logs: list[Path]) -> list[str]:
    """``table``'s rows with those printed into ``logs`` in place of the same (robot,
    controller, formulation), a row not in them marked :data:`STALE`; new ones after their
    robot's, robots in :data:`ROBOTS`' order."""
    new = {key(r): r for f in logs for r in f.read_text(encoding="utf-8").splitlines()
           if r.startswith("| ") and key(r)[0] in ROBOTS}
    rows = [new.pop(key(r), stale(r)) for r in table]
    rows += new.values()
    order = list(ROBOTS)
    return sorted(rows, key=lambda r: order.index(key(r)[0]) if key(r)[0] in order
                  else len(order))


HEADER = ["| robot | controller | form | proved jitter | necessary boundary | smallest "
          "destabilising found | time of one budget (wall) | note |",
          "|---|---|---|---:|---:|---:|---:|---|"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "STABILITY.md")
    parser.add_argument("--print", action="store_true", help="print the rows only")
    parser.add_argument("--controllers", default=None, help="only these (comma-separated)")
    parser.add_argument("--formulations", default=None, help="only these (comma-separated)")
    parser.add_argument("--search-only", action="store_true",
                        help="only the adversarial column (the others left at 0)")
    parser.add_argument("--merge", type=Path, nargs="+", default=None,
                        help="merge the rows printed into these files into the table")
    args = parser.parse_args(argv)
    text = args.out.read_text(encoding="utf-8")
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    if args.merge:
        old = pattern.search(text)
        body = [] if old is None else [r for r in old.group(0).splitlines()[3:-1]
                                       if r.startswith("| ")]
        missing = [f for f in args.merge if not f.is_file()]
        if missing:
            print(f"error: no such file: {missing[0]}")
            return 2
        table = [*HEADER, *merge(body, args.merge)]
        block = "\n".join([BEGIN, *table, END])
        args.out.write_text(pattern.sub(lambda _: block, text) if old else
                            text + "\n" + block + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
        return 0
    table = list(HEADER)
    for name in args.robots.split(","):
        table += rows(name, set(args.controllers.split(",")) if args.controllers else None,
                      set(args.formulations.split(",")) if args.formulations else None,
                      args.search_only)
    if args.print:
        return 0
    block = "\n".join([BEGIN, *table, END])
    text = pattern.sub(lambda _: block, text) if BEGIN in text else text + "\n" + block + "\n"
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
