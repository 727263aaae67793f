"""``python -m runtime bench`` (``make bench``): our generated code against CasADi's
generated C, plain SymPy C, hand-written C and NumPy, all measured in one run.

C: one executable holds every variant (our double and float32 builds — the float objects'
symbols renamed — CasADi's ``CodeGenerator`` output, ``sympy.ccode`` after ``cse``, and
hand-written C) so they share one process, one compiler (gcc -O2) and one input table.
Each case: median, min and max over ``repeats`` repetitions of ``calls`` calls cycling
through 256 pre-generated input sets through a function pointer, outputs summed into a
printed checksum so nothing can be hoisted or removed.

Writes ``BENCHMARKS.md`` and ``benchmarks.json`` at the repository root.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import timeit
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from codegen.backends import c as c_backend
from codegen.backends.c.config import CConfig, StatusCode
from codegen.backends.casadi import generate_c, to_casadi
from codegen.cse import count_ops, cse_function
from codegen.spec import FunctionSpec
from codegen.wmr_functions import law_specs, model_specs
from runtime.cbuild import GENERATED_C

ROOT = Path(__file__).resolve().parent.parent
CSRC = Path(__file__).resolve().parent / "csrc"
CFLAGS = ["-std=c99", "-O2"]
MODEL_FUNCTIONS = ("mass_matrix", "bias_forces", "forward_dynamics", "kinematics")
# One controller step = the kernels it evaluates (paper formulation).
STEP_KERNELS = {
    "tdc": ("paper_tde", "paper_tdc_law"),
    "tdroc": ("paper_tde", "paper_tdroc_gain", "paper_tdroc_law"),
    "roc": ("paper_roc_law",),
    "asmc": ("paper_asmc_law",),
}
HAND_WRITTEN = set(MODEL_FUNCTIONS)


def specs_by_name() -> dict[str, FunctionSpec]:
    return {s.name: s for s in (*model_specs(), *law_specs())}


def input_size(spec: FunctionSpec) -> int:
    return len(spec.input_symbols())


def output_sizes(spec: FunctionSpec) -> list[int]:
    return [len(a.exprs) for a in spec.outputs]


def input_ranges(spec: FunctionSpec) -> list[tuple[float, float]]:
    """Plausible ranges per flattened input: parameters ±20 % around Drishti's, angles,
    rates, gains; keeps every variant on the same, physically meaningful inputs."""
    drishti = {"m": 36.0, "I": 5.72, "K": 0.34, "I_w": 0.07, "r": 0.096, "b": 0.414, "d": 0.12}
    out = []
    for s in spec.input_symbols():
        name = str(s)
        if name in drishti:
            out.append((0.8 * drishti[name], 1.2 * drishti[name]))
        elif name.startswith(("w", "eps", "h", "span", "k1", "k2", "p12", "p22", "gamma")):
            out.append((0.1, 1.0))
        elif name in ("alpha",):
            out.append((0.1, 0.5))
        else:
            out.append((-3.0, 3.0))
    return out


def sympy_c(specs: Sequence[FunctionSpec]) -> str:
    """Plain SymPy: ``cse`` then ``ccode``, one ``sympy_<name>(in, out)`` per function."""
    import sympy as sp

    lines = ["#include <math.h>", ""]
    for spec in specs:
        syms = spec.input_symbols()
        names = {s: sp.Symbol(f"in[{k}]") for k, s in enumerate(syms)}
        exprs = [e.xreplace(names) for a in spec.outputs for e in a.exprs]
        temps, reduced = sp.cse(exprs)
        lines.append(f"void sympy_{spec.name}(const double *in, double *out)\n{{")
        for t, e in temps:
            lines.append(f"    const double {t} = {sp.ccode(e)};")
        for k, e in enumerate(reduced):
            lines.append(f"    out[{k}] = {sp.ccode(e)};")
        lines.append("}\n")
    return "\n".join(lines)


def _ours_wrapper(spec: FunctionSpec, prefix: str, real: str) -> str:
    """``<prefix>_<name>(in, out)`` calling our generated function (params struct first)."""
    args, off = [], 0
    body = []
    for a in spec.inputs:
        n = len(a.all_symbols())
        if a.kind == "params":
            fields = ", ".join(f"in[{off + k}]" for k in range(n))
            body.append(f"    const wmr_params_t {a.name}_s = {{{fields}}};")
            args.append(f"&{a.name}_s")
        else:
            args.append(f"in + {off}")
        off += n
    outs, o = [], 0
    for size in output_sizes(spec):
        outs.append(f"out + {o}")
        o += size
    fn = f"{'f32_' if real == 'float' else ''}wmr_{spec.name}"
    return (
        f"static void {prefix}_{spec.name}(const void *in_, void *out_)\n{{\n"
        f"    const {real} *in = (const {real} *)in_;\n    {real} *out = ({real} *)out_;\n"
        + "\n".join(body)
        + f"\n    {fn}({', '.join(args + outs)});\n}}\n"
    )


def _casadi_wrapper(spec: FunctionSpec) -> str:
    sizes = [len(a.all_symbols()) for a in spec.inputs]
    offs = np.cumsum([0, *sizes])[:-1]
    args = ", ".join(f"in + {o}" for o in offs)
    out_offs = np.cumsum([0, *output_sizes(spec)])[:-1]
    res = ", ".join(f"out + {o}" for o in out_offs)
    return (
        f"static void casadi_w_{spec.name}(const void *in_, void *out_)\n{{\n"
        f"    const double *in = (const double *)in_;\n    double *out = (double *)out_;\n"
        f"    const double *arg[{len(sizes)}] = {{{args}}};\n"
        f"    double *res[{len(out_offs)}] = {{{res}}};\n"
        f"    casadi_{spec.name}(arg, res, 0, 0, 0);\n}}\n"
    )


HARNESS = r"""
#include <stdio.h>
#include <time.h>

typedef void (*bench_fn)(const void *in, void *out);
typedef struct { const char *function; const char *variant; bench_fn fn; int n_in; int n_out;
                 int is_float; const double *lo; const double *hi; } bench_case;

#define NSETS 256
static double now_ns(void) {
    struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}
static unsigned long long rng = 88172645463325252ULL;
static double urand(void) {
    rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}
static double din[NSETS * 512], dout[512];
static float fin[NSETS * 512], fout[512];

static void run(const bench_case *c, long calls, int repeats) {
    int k, rep; long i; double sink = 0.0;
    rng = 88172645463325252ULL;  /* the same inputs for every variant of a function */
    for (k = 0; k < NSETS * c->n_in; ++k) {
        int j = k % c->n_in;
        din[k] = c->lo[j] + (c->hi[j] - c->lo[j]) * urand();
        fin[k] = (float)din[k];
    }
    printf("{\"function\": \"%s\", \"variant\": \"%s\", \"ns\": [", c->function, c->variant);
    for (rep = 0; rep < repeats; ++rep) {
        double t0 = now_ns(), t1;
        for (i = 0; i < calls; ++i) {
            const int set = (int)(i & (NSETS - 1));
            if (c->is_float) {
                c->fn(fin + set * c->n_in, fout);
                sink += (double)fout[i % c->n_out];
            } else {
                c->fn(din + set * c->n_in, dout);
                sink += dout[i % c->n_out];
            }
        }
        t1 = now_ns();
        printf("%s%.4f", rep ? ", " : "", (t1 - t0) / (double)calls);
    }
    printf("], \"checksum\": %.15e}\n", sink);
    fflush(stdout);
}
"""


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
    for src in gen_sources:  # ours, float32, symbols renamed wmr_ -> f32_wmr_
        obj = workdir / f"f_{src.stem}.o"
        subprocess.run(
            ["gcc", *CFLAGS, "-DWMR_FLOAT32", "-c", f"-I{GENERATED_C}", str(src), "-o", str(obj)],
            check=True,
        )
        names = subprocess.run(
            ["nm", "--defined-only", "-g", str(obj)], check=True, capture_output=True, text=True
        ).stdout.split()
        mapping = workdir / f"{src.stem}.redefine"
        mapping.write_text("".join(f"{n} f32_{n}\n" for n in names if n.startswith("wmr_")))
        # Undefined references to other wmr_ objects must be renamed too.
        undefined = subprocess.run(
            ["nm", "-u", str(obj)], check=True, capture_output=True, text=True
        ).stdout.split()
        extra = "".join(f"{n} f32_{n}\n" for n in undefined if n.startswith("wmr_"))
        mapping.write_text(mapping.read_text() + extra)
        subprocess.run(["objcopy", f"--redefine-syms={mapping}", str(obj)], check=True)
        objs.append(str(obj))
    # Ours without input/guard/output validation, to measure what the checks cost: the
    # same specs rendered by the same backend under another prefix (wmrn_).
    unchecked = [
        replace(specs[n], returns_status=False, guards=(), nonfinite_input="",
                nonfinite_output="")
        for n in used if specs[n].returns_status
    ]
    cfg = CConfig(prefix="wmrn_", types_header="wmrn_types.h", real_type="wmrn_real_t",
                  status_type="wmrn_status_t", params_ctype="wmrn_params_t",
                  literal_macro="WMRN_LIT", status_codes=(StatusCode("WMRN_OK", 0, "ok"),))
    for fname, text in c_backend.render_all({"wmrn_model": unchecked}, cfg).items():
        (workdir / fname).write_text(text)
    sources = [workdir / "casadi_gen.c", workdir / "sympy_gen.c", CSRC / "hand_model.c"]
    if unchecked:
        sources.append(workdir / "wmrn_model.c")
    for src in sources:
        obj = workdir / f"x_{src.stem}.o"
        subprocess.run(
            ["gcc", *CFLAGS, "-c", f"-I{CSRC}", f"-I{workdir}", str(src), "-o", str(obj)],
            check=True,
        )
        objs.append(str(obj))
    # Harness.
    lines = [
        '#include "wmr_model.h"',
        '#include "wmr_laws.h"',
        '#include "casadi_gen.h"',
        '#include "hand_model.h"',
        HARNESS,
    ]
    for name in used:
        spec = specs[name]
        n_in = input_size(spec)
        lines.append(f"void sympy_{name}(const double *in, double *out);")
        lines.append(_ours_wrapper(spec, "ours", "double"))
        lines.append(_casadi_wrapper(spec))
        lo, hi = zip(*input_ranges(spec), strict=True)
        lines.append(f"static const double lo_{name}[{n_in}] = {{{', '.join(map(repr, lo))}}};")
        lines.append(f"static const double hi_{name}[{n_in}] = {{{', '.join(map(repr, hi))}}};")
        lines.append(
            f"static void sympy_w_{name}(const void *in, void *out) "
            f"{{ sympy_{name}((const double *)in, (double *)out); }}"
        )
    # float32 prototypes: our signatures with float and the renamed symbols.
    for name in used:
        spec = specs[name]
        params = []
        for a in spec.inputs:
            params.append("const wmr_params_f32_t *" if a.kind == "params" else "const float *")
        params += ["float *"] * len(spec.outputs)
        lines.append(f"void f32_wmr_{name}({', '.join(params)});")
    lines.insert(0, "typedef struct { float m, Iz, K, Iw, r, b, d; } wmr_params_f32_t;")
    for name in used:
        lines.append(
            _ours_wrapper(specs[name], "ours32", "float").replace(
                "const wmr_params_t", "const wmr_params_f32_t"
            )
        )
    if unchecked:
        lines.insert(0, '#include "wmrn_model.h"')
    for spec in unchecked:
        lines.append(_ours_wrapper(spec, "oursn", "double").replace(
            "const wmr_params_t", "const wmrn_params_t").replace(
            f"wmr_{spec.name}(", f"wmrn_{spec.name}("))
    for name in HAND_WRITTEN & set(used):
        lines.append(
            f"static void hand_w_{name}(const void *in, void *out) "
            f"{{ hand_{name}((const double *)in, (double *)out); }}"
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
            "casadi": f"casadi_w_{name}",
            "sympy": f"sympy_w_{name}",
            "hand": f"hand_w_{name}",
        }[variant]
        lines.append(
            f'        {{"{name}", "{variant}", {fn}, {input_size(spec)}, '
            f"{sum(output_sizes(spec))}, {int(variant == 'ours_float32')}, "
            f"lo_{name}, hi_{name}}},"
        )
    lines.append(
        "    };\n    size_t k;\n"
        "    for (k = 0; k < sizeof cases / sizeof cases[0]; ++k) "
        "run(&cases[k], calls, repeats);\n    return 0;\n}"
    )
    src = workdir / "bench_main.c"
    src.write_text("#define _POSIX_C_SOURCE 199309L\n#include <stdlib.h>\n" + "\n".join(lines))
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
        if name in HAND_WRITTEN:
            variants.append("hand")
        cases += [{"spec": name, "variant": v} for v in variants]
    return cases


def run_c(calls: int, repeats: int) -> list[dict[str, Any]]:
    specs = specs_by_name()
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_bench(Path(tmp), c_cases(specs), specs)
        out = subprocess.run(
            [str(exe), str(calls), str(repeats)], check=True, capture_output=True, text=True
        ).stdout
    return [json.loads(line) for line in out.splitlines() if line.startswith("{")]


def summarise_c(rows: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, float]]:
    out = {}
    for r in rows:
        ns = r["ns"]
        out[(r["function"], r["variant"])] = {
            "median": statistics.median(ns),
            "min": min(ns),
            "max": max(ns),
        }
    # Controller steps: sum of their kernels' medians (and of mins and maxes).
    for ctrl, kernels in STEP_KERNELS.items():
        for variant in ("ours", "ours_float32", "casadi", "sympy"):
            parts = [out[(k, variant)] for k in kernels]
            out[(f"{ctrl}_step_kernels", variant)] = {
                key: sum(p[key] for p in parts) for key in ("median", "min", "max")
            }
    return out


def casadi_op_count(spec: FunctionSpec) -> dict[str, int]:
    import casadi as ca

    f = to_casadi(spec)
    names = {
        ca.OP_ADD: "add",
        ca.OP_SUB: "add",
        ca.OP_MUL: "mul",
        ca.OP_DIV: "div",
        ca.OP_SIN: "sin/cos",
        ca.OP_COS: "sin/cos",
        ca.OP_SQRT: "sqrt",
        ca.OP_SQ: "mul",
        ca.OP_NEG: "neg",
        ca.OP_FMAX: "other",
        ca.OP_FABS: "other",
        ca.OP_TWICE: "add",
        ca.OP_INV: "div",
        ca.OP_POW: "other",
        ca.OP_CONSTPOW: "other",
    }
    counts: dict[str, int] = {}
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op in names:
            counts[names[op]] = counts.get(names[op], 0) + 1
    counts.pop("neg", None)
    return counts


def python_bench(number: int) -> list[dict[str, Any]]:
    """Generated Python vs hand-written NumPy (if present), sympy.lambdify and CasADi."""
    import casadi as ca
    import sympy as sp

    from runtime.generated_modules import robot, wmr_model

    p = dict(robot.PARAMS)
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, 5)
    qdot = rng.uniform(-1, 1, 5)
    tau = rng.uniform(-1, 1, 2)
    specs = specs_by_name()
    fd = specs["forward_dynamics"]
    syms = fd.input_symbols()
    lam = sp.lambdify(syms, [e for a in fd.outputs for e in a.exprs], "numpy")
    pvec = [p[k] for k in ("m", "I", "K", "Iw", "r", "b", "d")]
    flat = [*pvec, *q, *qdot, *tau]
    f_ca = to_casadi(fd)
    cases: dict[str, Callable[[], object]] = {
        "ours (generated Python)": lambda: wmr_model.forward_dynamics(q, qdot, tau, p),
        "sympy.lambdify": lambda: lam(*flat),
        "casadi.Function": lambda: f_ca(ca.DM(pvec), ca.DM(q), ca.DM(qdot), ca.DM(tau)),
    }
    try:
        from runtime.handwritten import model as hand

        cases["hand-written NumPy"] = lambda: hand.forward_dynamics(q, qdot, tau, p)
    except (ImportError, AttributeError):
        pass
    rows = []
    for label, fn in cases.items():
        times = timeit.repeat(fn, number=number, repeat=5)
        per = [t / number * 1e6 for t in times]
        rows.append(
            {
                "function": "forward_dynamics",
                "variant": label,
                "us": {"median": statistics.median(per), "min": min(per), "max": max(per)},
            }
        )
    return rows


DERIVATION_SNIPPET = """
import time
t0 = time.perf_counter()
from modeling import wmr
s = wmr.wmr_system()
for name in ("mass_matrix", "bias", "null_space", "null_space_rate", "reduced_mass_matrix",
             "reduced_bias", "minimal_mass_matrix", "minimal_bias", "reduced_mass_matrix_inverse"):
    getattr(s, name)
s.multipliers_given_accelerations(wmr.tau)
s.reduced_forward_dynamics(wmr.tau)
wmr.lumped_relations(wmr.physical_bodies())
print(time.perf_counter() - t0)
"""


def toolchain_times() -> dict[str, float]:
    """Cold-start wall times in fresh interpreters (median of 3 for the derivation)."""
    runs = [
        float(
            subprocess.run(
                [sys.executable, "-c", DERIVATION_SNIPPET],
                check=True,
                capture_output=True,
                text=True,
                cwd=ROOT,
            ).stdout
        )
        for _ in range(3)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "codegen", "--out", tmp],
            check=True,
            capture_output=True,
            cwd=ROOT,
        )
        model = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "runtime", "reproduce", "--out", tmp + "/r"],
            check=True,
            capture_output=True,
            cwd=ROOT,
        )
        rep = time.perf_counter() - t0
    return {"derivation_s": statistics.median(runs), "make_model_s": model, "reproduce_s": rep}


def write_report(
    c: dict[tuple[str, str], dict[str, float]],
    py: list[dict[str, Any]],
    ops: dict[str, dict[str, Any]],
    tool: dict[str, float],
    calls: int,
    repeats: int,
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
        "| function | ours double | ours float32 | ours, no validation | CasADi C | SymPy ccode "
        "| hand-written |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for f in funcs:
        ours = c[(f, "ours")]["median"]
        cells = []
        for v in ("ours", "ours_float32", "ours_unchecked", "casadi", "sympy", "hand"):
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
        "A controller step here is the sum of its kernels (TDE (17), TDROC gain (25), law);",
        "our complete `wmr_<ctrl>_step` adds validation, history and saturation on top.",
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
    parser = argparse.ArgumentParser(prog="python -m runtime bench")
    parser.add_argument("--calls", type=int, default=1_000_000, help="calls per repetition")
    parser.add_argument("--repeats", type=int, default=5, help="repetitions (≥ 5)")
    parser.add_argument("--out", type=Path, default=ROOT, help="folder for the reports")
    args = parser.parse_args(argv)
    if args.calls < 1 or args.repeats < 1:
        print("error: --calls and --repeats must be positive", file=sys.stderr)
        return 2
    print("C benchmarks ...", flush=True)
    c = summarise_c(run_c(args.calls, args.repeats))
    print("Python benchmarks ...", flush=True)
    py = python_bench(max(1, args.calls // 100))
    specs = specs_by_name()
    ops = {}
    for name in (*MODEL_FUNCTIONS, *sorted({k for ks in STEP_KERNELS.values() for k in ks})):
        casadi_counts = casadi_op_count(specs[name])
        ops[name] = {
            "ours": count_ops(cse_function(specs[name].checked_spec())).summary(),
            "casadi": ", ".join(f"{v} {k}" for k, v in sorted(casadi_counts.items())),
        }
    print("toolchain timings ...", flush=True)
    tool = toolchain_times()
    text = write_report(c, py, ops, tool, args.calls, args.repeats)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "BENCHMARKS.md").write_text(text)
    (args.out / "benchmarks.json").write_text(
        json.dumps(
            {
                "c_ns": {f"{f}/{v}": s for (f, v), s in sorted(c.items())},
                "python_us": py,
                "ops": ops,
                "toolchain": tool,
            },
            indent=1,
            sort_keys=True,
        )
        + "\n"
    )
    print(text)
    return 0
