"""Instructions per TDROC step, the noise-free figure beside the step benchmark's times: the
same executable as :mod:`runtime.tooling.bench.step_bench` (every variant, checked equal
to ours on the bad-input cases and the recorded loop before anything runs), run under
valgrind's callgrind twice, with one and with ``1 + extra`` timed passes of the recording.
Each variant's step function's inclusive instruction count (its callees, libm's sin/cos
included) differs between the two runs by exactly its ``extra`` timed passes, so the
difference over ``extra`` x the recording's steps is its instructions per step on the
recorded loop, whatever the checks before the timing cost.

``python -m runtime.tooling.bench.step_callgrind`` prints the table (needs valgrind).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from runtime.tooling.bench.step_bench import (
    RATIOS,
    STEP_ROBOTS,
    StepRobot,
    _variants,
    build_step_bench,
    step_cases,
)


def inclusive_counts(out_file: Path) -> dict[str, int]:
    """Function name -> inclusive instructions (Ir) from a callgrind output file."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                           str(out_file)], check=True, capture_output=True, text=True).stdout
    counts: dict[str, int] = {}
    for line in text.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+(?:\([^)]*\)\s+)?(?:\S+:)?(\w+)", line)
        if m:
            counts.setdefault(m.group(2), int(m.group(1).replace(",", "")))
    return counts


def _run(exe: Path, passes: int, nsteps: int, out: Path) -> dict[str, int]:
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", str(exe),
                    str(passes * nsteps), "1"], check=True, capture_output=True)
    return inclusive_counts(out)


def step_instructions(robot: StepRobot, formulation: str, precision: str,
                      extra: int = 2) -> dict[str, float]:
    """Variant -> instructions per step (callgrind, inclusive) for one case; and
    ``ratio:num/den`` for each of the step benchmark's ratios."""
    from runtime.bindings.generated import load_robot_code
    from runtime.tooling.firmware.emulated_run import record_closed_loop

    float32 = precision == "float32"
    rec = record_closed_loop("tdroc", formulation, eps=0.5, float32=float32, robot=robot.code)
    pre = load_robot_code(robot.code).prefix
    nsteps = len(rec.inputs)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        exe = build_step_bench(work, rec.config, rec.inputs, float32, robot)
        one = _run(exe, 1, nsteps, work / "one.out")
        more = _run(exe, 1 + extra, nsteps, work / "more.out")
    per_step: dict[str, float] = {}
    for name, _, step, _ in _variants(float32, pre):
        per_step[name] = (more[step] - one[step]) / (extra * nsteps)
    for num, den in RATIOS:
        per_step[f"ratio:{num}/{den}"] = per_step[num] / per_step[den]
    return per_step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--extra", type=int, default=2, help="timed passes counted")
    args = parser.parse_args()
    if shutil.which("valgrind") is None or shutil.which("callgrind_annotate") is None:
        raise SystemExit("step_callgrind: valgrind (callgrind) is not installed")
    names = ("ours", "ours_libm", "hand", "hand_fast", "ours_frozen", "hand_frozen",
             "hand_fast_frozen")
    keys = ("ours/hand", "ours/hand_fast", "ours_libm/hand_fast", "ours_frozen/hand_frozen",
            "ours_frozen/hand_fast_frozen")
    print("| case | " + " | ".join(names) + " | " + " | ".join(keys) + " |")
    print("|---" * (len(names) + len(keys) + 1) + "|")
    for robot, formulation, precision in step_cases(STEP_ROBOTS):
        r = step_instructions(robot, formulation, precision, args.extra)
        ratios = [r[f"ratio:{k}"] for k in keys]
        print(f"| {robot.case(formulation, precision)} | "
              + " | ".join(f"{r[n]:.0f}" for n in names) + " | "
              + " | ".join(f"{x:.3f}" for x in ratios) + " |", flush=True)


if __name__ == "__main__":
    main()
