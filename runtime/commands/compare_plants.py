"""``python -m runtime.commands.compare_plants``: the command line of
:mod:`runtime.plant_comparison` (the generated-model plant and MuJoCo side by side); writes
``docs/MUJOCO.md``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from modeling.package_paths import default_output
from runtime.commands.options import add_experiment_option, add_robot_options, load_setting
from runtime.plant_comparison import SENSINGS, compare, markdown


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m runtime.commands.compare_plants",
                                description="The generated-model plant against MuJoCo: "
                                "every controller, path and sensing, at several floors.")
    add_experiment_option(p)
    add_robot_options(p)
    p.add_argument("--sensing", default=",".join(SENSINGS), metavar="MODEL[,MODEL]")
    p.add_argument("--out", type=Path, default=None,
                   help="the document (default: docs/MUJOCO.md for the paper's robot, "
                   "./mujoco/<robot>/MUJOCO.md for another)")
    p.add_argument("--no-verdicts", action="store_true",
                   help="leave out the verdicts of wmr stability against the engine (h and μ "
                   "swept: the slow part)")
    args = p.parse_args(argv)
    try:
        setting = load_setting(args)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    out = args.out or (default_output("docs/MUJOCO.md") if setting.is_paper_robot
                       else Path("mujoco") / setting.robot.name / "MUJOCO.md")
    start = time.perf_counter()
    comp = compare(setting, tuple(args.sensing.split(",")), progress=True,
                   verdicts=not args.no_verdicts)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(markdown(comp), encoding="utf-8")
    print(f"wrote {out}: wall time {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
