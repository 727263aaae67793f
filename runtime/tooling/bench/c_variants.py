"""What the C benchmark compares: the functions (model functions and the kernels of each
controller step), their plausible input ranges, and the C source of each variant — plain
SymPy ``ccode``, the ``(in, out)`` wrappers around ours and CasADi's functions, and the
timing harness every variant runs in.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from codegen.backends.casadi import to_casadi
from codegen.robot_functions import law_specs, model_specs
from codegen.spec import Argument, FunctionSpec
from modeling.robots.drishti.model import robot_model

MODEL_FUNCTIONS = ("mass_matrix", "bias_forces", "forward_dynamics", "kinematics")
# One controller step = the kernels it evaluates (paper formulation).
STEP_KERNELS = {
    "tdc": ("paper_tde", "paper_tdc_law"),
    "tdroc": ("paper_tde", "paper_omega_difference", "tdroc_weighted_gain", "paper_tdroc_law"),
    "roc": ("paper_roc_law",),
    "asmc": ("paper_asmc_law",),
}
HAND_WRITTEN = set(MODEL_FUNCTIONS)
# Hand-written with the same checks and status codes as ours (csrc/hand_tdroc.c).
HAND_CHECKED = {"forward_dynamics"}


def specs_by_name() -> dict[str, FunctionSpec]:
    return {s.name: s for s in (*model_specs(robot_model()), *law_specs(robot_model()))}


def input_size(spec: FunctionSpec) -> int:
    return len(spec.input_symbols())


def output_sizes(spec: FunctionSpec) -> list[int]:
    return [len(a.exprs) for a in spec.outputs]


DRISHTI_NOMINAL = {"m": 36.0, "I": 5.72, "K": 0.34, "I_w": 0.07, "r": 0.096, "b": 0.414,
                   "d": 0.12}


def input_ranges(spec: FunctionSpec, nominal: Mapping[str, float] = DRISHTI_NOMINAL,
                 spread: float = 0.2) -> list[tuple[float, float]]:
    """Plausible ranges per flattened input: parameters (``nominal``, by symbol name)
    within ±``spread`` of their values, angles, rates, gains; keeps every variant on the
    same, physically meaningful inputs."""
    out = []
    for s in spec.input_symbols():
        name = str(s)
        if name in nominal:
            lo, hi = (1 - spread) * nominal[name], (1 + spread) * nominal[name]
            out.append((min(lo, hi), max(lo, hi)))
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
        names: dict[sp.Basic, sp.Expr] = {s: sp.Symbol(f"in[{k}]") for k, s in enumerate(syms)}
        for symbol, definition in spec.definitions:  # plain SymPy sees the expanded outputs
            names[symbol] = definition.xreplace(names)
        exprs = [e.xreplace(names) for a in spec.outputs for e in a.exprs]
        temps, reduced = sp.cse(exprs)
        lines.append(f"void sympy_{spec.name}(const double *in, double *out)\n{{")
        for t, e in temps:
            lines.append(f"    const double {t} = {sp.ccode(e)};")
        for k, e in enumerate(reduced):
            lines.append(f"    out[{k}] = {sp.ccode(e)};")
        lines.append("}\n")
    return "\n".join(lines)


def params_in_place(arg: Argument, ctype: str, real: str, offset: int, tag: str
                    ) -> tuple[str, str]:
    """The parameters struct ``ctype`` read in place from the flat inputs at ``offset``,
    as the other variants read theirs (no per-call copy in the timed loop): the argument's
    C expression, and compile-time checks that the struct is exactly those ``real``s in
    the spec's order (a layout that differs fails to compile)."""
    n = len(arg.fields)
    checks = [f"typedef char {tag}_size[sizeof({ctype}) == {n} * sizeof({real}) ? 1 : -1];"]
    checks += [f"typedef char {tag}_at{k}[offsetof({ctype}, {f.c_field}) == {k} * "
               f"sizeof({real}) ? 1 : -1];" for k, f in enumerate(arg.fields)]
    return f"(const {ctype} *)(in + {offset})", "\n".join(checks) + "\n"


def ours_wrapper(spec: FunctionSpec, prefix: str, real: str, params_ctype: str = "",
                 c_prefix: str = "wmr") -> str:
    """``<prefix>_<name>(in, out)`` calling our generated ``<c_prefix>_<name>``
    (``f32_<c_prefix>_<name>`` in float), its parameters struct (``params_ctype``, default
    ``<c_prefix>_params_t``) read in place: :func:`params_in_place`."""
    params_ctype = params_ctype or f"{c_prefix}_params_t"
    args, off = [], 0
    checks = ""
    for a in spec.inputs:
        n = len(a.all_symbols())
        if a.kind == "params":
            expr, checks = params_in_place(a, params_ctype, real, off,
                                           f"{prefix}_{spec.name}_{a.name}")
            args.append(expr)
        else:
            args.append(f"in + {off}")
        off += n
    outs, o = [], 0
    for size in output_sizes(spec):
        outs.append(f"out + {o}")
        o += size
    fn = f"{'f32_' if real == 'float' else ''}{c_prefix}_{spec.name}"
    return (
        checks
        + f"static void {prefix}_{spec.name}(const void *in_, void *out_)\n{{\n"
        f"    const {real} *in = (const {real} *)in_;\n    {real} *out = ({real} *)out_;\n"
        f"    {fn}({', '.join(args + outs)});\n}}\n"
    )


def prepared_wrapper(spec: FunctionSpec, prefix: str = "oursp") -> str:
    """For a spec with ``prepared``: ``prepare_<name>``, which prepares the parameters of
    every input set once (``wmr_model_prepare``, before any timing) into a table of
    records (the prepared struct, then the other inputs), and ``<prefix>_<name>(record,
    out)`` calling ``wmr_<name>_prepared`` on one record: the timed call."""
    params = spec.inputs[0]
    if params.kind != "params" or any(a.kind == "params" for a in spec.inputs[1:]):
        raise ValueError(f"{spec.name}: the parameters must be the only params input, first")
    n_p = len(params.all_symbols())
    n_rest = input_size(spec) - n_p
    fields = ", ".join(f"x[{k}]" for k in range(n_p))
    args, off = [], 0
    for a in spec.inputs[1:]:
        args.append(f"r->x + {off}")
        off += len(a.all_symbols())
    outs, o = [], 0
    for size in output_sizes(spec):
        outs.append(f"out + {o}")
        o += size
    name = spec.name
    return (
        f"typedef struct {{ wmr_model_prepared_t prepared; double x[{n_rest}]; }} "
        f"prep_{name}_t;\n"
        f"static prep_{name}_t prep_{name}_table[NSETS];\n"
        f"static const void *prepare_{name}(const double *in, int nsets, int n_in, "
        f"size_t *stride)\n{{\n"
        f"    int set, k;\n"
        f"    for (set = 0; set < nsets; ++set) {{\n"
        f"        const double *x = in + set * n_in;\n"
        f"        const wmr_params_t p = {{{fields}}};\n"
        f"        prep_{name}_t *r = &prep_{name}_table[set];\n"
        f"        if (wmr_model_prepare(&p, &r->prepared) != WMR_OK) r->prepared.magic = 0;\n"
        f"        for (k = 0; k < {n_rest}; ++k) r->x[k] = x[{n_p} + k];\n"
        f"    }}\n"
        f"    *stride = sizeof prep_{name}_table[0];\n"
        f"    return prep_{name}_table;\n}}\n"
        f"static void {prefix}_{name}(const void *in_, void *out_)\n{{\n"
        f"    const prep_{name}_t *r = (const prep_{name}_t *)in_;\n"
        f"    double *out = (double *)out_;\n"
        f"    wmr_{name}_prepared(&r->prepared, {', '.join(args + outs)});\n}}\n"
    )


def casadi_wrapper(spec: FunctionSpec, prefix: str = "casadi_", real: str = "double") -> str:
    """``<prefix>w_<name>(in, out)`` calling CasADi's generated ``<prefix><name>`` (declared
    here: CasADi's headers of two precisions cannot both be included) with the arg/res
    pointer arrays into the flat inputs and outputs and work vectors as large as the
    function asks for."""
    function = to_casadi(spec)
    offs = np.cumsum([0, *(len(a.all_symbols()) for a in spec.inputs)])[:-1]
    out_offs = np.cumsum([0, *output_sizes(spec)])[:-1]
    name = f"{prefix}{spec.name}"
    return (
        f"int {name}(const {real} **arg, {real} **res, long long int *iw, {real} *w, int mem);\n"
        f"static {real} {name}_wv[{max(1, function.sz_w())}];\n"
        f"static long long int {name}_iwv[{max(1, function.sz_iw())}];\n"
        f"static void {prefix}w_{spec.name}(const void *in_, void *out_)\n{{\n"
        f"    const {real} *in = (const {real} *)in_;\n    {real} *out = ({real} *)out_;\n"
        f"    const {real} *arg[{len(offs)}] = {{{', '.join(f'in + {o}' for o in offs)}}};\n"
        f"    {real} *res[{len(out_offs)}] = {{{', '.join(f'out + {o}' for o in out_offs)}}};\n"
        f"    (void){name}(arg, res, {name}_iwv, {name}_wv, 0);\n}}\n"
    )


def prototype(spec: FunctionSpec, function: str, real: str, params_ctype: str,
              status_type: str) -> str:
    """The C declaration of our generated ``spec`` as ``function`` (a renamed object's
    symbol: the float32 or libm-trig build), in ``real`` with ``params_ctype``."""
    params = [f"const {params_ctype} *" if a.kind == "params" else f"const {real} *"
              for a in spec.inputs] + [f"{real} *"] * len(spec.outputs)
    ret = status_type if spec.returns_status else "void"
    return f"{ret} {function}({', '.join(params)});"


HARNESS = r"""
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <time.h>

#define NSETS 256
typedef void (*bench_fn)(const void *in, void *out);
/* A variant whose inputs are records of its own (the prepared parameters and the other
   inputs), built from the input sets once, before it is checked or timed. */
typedef const void *(*bench_prep)(const double *in, int nsets, int n_in, size_t *stride);
typedef struct { const char *function; const char *variant; bench_fn fn; int n_in; int n_out;
                 int is_float; const double *lo; const double *hi; bench_prep prep; } bench_case;

#define MAX_REPEATS 64
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
static double ref_out[NSETS * 64];

/* The same inputs for every variant of a function; a variant with records of its own
   gets them here (built from the same input sets, outside any timing). */
static const char *fill(const bench_case *c, size_t *stride) {
    int k;
    rng = 88172645463325252ULL;
    for (k = 0; k < NSETS * c->n_in; ++k) {
        int j = k % c->n_in;
        din[k] = c->lo[j] + (c->hi[j] - c->lo[j]) * urand();
        fin[k] = (float)din[k];
    }
    *stride = 0;
    return c->prep ? (const char *)c->prep(din, NSETS, c->n_in, stride) : 0;
}

/* Before any timing: every variant's outputs on the NSETS inputs against the first
   variant of the same function (ours, double): 1e-9 (float32: 1e-3) relative to the
   largest output. Returns 0 when they agree. */
static int check(const bench_case *c, int is_ref) {
    int set, k;
    double scale = 1.0, worst = 0.0;
    size_t stride;
    const char *records = fill(c, &stride);
    for (set = 0; set < NSETS; ++set) {
        for (k = 0; k < c->n_out; ++k) { dout[k] = 0.0; fout[k] = 0.0f; }
        if (records) c->fn(records + (size_t)set * stride, dout);
        else if (c->is_float) c->fn(fin + set * c->n_in, fout);
        else c->fn(din + set * c->n_in, dout);
        for (k = 0; k < c->n_out; ++k) {
            const double x = c->is_float ? (double)fout[k] : dout[k];
            if (is_ref) ref_out[set * c->n_out + k] = x;
            const double ref = ref_out[set * c->n_out + k];
            if (fabs(ref) > scale) scale = fabs(ref);
            if (!(fabs(x - ref) <= worst)) worst = fabs(x - ref);
        }
    }
    if (!(worst <= (c->is_float ? 1e-3 : 1e-9) * scale)) {
        printf("{\"error\": \"%s/%s differs from ours by %.3e (scale %.3e)\"}\n",
               c->function, c->variant, worst, scale);
        return 1;
    }
    return 0;
}

static double time_once(const bench_case *c, long calls, double *sink) {
    long i;
    double t0, t1;
    size_t stride;
    const char *records = fill(c, &stride);
    t0 = now_ns();
    for (i = 0; i < calls; ++i) {
        const int set = (int)(i & (NSETS - 1));
        if (records) {
            c->fn(records + (size_t)set * stride, dout);
            *sink += dout[i % c->n_out];
        } else if (c->is_float) {
            c->fn(fin + set * c->n_in, fout);
            *sink += (double)fout[i % c->n_out];
        } else {
            c->fn(din + set * c->n_in, dout);
            *sink += dout[i % c->n_out];
        }
    }
    t1 = now_ns();
    return (t1 - t0) / (double)calls;
}

/* Check every case, then time them interleaved: each repetition times every case once. */
static int run_all(const bench_case *cases, size_t n, long calls, int repeats) {
    static double ns[256][MAX_REPEATS], sums[256];
    size_t k;
    int rep;
    for (k = 0; k < n; ++k) {
        const int is_ref = k == 0 || strcmp(cases[k].function, cases[k - 1].function) != 0;
        if (check(&cases[k], is_ref)) return 3;
    }
    if (repeats > MAX_REPEATS) repeats = MAX_REPEATS;
    for (rep = 0; rep < repeats; ++rep) {
        for (k = 0; k < n; ++k) ns[k][rep] = time_once(&cases[k], calls, &sums[k]);
    }
    for (k = 0; k < n; ++k) {
        printf("{\"function\": \"%s\", \"variant\": \"%s\", \"ns\": [", cases[k].function,
               cases[k].variant);
        for (rep = 0; rep < repeats; ++rep) printf("%s%.4f", rep ? ", " : "", ns[k][rep]);
        printf("], \"checksum\": %.15e}\n", sums[k]);
    }
    fflush(stdout);
    return 0;
}
"""
