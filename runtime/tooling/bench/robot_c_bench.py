"""Every shipped robot's generated C against CasADi's C of the same specs: the forward
dynamics (both formulations) and the kernels of one minimal-formulation TDROC step, in
double and in float32 (CasADi's with ``casadi_real`` float), one process per robot,
interleaved repetitions, every variant checked against ours (double) before it is timed.

Drishti's functions have hand-written competitors in :mod:`c_bench`; the trailer's forward
dynamics (both formulations) have one here (``csrc/hand_trailer.c``, double and float32,
the same statuses), timed in the same process. The longer trains have CasADi's C, the
competitor that grows with the robot at no cost to anyone.
"""

from __future__ import annotations

import json
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from codegen.backends.casadi import generate_c
from codegen.robot_functions import law_specs, mhat_kernels, minv_norm_needs_q, model_specs
from codegen.spec import FunctionSpec
from modeling.robot_file import load_robot_model
from modeling.robot_io import shipped_robot_file
from modeling.robot_model import RobotModel
from runtime.tooling.bench.c_bench import BENCH_CSRC, CFLAGS, renamed_objects, spread
from runtime.tooling.bench.c_variants import (
    HARNESS,
    casadi_wrapper,
    input_ranges,
    input_size,
    ours_wrapper,
    output_sizes,
    prototype,
)
from runtime.tooling.bench.scale import LADDER, ROOT, generated_folder

FUNCTIONS = ("forward_dynamics", "minimal_forward_dynamics")
# One TDROC step of the minimal formulation: TDE (17), the window's difference, the
# nominal ||M^-1|| (per step when it depends on q), the gain (25), the law (22).
STEP_KERNELS = ("minimal_tde", "minimal_omega_difference", "minimal_minv_norm",
                "tdroc_weighted_gain", "minimal_tdroc_law")
# A robot whose M-hat depends on q: the step evaluates M-hat once and the `_mhat` kernels
# read it (robot_functions.mhat_kernels); (17) reads the M-hat the previous step kept.
MHAT_STEP_KERNELS = ("minimal_mhat", "minimal_tde_mhat", "minimal_omega_difference",
                     "minimal_minv_norm_mhat", "tdroc_weighted_gain", "minimal_tdroc_law_mhat")
# variant: its C real type (the harness checks float against ours double to 1e-3, double to 1e-9)
VARIANTS = {"ours": "double", "ours_float32": "float", "casadi": "double",
            "casadi_float32": "float"}
# Hand-written competitors per robot (csrc/<file>, functions named hand_<robot>_<name> and,
# with -DHAND_FLOAT32, handf32_<robot>_<name>): the forward dynamics, both formulations.
HAND_WRITTEN = {"trailer": "hand_trailer.c"}
HAND_VARIANTS = {"hand": "double", "hand_float32": "float"}
PARAMETER_SPREAD = 0.05  # parameters drawn within ±5 % of the robot file's values


@dataclass(frozen=True)
class RobotFunctions:
    """The functions measured for one robot and where its generated C is."""

    model: RobotModel
    specs: tuple[FunctionSpec, ...]
    c_dir: Path

    @property
    def prefix(self) -> str:
        return self.model.prefix


def robot_functions(robot: str, root: Path = ROOT) -> RobotFunctions:
    model, _ = load_robot_model(shipped_robot_file(robot))
    by_name = {s.name: s for s in (*model_specs(model), *law_specs(model))}
    kernels = (list(MHAT_STEP_KERNELS) if mhat_kernels(model, "minimal") else
               [k for k in STEP_KERNELS if k != "minimal_minv_norm" or minv_norm_needs_q(model)])
    specs = tuple(by_name[n] for n in (*FUNCTIONS, *kernels))
    return RobotFunctions(model, specs, generated_folder(root, robot) / "c")


def nominal_values(model: RobotModel) -> dict[str, float]:
    """The robot file's parameter values by symbol name (what :func:`input_ranges` keys)."""
    return {str(p.symbol): model.values[p.key] for p in model.params}


def build(workdir: Path, rf: RobotFunctions) -> Path:
    """One executable timing ours (double, float32) and CasADi's (double, float) C of
    ``rf``'s functions in the harness of :mod:`c_variants`; returns its path."""
    prefix = rf.prefix
    sources = [rf.c_dir / f"{prefix}_model.c", rf.c_dir / f"{prefix}_laws.c"]
    objs = []
    for src in sources:
        obj = workdir / f"d_{src.stem}.o"
        subprocess.run(["gcc", *CFLAGS, "-c", f"-I{rf.c_dir}", str(src), "-o", str(obj)],
                       check=True)
        objs.append(str(obj))
    objs += renamed_objects(workdir, sources, (f"-D{prefix.upper()}_FLOAT32",), "f32_",
                            include=rf.c_dir, symbols=f"{prefix}_")
    for tag, real in (("casadi", "double"), ("casadif", "float")):
        c_file, _ = generate_c(rf.specs, workdir, f"{tag}_gen", prefix=f"{tag}_", real=real)
        obj = workdir / f"{tag}_gen.o"
        subprocess.run(["gcc", *CFLAGS, "-c", str(c_file), "-o", str(obj)], check=True)
        objs.append(str(obj))
    hand = HAND_WRITTEN.get(rf.model.name)
    if hand is not None:  # the hand-written competitor, double and float32
        for define, tag in (((), "hand"), (("-DHAND_FLOAT32",), "handf32")):
            obj = workdir / f"{tag}_{Path(hand).stem}.o"
            subprocess.run(["gcc", *CFLAGS, *define, "-c", str(BENCH_CSRC / hand), "-o",
                            str(obj)], check=True)
            objs.append(str(obj))
    params = rf.specs[0].inputs[0]
    members = " ".join(f"float {f.c_field};" for f in params.fields)
    lines = [f'#include "{prefix}_model.h"', f'#include "{prefix}_laws.h"',
             f"typedef struct {{ {members} }} {prefix}_params_f32_t;", HARNESS]
    for spec in rf.specs:
        lo, hi = zip(*input_ranges(spec, nominal_values(rf.model), PARAMETER_SPREAD),
                     strict=True)
        n_in = input_size(spec)
        lines += [
            f"static const double lo_{spec.name}[{n_in}] = {{{', '.join(map(repr, lo))}}};",
            f"static const double hi_{spec.name}[{n_in}] = {{{', '.join(map(repr, hi))}}};",
            prototype(spec, f"f32_{prefix}_{spec.name}", "float", f"{prefix}_params_f32_t",
                      f"{prefix}_status_t"),
            ours_wrapper(spec, "ours", "double", c_prefix=prefix),
            ours_wrapper(spec, "ours32", "float", f"{prefix}_params_f32_t", prefix),
            casadi_wrapper(spec, "casadi_", "double"),
            casadi_wrapper(spec, "casadif_", "float"),
        ]
        if hand is not None and spec.name in FUNCTIONS:
            for tag, real in (("hand", "double"), ("handf32", "float")):
                fn = f"{tag}_{rf.model.name}_{spec.name}"
                lines += [f"int {fn}(const {real} *in, {real} *out);",
                          f"static void {tag}_w_{spec.name}(const void *in, void *out) "
                          f"{{ (void){fn}((const {real} *)in, ({real} *)out); }}"]
    fns = {"ours": "ours_{}", "ours_float32": "ours32_{}", "casadi": "casadi_w_{}",
           "casadi_float32": "casadif_w_{}", "hand": "hand_w_{}", "hand_float32": "handf32_w_{}"}
    cases = [
        f'        {{"{s.name}", "{v}", {fns[v].format(s.name)}, {input_size(s)}, '
        f"{sum(output_sizes(s))}, {int(real == 'float')}, lo_{s.name}, hi_{s.name}, 0}},"
        for s in rf.specs for v, real in variants(rf.model.name, s.name).items()
    ]
    lines += [
        "int main(int argc, char **argv) {",
        "    long calls = argc > 1 ? atol(argv[1]) : 200000; "
        "int repeats = argc > 2 ? atoi(argv[2]) : 5;",
        "    bench_case cases[] = {", *cases, "    };",
        "    return run_all(cases, sizeof cases / sizeof cases[0], calls, repeats);\n}",
    ]
    src = workdir / "robot_bench.c"
    src.write_text("#define _POSIX_C_SOURCE 199309L\n#include <stdlib.h>\n#include <string.h>\n"
                   + "\n".join(lines))
    exe = workdir / "robot_bench"
    subprocess.run(["gcc", *CFLAGS, f"-I{rf.c_dir}", str(src), *objs, "-lm", "-o", str(exe)],
                   check=True)
    return exe


def variants(robot: str, function: str) -> dict[str, str]:
    """The variants timed for ``robot``'s ``function`` and their C real types."""
    if robot in HAND_WRITTEN and function in FUNCTIONS:
        return {**VARIANTS, **HAND_VARIANTS}
    return VARIANTS


def run_robot(robot: str, calls: int, repeats: int, root: Path = ROOT) -> list[dict[str, Any]]:
    """One robot's rows (``function``, ``variant``, ``ns`` per repetition), each tagged
    with ``robot``; raises if a variant disagrees with ours (then nothing was timed)."""
    rf = robot_functions(robot, root)
    with tempfile.TemporaryDirectory() as tmp:
        exe = build(Path(tmp), rf)
        proc = subprocess.run([str(exe), str(calls), str(repeats)], check=False,
                              capture_output=True, text=True)
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0:
        raise RuntimeError(f"{robot}: the C benchmark refused to time: {rows or proc.stderr}")
    return [{**r, "robot": robot} for r in rows]


def run(calls: int = 200_000, repeats: int = 7, robots: tuple[str, ...] = LADDER,
        root: Path = ROOT) -> list[dict[str, Any]]:
    rows = []
    for robot in robots:
        print(f"robot C benchmark: {robot} ...", flush=True)
        rows += run_robot(robot, calls, repeats, root)
    return rows


def summarise(rows: list[dict[str, Any]]) -> dict[tuple[str, str, str], dict[str, float]]:
    """(robot, function, variant) → ns, and (robot, function, "ours/casadi",
    "ours_float32/casadi_float32", and where a hand-written competitor exists "ours/hand",
    "ours_float32/hand_float32") → the per-repetition ratio; function "tdroc_step_kernels"
    is the sum of the step's kernels per repetition."""
    ns = {(r["robot"], r["function"], r["variant"]): r["ns"] for r in rows}
    for robot in {r["robot"] for r in rows}:
        kernels = [k for k in dict.fromkeys((*STEP_KERNELS, *MHAT_STEP_KERNELS))
                   if (robot, k, "ours") in ns]
        for v in VARIANTS:
            ns[(robot, "tdroc_step_kernels", v)] = [
                sum(t) for t in zip(*(ns[(robot, k, v)] for k in kernels), strict=True)]
    out = {key: spread(t) for key, t in ns.items()}
    for (robot, function, variant), t in ns.items():
        if not variant.startswith("ours"):
            continue
        for rival in ("casadi", "hand"):
            other = variant.replace("ours", rival)
            if (robot, function, other) in ns:
                ratios = [a / b for a, b in zip(t, ns[(robot, function, other)], strict=True)]
                out[(robot, function, f"{variant}/{other}")] = spread(ratios)
    return out


def section(s: dict[tuple[str, str, str], dict[str, float]], calls: int, repeats: int
            ) -> list[str]:
    """BENCHMARKS.md's table: per robot and function, ours and CasADi's ns and the ratio."""
    robots = [r for r in LADDER if any(k[0] == r for k in s)]
    lines = [
        "## Every shipped robot: ours against CasADi's C, ns per call (gcc -O2)",
        "",
        "The same specs through CasADi's `CodeGenerator` (double, and `casadi_real` float),",
        f"one process per robot, interleaved repetitions of {calls:,} calls over 256 input",
        f"sets (parameters within ±{100 * PARAMETER_SPREAD:.0f} % of the robot file's; our "
        "parameters struct read in place",
        "from them, as CasADi reads its arrays), each variant checked against ours (double)",
        "first: 1e-9 relative to the largest output, float32 1e-3. Ours checks its inputs,",
        "parameters and results (the statuses of the contract); CasADi's C checks nothing.",
        "The TDROC step's kernels (minimal formulation): TDE (17), the window's difference,",
        "‖M⁻¹‖ when it depends on q, the gain (25), the law (22), summed per repetition.",
        "Ratio: ours / CasADi per repetition, median (min–max); goal ≤ 0.8 (issue 31).",
        "",
        "| robot | function | ours double | CasADi double | ratio | ours float32 "
        "| CasADi float | ratio |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    lines += _rows(s, [(r, f) for r in robots for f in (*FUNCTIONS, "tdroc_step_kernels")
                       if (r, f, "ours") in s], "casadi")
    hand = [(r, f) for r in robots for f in FUNCTIONS if (r, f, "hand") in s]
    if hand:
        lines += [
            "",
            "Against hand-written C (`csrc/hand_trailer.c`: derived by hand from the robot's",
            "kinetic energy in the tractor's forward speed and yaw rate, sin and cos of the",
            "hitch angle and of the heading only, libm's sin/cos, the same statuses; checked",
            "against ours first, and its statuses on bad inputs by the tests). Ratio: ours /",
            "hand per repetition, median (min–max); goal ≤ 1.0 (issue 31).",
            "",
            "| robot | function | ours double | hand-written double | ratio | ours float32 "
            "| hand-written float32 | ratio |",
            "|---|---|---:|---:|---:|---:|---:|---:|",
        ]
        lines += _rows(s, hand, "hand")
    return lines


def _rows(s: dict[tuple[str, str, str], dict[str, float]], cases: list[tuple[str, str]],
          rival: str) -> list[str]:
    """A table row per (robot, function): ours and ``rival``'s ns and their ratio, double
    and float32."""
    lines = []
    for robot, function in cases:
        cells = []
        for v in ("ours", "ours_float32"):
            other = v.replace("ours", rival)
            cells += [f"{s[(robot, function, v)]['median']:.1f}",
                      f"{s[(robot, function, other)]['median']:.1f}",
                      _ratio_cell(s[(robot, function, f"{v}/{other}")])]
        lines.append(f"| {robot} | {function} | " + " | ".join(cells) + " |")
    return lines


def _ratio_cell(x: dict[str, float]) -> str:
    return f"{x['median']:.2f}× ({x['min']:.2f}–{x['max']:.2f})"
