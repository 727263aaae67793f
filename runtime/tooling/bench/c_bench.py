"""The C benchmark: every variant compiled into one executable (gcc -O2; our float32
objects' symbols renamed; ours without validation rendered under the prefix wmrn_), run,
and summarised per function and per controller step (median, min, max).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

import sympy as sp

from codegen.backends import c as c_backend
from codegen.backends.c.config import CConfig, StatusCode
from codegen.backends.casadi import generate_c
from codegen.spec import FunctionSpec
from modeling.robots.drishti.parameters import LUMPED
from runtime.bindings.cbuild import GENERATED_C
from runtime.tooling.bench.c_variants import (
    HAND_CHECKED,
    HAND_WRITTEN,
    HARNESS,
    MODEL_FUNCTIONS,
    STEP_KERNELS,
    casadi_wrapper,
    input_ranges,
    input_size,
    ours_wrapper,
    output_sizes,
    prepared_wrapper,
    prototype,
    specs_by_name,
    sympy_c,
)

CSRC = Path(__file__).resolve().parents[1] / "witness" / "csrc"  # runtime/tooling/witness/csrc
BENCH_CSRC = Path(__file__).resolve().parent / "csrc"  # hand-written with the same checks
CFLAGS = ["-std=c99", "-O2"]
# (function, numerator, denominator): the ratios reported per repetition (goals of issue 31).
RATIO_PAIRS = (
    ("forward_dynamics", "ours", "hand_checked"),
    ("forward_dynamics", "ours_float32", "hand_checked_float32"),
    ("forward_dynamics", "ours", "casadi"),
    ("forward_dynamics", "ours_prepared", "hand_checked"),
    ("forward_dynamics", "ours_prepared", "casadi"),
)


def uses_trig(spec: FunctionSpec) -> bool:
    """Whether the function evaluates sin or cos (generated in double, libm's with
    ``-DWMR_LIBM_TRIG``): then the benchmark times both."""
    return any(expr.has(sp.sin, sp.cos) for out in spec.outputs for expr in out.exprs)


def renamed_objects(workdir: Path, sources: list[Path], defines: tuple[str, ...],
                    tag: str, include: Path = GENERATED_C, symbols: str = "wmr_") -> list[str]:
    """``sources`` compiled with ``defines``, every symbol (defined or referenced) that
    starts with ``symbols`` renamed to ``<tag><symbol>`` so that the objects link beside
    the default build."""
    objs = []
    for src in sources:
        obj = workdir / f"{tag}{src.stem}.o"
        subprocess.run(["gcc", *CFLAGS, *defines, "-c", f"-I{include}", str(src), "-o",
                        str(obj)], check=True)
        names = [*subprocess.run(["nm", "--defined-only", "-g", str(obj)], check=True,
                                 capture_output=True, text=True).stdout.split(),
                 *subprocess.run(["nm", "-u", str(obj)], check=True, capture_output=True,
                                 text=True).stdout.split()]
        mapping = workdir / f"{tag}{src.stem}.redefine"
        mapping.write_text("".join(f"{n} {tag}{n}\n" for n in names if n.startswith(symbols)))
        subprocess.run(["objcopy", f"--redefine-syms={mapping}", str(obj)], check=True)
        objs.append(str(obj))
    return objs


def build_bench(workdir: Path, cases: list[dict[str, Any]], specs: dict[str, FunctionSpec]) -> Path:
    """Compile every variant into one executable; returns its path."""
    used = sorted({c["spec"] for c in cases})
    spec_list = [specs[n] for n in used]
    # CasADi's own C for the same symbolic functions.
    generate_c(spec_list, workdir, "casadi_gen", prefix="casadi_")
    (workdir / "sympy_gen.c").write_text(sympy_c(spec_list))
    objs: list[str] = []
    gen_sources = [p for p in sorted(GENERATED_C.glob("wmr_*.c")) if p.name != "wmr_plant.c"]
    for src in gen_sources:  # ours, double
        obj = workdir / f"d_{src.stem}.o"
        subprocess.run(
            ["gcc", *CFLAGS, "-c", f"-I{GENERATED_C}", str(src), "-o", str(obj)], check=True
        )
        objs.append(str(obj))
    # ours, float32; and ours with libm's sin/cos: each with its symbols renamed
    objs += renamed_objects(workdir, gen_sources, ("-DWMR_FLOAT32",), "f32_")
    objs += renamed_objects(workdir, gen_sources, ("-DWMR_LIBM_TRIG",), "lm_")
    # Ours without input/guard/output validation, to measure what the checks cost: the
    # same specs rendered by the same backend under another prefix (wmrn_).
    unchecked = [
        replace(specs[n], returns_status=False, guards=(), nonfinite_input="",
                nonfinite_output="", prepared=False)
        for n in used if specs[n].returns_status
    ]
    cfg = CConfig(prefix="wmrn_", types_header="wmrn_types.h", real_type="wmrn_real_t",
                  status_type="wmrn_status_t", params_ctype="wmrn_params_t",
                  literal_macro="WMRN_LIT", status_codes=(StatusCode("WMRN_OK", 0, "ok"),))
    for fname, text in c_backend.render_all({"wmrn_model": unchecked}, cfg).items():
        (workdir / fname).write_text(text)
    sources = [workdir / "casadi_gen.c", workdir / "sympy_gen.c", CSRC / "hand_model.c",
               BENCH_CSRC / "hand_tdroc.c"]
    # the hand-written forward dynamics with the same checks, float32 (renamed handf32_*)
    hand32 = workdir / "x_hand_tdroc_f32.o"
    subprocess.run(
        ["gcc", *CFLAGS, "-DWMR_FLOAT32", "-c", f"-I{GENERATED_C}", f"-I{BENCH_CSRC}",
         *(f"-Dhand_{n}=handf32_{n}" for n in ("tdroc_init", "tdroc_step",
                                               "forward_dynamics_checked")),
         str(BENCH_CSRC / "hand_tdroc.c"), "-o", str(hand32)],
        check=True,
    )
    objs.append(str(hand32))
    if unchecked:
        sources.append(workdir / "wmrn_model.c")
    for src in sources:
        obj = workdir / f"x_{src.stem}.o"
        subprocess.run(
            ["gcc", *CFLAGS, "-c", f"-I{CSRC}", f"-I{workdir}", f"-I{GENERATED_C}",
             f"-I{BENCH_CSRC}", str(src), "-o", str(obj)],
            check=True,
        )
        objs.append(str(obj))
    # Harness.
    lines = [
        '#include "wmr_model.h"',
        '#include "wmr_laws.h"',
        '#include "casadi_gen.h"',
        '#include "hand_model.h"',
        "int hand_forward_dynamics_checked(const double *in, double *qdd);",
        "int handf32_forward_dynamics_checked(const float *in, float *qdd);",
        HARNESS,
    ]
    for name in used:
        spec = specs[name]
        n_in = input_size(spec)
        lines.append(f"void sympy_{name}(const double *in, double *out);")
        lines.append(ours_wrapper(spec, "ours", "double"))
        lines.append(casadi_wrapper(spec))
        lo, hi = zip(*input_ranges(spec), strict=True)
        lines.append(f"static const double lo_{name}[{n_in}] = {{{', '.join(map(repr, lo))}}};")
        lines.append(f"static const double hi_{name}[{n_in}] = {{{', '.join(map(repr, hi))}}};")
        lines.append(
            f"static void sympy_w_{name}(const void *in, void *out) "
            f"{{ sympy_{name}((const double *)in, (double *)out); }}"
        )
    # float32 prototypes: our signatures with float and the renamed symbols.
    for name in used:
        lines.append(prototype(specs[name], f"f32_wmr_{name}", "float", "wmr_params_f32_t",
                               "wmr_status_t"))
    members = ", ".join(p.c_field for p in LUMPED)  # wmr_params_t's, in order
    lines.insert(0, f"typedef struct {{ float {members}; }} wmr_params_f32_t;")
    for name in used:
        lines.append(
            ours_wrapper(specs[name], "ours32", "float", "wmr_params_f32_t")
        )
    # libm sin/cos prototypes: our signatures under the renamed symbols.
    for name in (n for n in used if uses_trig(specs[n])):
        spec = specs[name]
        lines.append(prototype(spec, f"lm_wmr_{name}", "double", "wmr_params_t",
                               "wmr_status_t"))
        lines.append(ours_wrapper(spec, "ourslm", "double").replace(
            f"    wmr_{name}(", f"    lm_wmr_{name}("))
    if unchecked:
        lines.insert(0, '#include "wmrn_model.h"')
    for spec in unchecked:
        lines.append(ours_wrapper(spec, "oursn", "double", c_prefix="wmrn"))
    for name in HAND_WRITTEN & set(used):
        lines.append(
            f"static void hand_w_{name}(const void *in, void *out) "
            f"{{ hand_{name}((const double *)in, (double *)out); }}"
        )
    for name in used:
        if specs[name].prepared:
            lines.append(prepared_wrapper(specs[name]))
    for name in HAND_CHECKED & set(used):
        lines.append(
            f"static void handc_w_{name}(const void *in, void *out) "
            f"{{ (void)hand_{name}_checked((const double *)in, (double *)out); }}"
        )
        lines.append(
            f"static void handc32_w_{name}(const void *in, void *out) "
            f"{{ (void)handf32_{name}_checked((const float *)in, (float *)out); }}"
        )
    lines.append("int main(int argc, char **argv) {")
    lines.append(
        "    long calls = argc > 1 ? atol(argv[1]) : 1000000; "
        "int repeats = argc > 2 ? atoi(argv[2]) : 5;"
    )
    lines.append("    bench_case cases[] = {")
    for c in cases:
        name, variant = c["spec"], c["variant"]
        spec = specs[name]
        fn = {
            "ours": f"ours_{name}",
            "ours_float32": f"ours32_{name}",
            "ours_unchecked": f"oursn_{name}",
            "ours_prepared": f"oursp_{name}",
            "ours_libm": f"ourslm_{name}",
            "casadi": f"casadi_w_{name}",
            "sympy": f"sympy_w_{name}",
            "hand": f"hand_w_{name}",
            "hand_checked": f"handc_w_{name}",
            "hand_checked_float32": f"handc32_w_{name}",
        }[variant]
        lines.append(
            f'        {{"{name}", "{variant}", {fn}, {input_size(spec)}, '
            f"{sum(output_sizes(spec))}, {int(variant.endswith('float32'))}, "
            f"lo_{name}, hi_{name}, "
            f"{f'prepare_{name}' if variant == 'ours_prepared' else '0'}}},"
        )
    lines.append(
        "    };\n"
        "    return run_all(cases, sizeof cases / sizeof cases[0], calls, repeats);\n}"
    )
    src = workdir / "bench_main.c"
    head = "#define _POSIX_C_SOURCE 199309L\n#include <stdlib.h>\n#include <string.h>\n"
    src.write_text(head + "\n".join(lines))
    exe = workdir / "bench"
    subprocess.run(
        [
            "gcc",
            *CFLAGS,
            f"-I{GENERATED_C}",
            f"-I{workdir}",
            f"-I{CSRC}",
            str(src),
            *objs,
            "-lm",
            "-o",
            str(exe),
        ],
        check=True,
    )
    return exe


def c_cases(specs: dict[str, FunctionSpec]) -> list[dict[str, Any]]:
    kernels = sorted({k for ks in STEP_KERNELS.values() for k in ks})
    cases = []
    for name in (*MODEL_FUNCTIONS, *kernels):
        variants = ["ours", "ours_float32", "casadi", "sympy"]
        if specs[name].returns_status:
            variants.append("ours_unchecked")
        if specs[name].prepared:
            variants.append("ours_prepared")
        if uses_trig(specs[name]):
            variants.append("ours_libm")
        if name in HAND_WRITTEN:
            variants.append("hand")
        if name in HAND_CHECKED:
            variants += ["hand_checked", "hand_checked_float32"]
        cases += [{"spec": name, "variant": v} for v in variants]
    return cases


def run_c(calls: int, repeats: int) -> list[dict[str, Any]]:
    specs = specs_by_name()
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_bench(Path(tmp), c_cases(specs), specs)
        proc = subprocess.run(
            [str(exe), str(calls), str(repeats)], check=False, capture_output=True, text=True
        )
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0:  # a variant disagreed with ours: nothing is timed
        raise RuntimeError(f"C benchmark refused to time: {rows or proc.stderr}")
    return rows


def spread(values: list[float]) -> dict[str, float]:
    """Median, min and max of repeated measurements (what every table reports)."""
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def summarise_c(rows: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, float]]:
    out = {}
    for r in rows:
        out[(r["function"], r["variant"])] = spread(r["ns"])
    # Ratios per repetition (both timed in the same repetition): median, min, max.
    ns_of = {(r["function"], r["variant"]): r["ns"] for r in rows}
    for f, num, den in RATIO_PAIRS:
        if (f, num) in ns_of and (f, den) in ns_of:
            ratios = [a / b for a, b in zip(ns_of[(f, num)], ns_of[(f, den)], strict=True)]
            out[(f"{f}_ratio", f"{num}/{den}")] = spread(ratios)
    # Controller steps: sum of their kernels' medians (and of mins and maxes).
    for ctrl, kernels in STEP_KERNELS.items():
        for variant in ("ours", "ours_float32", "casadi", "sympy"):
            parts = [out[(k, variant)] for k in kernels]
            out[(f"{ctrl}_step_kernels", variant)] = {
                key: sum(p[key] for p in parts) for key in ("median", "min", "max")
            }
    return out
