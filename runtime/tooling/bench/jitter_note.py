"""The jitter budget table (issue 46) → the marked section of ``docs/STABILITY.md``.

For each robot (Drishti, the trailer, trailer2, trailer3, tests/robots/small_robot.toml)
and every controller and formulation the analysis takes, at the experiment's setting
(sample-instant rates, the setting's switching gain, the paper's experiment scaled to the
robot): the delay jitter proved (:func:`runtime.stability.jitter.budget`: latencies in
[D − J, D + J] every sample, a common quadratic Lyapunov function), the necessary boundary
(every constant latency stable), the smallest jitter at which the adversarial search
(periodic patterns of the extreme latencies, greedy norm growth) found a growing sequence,
and the time of one budget. Run: ``python -m runtime.tooling.bench.jitter_note [--robots
a,b] [--out FILE]`` (several minutes per robot on one core); with ``--print`` the rows go
to stdout only.
"""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import replace
from pathlib import Path

from runtime.experiment.settings import Experiment
from runtime.setting.robot import robot_setting
from runtime.stability.analysis import setting_gain
from runtime.stability.jitter import budget
from runtime.stability.sampled_loop import NotLinearisable, refusal, setting

ROOT = Path(__file__).resolve().parents[3]
ROBOTS = {
    "drishti": (None, None),
    "trailer": (str(ROOT / "modeling" / "robots" / "trailer" / "trailer.toml"), None),
    "trailer2": (str(ROOT / "modeling" / "robots" / "trailer2" / "trailer2.toml"), None),
    "trailer3": (str(ROOT / "modeling" / "robots" / "trailer3" / "trailer3.toml"), None),
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
                continue
            try:
                s = setting(code, info.name, form, nominal, exp)
                g, _, _ = setting_gain(code, info.name, form, nominal, exp, True)
                if not math.isfinite(g):
                    out.append(where + "| | | | | no configuration (ROC's bounds) |")
                    continue
                b = budget(s, g, search_only)
            except (NotLinearisable, ValueError) as exc:
                out.append(where + f"| | | | | {exc} |")
                continue
            out.append(where + f"| {ms(b.proved)} | {ms(b.necessary)} | "
                       f"{ms(b.destabilising)} | {b.seconds:.1f} s | h = {s.h:g} s |")
            print(out[-1], flush=True)
    return out


HEADER = ["| robot | controller | form | proved jitter | necessary boundary | smallest "
          "destabilising found | time | note |", "|---|---|---|---:|---:|---:|---:|---|"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "STABILITY.md")
    parser.add_argument("--print", action="store_true", help="print the rows only")
    parser.add_argument("--controllers", default=None, help="only these (comma-separated)")
    parser.add_argument("--formulations", default=None, help="only these (comma-separated)")
    parser.add_argument("--search-only", action="store_true",
                        help="only the adversarial column (the others left at 0)")
    args = parser.parse_args(argv)
    table = list(HEADER)
    for name in args.robots.split(","):
        table += rows(name, set(args.controllers.split(",")) if args.controllers else None,
                      set(args.formulations.split(",")) if args.formulations else None,
                      args.search_only)
    if args.print:
        return 0
    text = args.out.read_text(encoding="utf-8")
    block = "\n".join([BEGIN, *table, END])
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    text = pattern.sub(lambda _: block, text) if BEGIN in text else text + "\n" + block + "\n"
    args.out.write_text(text, encoding="utf-8")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
