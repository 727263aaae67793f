"""``python -m runtime bench``: run every benchmark and write ``BENCHMARKS.md`` and
``benchmarks.json`` at the repository root.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

from codegen.backend import function_ir
from codegen.cse import count_ops, cse_function
from modeling.package_paths import default_output
from runtime.tooling.bench.c_bench import run_c, summarise_c
from runtime.tooling.bench.c_variants import MODEL_FUNCTIONS, STEP_KERNELS, specs_by_name
from runtime.tooling.bench.op_counts import casadi_op_count
from runtime.tooling.bench.python_timings import python_bench, toolchain_times
from runtime.tooling.bench.robot_c_bench import run as run_robots
from runtime.tooling.bench.robot_c_bench import section as robots_section
from runtime.tooling.bench.robot_c_bench import summarise as summarise_robots
from runtime.tooling.bench.scale import Rung, budget_section, growth_section
from runtime.tooling.bench.scale import measure as measure_scaling
from runtime.tooling.bench.scale import section as scale_section
from runtime.tooling.bench.step_bench import run_steps, step_cases, summarise_steps
from runtime.tooling.bench.step_callgrind import step_instructions

ROOT = default_output(".")  # BENCHMARKS.md and benchmarks.json: the repository's, else ./


STEP_LABELS = {
    "ours": "`<P>_tdroc_step` (ours)",
    "hand": "hand-written step",
    "ours_frozen": "`<P>_tdroc_step`, `-D<P>_TDROC_FROZEN` (`wmr freeze`)",
    "hand_frozen": "hand-written step, configuration compiled in",
    "ours_libm": "`<P>_tdroc_step`, `-D<P>_LIBM_TRIG` (libm's sin/cos, as the hand-written step)",
    "hand_fast": "improved hand-written step (issue 52)",
    "hand_fast_frozen": "improved hand-written step, configuration compiled in",
}
RATIO_LABELS = {
    "ratio:ours/hand": "`<P>_tdroc_step` / hand-written step",
    "ratio:ours_frozen/hand_frozen": "frozen `<P>_tdroc_step` / frozen hand-written step",
    "ratio:ours_libm/hand": "`<P>_tdroc_step` with libm's sin/cos / hand-written step",
    "ratio:ours/hand_fast": "`<P>_tdroc_step` / improved hand-written step",
    "ratio:ours_frozen/hand_fast_frozen":
        "frozen `<P>_tdroc_step` / frozen improved hand-written step",
}


def _cell(x: dict[str, float], digits: int = 1, unit: str = "") -> str:
    return (f"{x['median']:.{digits}f}{unit} ({x['min']:.{digits}f}–{x['max']:.{digits}f})")


def _step_section(c: dict[tuple[str, str], dict[str, float]], steps: dict[str, Any],
                  runs: int, robots: dict[tuple[str, str, str], dict[str, float]]
                  ) -> list[str]:
    """The full TDROC step (``wmr_tdroc_step``) against the hand-written step, per
    formulation and precision, and the goals of issue 31 that the host measures (ratios
    per repetition: median and range)."""
    st = summarise_steps(steps)
    cases = sorted({case for case, _ in st}, key=lambda c: (c.split("/")[0] != "paper", c))
    fd = {v: c[("forward_dynamics", v)]
          for v in ("ours", "ours_float32", "ours_prepared", "ours_libm", "hand_checked",
                    "hand_checked_float32", "casadi") if ("forward_dynamics", v) in c}
    lines = [
        "## The complete TDROC step, ns per step (gcc -O2)",
        "",
        "`<P>_tdroc_step` (what firmware calls; `<P>` is `wmr` for Drishti, `trailer` for",
        "the trailer) against a hand-written step written to be fast under the same contract",
        "(`runtime/tooling/bench/csrc/hand_tdroc.c`, `hand_trailer_tdroc.c`; and the",
        "improved ones of issue 52, `hand_tdroc_fast.c`, `hand_trailer_tdroc_fast.c`: norms",
        "and M-tilde x inlined, one straight-line body per formulation, the kept constants",
        "read in place, the configuration compared branch-free or by memcmp; the same",
        "statuses in the same order, the configuration compared bit for bit with the copy",
        "`_init` kept, commit on success; M-hat's structure, everything that depends on",
        "the configuration only kept by `_init`, the window's norms in a contiguous ring),",
        "on the controller inputs of the recorded closed loop (lawn mower; the trailer with",
        "its own parameters as the nominal model), per robot, formulation and precision;",
        "each also built with the configuration compiled in. Checked first,",
        "against ours: the statuses of every bad-input case (configuration fields, sign",
        "flips, NaN/Inf/out-of-bound inputs, NULL pointers, a state never initialised),",
        "the statuses and torques over the recording, and again with a bad input every",
        "seventh step (commit on success). Times: median (min–max) over the repetitions",
        f"of the median one of {runs} processes (by its ratio of medians, ours to the",
        "hand-written step: on this VM a process can run disturbed throughout, every variant",
        "about 1.5× slower or one alone, as its memory happens to be placed; the median",
        "process is robust to one such either way; the next table gives every process's",
        "ratio); ratios per repetition.",
        "",
        "| case | checks | " + " | ".join(STEP_LABELS[v] for v in STEP_LABELS) + " |",
        "|---|---|" + "---:|" * len(STEP_LABELS),
    ]
    for case in cases:
        chk = steps["checks"][case]
        cells = [_cell(st[(case, v)]) if (case, v) in st else "—" for v in STEP_LABELS]
        lines.append(f"| {case} | {chk['bad_input_cases']} bad-input cases, {chk['steps']} "
                     f"steps, |Δτ| ≤ {chk['max_abs_tau_diff']:.1e} N m | "
                     + " | ".join(cells) + " |")
    by_case: dict[str, dict[str, list[float]]] = {}
    for row in steps["rows"]:
        by_case.setdefault(row["case"], {})[row["variant"]] = row["run_medians"]
    lines += [
        "",
        "Every process's ratio of medians, in the order they ran (the median one is the table's):",
        "",
        "| case | ours / hand | frozen: ours / hand | ours / improved hand "
        "| frozen: ours / improved hand |",
        "|---|---|---|---|---|",
    ]
    for case in cases:
        med = by_case[case]
        pairs = [(n, d) for n, d in (("ours", "hand"), ("ours_frozen", "hand_frozen"),
                                     ("ours", "hand_fast"),
                                     ("ours_frozen", "hand_fast_frozen"))
                 if n in med and d in med]
        lines.append(f"| {case} | " + " | ".join(
            ", ".join(f"{a / b:.2f}" for a, b in zip(med[n], med[d], strict=True))
            for n, d in pairs) + " |")
    lines += instructions_section(steps.get("instructions", {}))
    lines += [
        "",
        "| forward dynamics | ns per call, median (min–max) |",
        "|---|---:|",
        *[f"| {v} | {_cell(x)} |" for v, x in fd.items()],
        "",
        *ratio_tables(c, steps, robots),
    ]
    return lines


def instructions_section(counts: dict[str, dict[str, float]]) -> list[str]:
    """Instructions per step under callgrind (:mod:`runtime.tooling.bench.step_callgrind`),
    the noise-free figure beside the times; a line saying why when valgrind is missing."""
    if not counts:
        return ["", "Instructions per step: not measured (valgrind's callgrind not installed)."]
    names = ("ours", "ours_libm", "hand", "hand_fast", "ours_frozen", "hand_frozen",
             "hand_fast_frozen")
    ratios = ("ratio:ours/hand", "ratio:ours/hand_fast", "ratio:ours_libm/hand_fast",
              "ratio:ours_frozen/hand_frozen", "ratio:ours_frozen/hand_fast_frozen")
    lines = [
        "",
        "Instructions per step (valgrind's callgrind, inclusive of libm's sin/cos, over the",
        "recorded loop: the difference of two runs with one and three timed passes), the",
        "noise-free figure; goal: ours ≤ the improved hand-written step.",
        "",
        "| case | ours | ours, libm sin/cos | hand | improved hand | ours frozen "
        "| hand frozen | improved hand frozen | ours / hand | ours / improved "
        "| ours, libm sin/cos / improved | frozen: ours / hand | frozen: ours / improved |",
        "|---|" + "---:|" * (len(names) + len(ratios)),
    ]
    for case, r in counts.items():
        lines.append(f"| {case} | " + " | ".join(f"{r[n]:.0f}" for n in names) + " | "
                     + " | ".join(f"{r[k]:.3f}" for k in ratios) + " |")
    return lines


def ratio_tables(c: dict[tuple[str, str], dict[str, float]], steps: dict[str, Any],
                 robots: dict[tuple[str, str, str], dict[str, float]]) -> list[str]:
    """The goals of issue 31 as measured: each ratio's median and range over the
    repetitions (the step's per formulation and precision, the forward dynamics', and
    every shipped robot's against CasADi's C). The README carries these lines as they are
    (:func:`sync_readme`)."""
    st = summarise_steps(steps)
    cases = sorted({case for case, _ in st}, key=lambda c: (c.split("/")[0] != "paper", c))
    fd_ratio = {k[1]: v for k, v in c.items() if k[0] == "forward_dynamics_ratio"}
    lines = [
        "Goals (issue 31), each ratio ≤ 1.0 (≤ 0.8 against CasADi): median (min–max) of the",
        "per-repetition ratios.",
        "",
        "| ratio | " + " | ".join(cases) + " |",
        "|---|" + "---:|" * len(cases),
    ]
    for key, label in RATIO_LABELS.items():
        cells = [_cell(st[(case, key)], 2, "×") if (case, key) in st else "—" for case in cases]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "| forward dynamics ratio (per repetition) | median (min–max) | goal |",
        "|---|---:|---|",
        *[f"| {k} | {_cell(v, 2, '×')} | {_verdict(v, FD_GOALS.get(k, ''))} |"
          for k, v in sorted(fd_ratio.items())],
        "",
        *robot_ratio_table(robots),
    ]
    return lines


def robot_ratio_table(robots: dict[tuple[str, str, str], dict[str, float]]) -> list[str]:
    """Per shipped robot: ours / CasADi's C (the same specs), double and float32; and
    ours / the hand-written C where a robot has one (the trailer's forward dynamics)."""
    functions = ("forward_dynamics", "minimal_forward_dynamics", "tdroc_step_kernels")
    lines = _ratio_table(robots, "ours / CasADi's C, per robot (goal ≤ 0.8)", functions,
                         "casadi")
    hand = _ratio_table(robots, "ours / hand-written C, per robot (goal ≤ 1.0)",
                        functions[:2], "hand")
    return [*lines, "", *hand] if hand else lines


def _ratio_table(robots: dict[tuple[str, str, str], dict[str, float]], title: str,
                 functions: tuple[str, ...], rival: str) -> list[str]:
    """A row per robot that has ``rival``'s ratios: ours / ``rival`` per function, double
    and float32 ("—" where missing); no table when no robot has them."""
    keys = [(f, f"ours/{rival}", f"ours_float32/{rival}_float32") for f in functions]
    names = [r for r in dict.fromkeys(k[0] for k in robots)
             if any((r, f, ratio) in robots for f, ratio, _ in keys)]
    if not names:
        return []
    lines = [f"| {title} | " + " | ".join(f"{f}, {p}" for f in functions
                                         for p in ("double", "float32")) + " |",
             "|---|" + "---:|" * (2 * len(functions))]
    for robot in names:
        cells = [_cell(robots[key], 2, "×") if key in robots else "—"
                 for f, double, single in keys
                 for key in ((robot, f, double), (robot, f, single))]
        lines.append(f"| {robot} | " + " | ".join(cells) + " |")
    return lines


def _verdict(ratio: dict[str, float], goal: str) -> str:
    """``≤ 0.8: met`` or ``≤ 0.8: missed by 12 %`` (on the median)."""
    if not goal:
        return ""
    bound = float(goal.split()[-1])
    if ratio["median"] <= bound:
        return f"{goal}: met"
    return f"{goal}: missed by {100 * (ratio['median'] / bound - 1):.0f} %"


README_BEGIN = "<!-- make bench: the ratios of BENCHMARKS.md, written by runtime/tooling/bench -->"
README_END = "<!-- end of make bench's ratios -->"


def sync_readme(readme: Path, lines: list[str]) -> bool:
    """Replace the README's block between the two markers with ``lines``; False (nothing
    written) if the README or its markers are missing."""
    if not readme.is_file():
        return False
    text = readme.read_text()
    start, end = text.find(README_BEGIN), text.find(README_END)
    if start < 0 or end < start:
        return False
    block = "\n".join([README_BEGIN, *lines, README_END])
    readme.write_text(text[:start] + block + text[end + len(README_END):])
    return True


FD_GOALS = {
    "ours/hand_checked": "≤ 1.0",
    "ours_float32/hand_checked_float32": "≤ 1.0",
    "ours/casadi": "≤ 0.8",
    "ours_prepared/hand_checked": "≤ 1.0",
    "ours_prepared/casadi": "≤ 0.8",
}


def write_report(
    c: dict[tuple[str, str], dict[str, float]],
    steps: dict[str, Any],
    py: list[dict[str, Any]],
    ops: dict[str, dict[str, Any]],
    tool: dict[str, float],
    calls: int,
    repeats: int,
    scaling: list[Rung],
    robots: dict[tuple[str, str, str], dict[str, float]],
    robot_calls: int,
    runs: int = 1,
) -> str:
    funcs = [*MODEL_FUNCTIONS, *(f"{k}_step_kernels" for k in STEP_KERNELS)]
    lines = [
        "# Benchmarks",
        "",
        "Written by `make bench` (`python -m runtime bench`). Do not edit.",
        "",
        f"Machine: {platform.machine()}, {platform.processor() or 'unknown CPU'}, "
        f"Python {platform.python_version()}, gcc -O2. C: median (min–max) of {repeats} "
        f"repetitions of {calls:,} calls over 256 varied inputs, every variant in one process.",
        "",
        "## C, ns per call (ratio = variant / ours double)",
        "",
        "| function | ours double | ours float32 | ours, no validation | ours, prepared "
        "| ours, libm sin/cos | CasADi C | SymPy ccode | hand-written "
        "| hand-written, same checks |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for f in funcs:
        ours = c[(f, "ours")]["median"]
        cells = []
        for v in ("ours", "ours_float32", "ours_unchecked", "ours_prepared", "ours_libm",
                  "casadi", "sympy", "hand", "hand_checked"):
            if (f, v) not in c:
                cells.append("—")
                continue
            s = c[(f, v)]
            ratio = "" if v == "ours" else f" ({s['median'] / ours:.2f}×)"
            cells.append(f"{s['median']:.1f} ({s['min']:.1f}–{s['max']:.1f}){ratio}")
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "“No validation”: the same specs without the finite-input, parameter-guard and",
        "finite-output checks (rendered under the prefix wmrn_), i.e. what the checks cost.",
        "“Hand-written, same checks”: the hand-written forward dynamics with our statuses",
        "(finite inputs, the parameter guards, finite outputs; `csrc/hand_tdroc.c`).",
        "“Ours, prepared”: `wmr_forward_dynamics_prepared` (the same results bit for bit, the",
        "state's checks and the finite-output check), each input set's parameters prepared",
        "once by `wmr_model_prepare` before anything is checked or timed.",
        "“Ours, libm sin/cos”: the same generated code built with `-DWMR_LIBM_TRIG` (libm's",
        "sin and cos instead of the generated ones of `wmr_types.h`, which the double build",
        "uses by default); CasADi's C and the hand-written C call libm's.",
        "Our parameters struct is read in place from the flat inputs (its layout checked at",
        "compile time), as CasADi's C and the hand-written C read theirs: no copy per call.",
        "Before any timing every variant's outputs on the 256 inputs are checked against",
        "ours (1e-9 relative, float32 1e-3); the repetitions are interleaved (each times",
        "every variant once). A controller step here is the sum of its kernels (TDE (17),",
        "TDROC gain (25), law); the complete step is timed below.",
        "",
        *_step_section(c, steps, runs, robots),
        "",
        *robots_section(robots, robot_calls, repeats),
        "",
        "## Python, µs per call of the forward dynamics",
        "",
        "| variant | median (min–max) |",
        "|---|---:|",
        *[
            f"| {r['variant']} | {r['us']['median']:.2f} ({r['us']['min']:.2f}–"
            f"{r['us']['max']:.2f}) |"
            for r in py
        ],
        "",
        "## Operations after CSE: ours vs CasADi's SX graph",
        "",
        "| function | ours | CasADi |",
        "|---|---|---|",
        *[f"| {name} | {v['ours']} | {v['casadi']} |" for name, v in ops.items()],
        "",
        "## How cost grows with the robot",
        "",
        "Drishti, the tractor with one, two and three trailers and the tugger train of five",
        "carts (`modeling/robots/`), each",
        "measured as a user meets it (`runtime/tooling/bench/scale.py`): `wmr model --robot`",
        "in a fresh process (wall and CPU time, peak memory: CPU time is the figure a",
        "shared machine disturbs least), the generated folder's bytes, the operations after",
        "CSE of `forward_dynamics` and of the kernels one TDROC step calls (minimal",
        "formulation), `gcc -O2 -c` of each generated C file (CPU time of the slowest, and the",
        "largest peak memory), a Cortex-M4 float32 image with TDROC alone (generated code",
        "bytes, the step's worst-case stack) and the x86 TDROC step (gcc -O2, double, best",
        "of interleaved passes).",
        "",
        *scale_section(scaling),
        "",
        "Operations added per cart between consecutive robots (three to five carts: the",
        "mean of the two carts), and issue 51's budgets against the measurements:",
        "",
        *growth_section(scaling),
        "",
        *budget_section(scaling),
        "",
        "## Toolchain",
        "",
        f"- derivation (1)–(14), (31), minimal form, multipliers, lumped relations, cold "
        f"start: {tool['derivation_s']:.2f} s",
        f"- `python -m codegen` (what `make model` runs), cold start: {tool['make_model_s']:.1f} s",
        f"- `python -m runtime reproduce` (16 runs + ε sweep + figures): "
        f"{tool['reproduce_s']:.1f} s",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="wmr bench")
    parser.add_argument("--calls", type=int, default=1_000_000, help="calls per repetition")
    parser.add_argument("--repeats", type=int, default=5, help="repetitions (≥ 5)")
    parser.add_argument("--runs", type=int, default=3,
                        help="separate processes of the step benchmark (ratios pooled)")
    parser.add_argument("--out", type=Path, default=ROOT, help="folder for the reports")
    args = parser.parse_args(argv)
    if args.calls < 1 or args.repeats < 1:
        print("error: --calls and --repeats must be positive", file=sys.stderr)
        return 2
    print("C benchmarks ...", flush=True)
    c = summarise_c(run_c(args.calls, args.repeats))
    print("C step benchmark ...", flush=True)
    steps = run_steps(args.calls, args.repeats, args.runs)
    if shutil.which("valgrind") is not None and shutil.which("callgrind_annotate") is not None:
        print("C step instructions (callgrind) ...", flush=True)
        steps["instructions"] = {robot.case(f, p): step_instructions(robot, f, p)
                                 for robot, f, p in step_cases()}
    robot_calls = max(1, args.calls // 5)  # the trailers' functions take 5-30x longer
    robots = summarise_robots(run_robots(robot_calls, args.repeats))
    print("Python benchmarks ...", flush=True)
    py = python_bench(max(1, args.calls // 100))
    specs = specs_by_name()
    ops = {}
    for name in (*MODEL_FUNCTIONS, *sorted({k for ks in STEP_KERNELS.values() for k in ks})):
        casadi_counts = casadi_op_count(specs[name])
        ops[name] = {
            "ours": count_ops(cse_function(specs[name].checked_spec(), reciprocals=True)).summary(),
            "casadi": ", ".join(f"{v} {k}" for k, v in sorted(casadi_counts.items())),
        }
        form = function_ir(specs[name]).prepared
        if form is not None:  # what the prepared call evaluates, and prepare once
            ops[f"{name}_prepared"] = {
                "ours": f"{form.ops('per_call').summary()} (prepare, once: "
                f"{form.ops('prepare').summary()})",
                "casadi": ops[name]["casadi"],
            }
    print("toolchain timings ...", flush=True)
    tool = toolchain_times()
    print("scaling with the robot ...", flush=True)
    scaling = measure_scaling()
    text = write_report(c, steps, py, ops, tool, args.calls, args.repeats, scaling, robots,
                        robot_calls, args.runs)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "BENCHMARKS.md").write_text(text)
    # the README's ratio tables are BENCHMARKS.md's (tests/runtime/test_bench.py compares them)
    sync_readme(args.out / "README.md", ratio_tables(c, steps, robots))
    (args.out / "benchmarks.json").write_text(
        json.dumps(
            {
                "c_ns": {f"{f}/{v}": s for (f, v), s in sorted(c.items())},
                "c_step_ns": {
                    f"{case}/{v}": s for (case, v), s in sorted(summarise_steps(steps).items())
                },
                "c_step_checks": steps["checks"],
                "c_step_instructions": steps.get("instructions", {}),
                "c_robots_ns": {"/".join(k): s for k, s in sorted(robots.items())},
                "python_us": py,
                "ops": ops,
                "toolchain": tool,
                "scaling": [asdict(r) for r in scaling],
            },
            indent=1,
            sort_keys=True,
        )
        + "\n"
    )
    print(text)
    return 0
