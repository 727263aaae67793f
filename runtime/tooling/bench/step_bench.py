"""The full controller step benchmark: ``<prefix>_tdroc_step`` (what firmware calls) against
a hand-written step written to be fast under the same contract (``csrc/hand_tdroc.c`` for
Drishti, ``csrc/hand_trailer_tdroc.c`` for the trailer: :data:`STEP_ROBOTS`), on the
controller inputs of a recorded closed loop (consistent states, lawn-mower path), for each
robot, formulation (Drishti: paper, minimal; the trailer: minimal) and precision (double,
float32). Each robot also has an improved hand-written step (issue 52:
``csrc/hand_tdroc_fast.c``, ``csrc/hand_trailer_tdroc_fast.c``; norms and M-tilde x
inlined, one straight-line body per formulation, the kept constants read in place, the
configuration compared branch-free or by memcmp), checked and timed beside the old one.

One executable per formulation and precision (gcc -O2) holds every variant: ours
(run-time configuration), the hand-written step, both again built with the configuration
compiled in (ours: ``wmr freeze``'s header and ``-DWMR_TDROC_FROZEN``; hand: the same
configuration as a constant, ``-DHAND_FROZEN``) and ours with libm's sin/cos.
Before any timing it checks, against ours:

* the statuses of the bad-input cases: every configuration field made invalid (at
  ``_init`` and at a step), valid changes and sign flips of the configuration, NaN, ±Inf
  and out-of-bound values in each of the 5 n inputs, each NULL pointer, a state never
  initialised (frozen variants: the configuration refused at another address);
* the statuses and torques over the recording, and again with a bad input every seventh
  step (what an error step leaves behind: commit on success);

and refuses to time otherwise. Then the timing, interleaved: each repetition times every
variant once (in an order rotated per repetition) over whole passes of the recording (a
fresh ``_init`` before each pass, not timed). Ratios are taken per repetition (the two
variants timed moments apart) and reported as median and range over the repetitions of
every run.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.tooling.bench.c_bench import renamed_objects, spread
from runtime.tooling.firmware.build import frozen_define

BENCH_CSRC = Path(__file__).resolve().parent / "csrc"
CFLAGS = ["-std=c99", "-O2"]
FORMULATIONS = ("paper", "minimal")
PRECISIONS = ("double", "float32")
# ours = wmr_tdroc_step; hand = hand_tdroc_step; ours_frozen / hand_frozen = each with the
# configuration compiled in; ours_libm = wmr_tdroc_step built with -DWMR_LIBM_TRIG
# (libm's sin/cos, as the hand-written step uses), in both precisions: on an x86-64 host
# glibc's float32 sincosf is an FMA build that our portable one is not.
VARIANTS = ("ours", "hand", "ours_frozen", "hand_frozen", "ours_libm", "hand_fast",
            "hand_fast_frozen")
# The torques of every variant against ours over the recording, relative to the largest
# |tau|: double agrees to rounding; float32 to float rounding amplified by (17)'s 1/h.
TORQUE_TOLERANCE = {"double": 1e-9, "float32": 1e-4}
# (numerator, denominator) of each ratio the benchmark reports; the goals are <= 1.0.
RATIOS = (("ours", "hand"), ("ours_frozen", "hand_frozen"), ("ours_libm", "hand"),
          ("ours", "hand_fast"), ("ours_frozen", "hand_fast_frozen"),
          ("ours_libm", "hand_fast"))

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "HAND_HEADER"
#include "wmr_tdroc.h"

typedef wmr_real_t real;
typedef wmr_status_t (*init_fn)(void *state, const wmr_tdroc_config_t *config);
typedef wmr_status_t (*step_fn)(void *state, const wmr_tdroc_config_t *config,
    const real q[NQ], const real qdot[NQ], const real q_des[NQ], const real qdot_des[NQ],
    const real qddot_des[NQ], real tau[2]);

PROTOTYPES

typedef union { wmr_tdroc_state_t ours; hand_tdroc_state_t hand; } any_state;
typedef struct {
    const char *name; init_fn init; step_fn step; int frozen;
} variant;

static double now_ns(void) {
    struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e9 * (double)ts.tv_sec + (double)ts.tv_nsec;
}
static wmr_tdroc_config_t cfg;
static any_state states[NV];

static const wmr_tdroc_config_t *config_of(const variant *v) {
    return v->frozen == 1 ? &fz_wmr_tdroc_frozen_config
         : v->frozen == 2 ? &handfz_frozen_config
         : v->frozen == 3 ? &handfastfz_frozen_config : &cfg;
}

/* A fresh state for variant k (not timed). */
static void fresh(int k) {
    if (VARIANTS[k].init(&states[k], config_of(&VARIANTS[k])) != WMR_OK) {
        fprintf(stderr, "init failed: %s\n", VARIANTS[k].name); exit(2);
    }
}

/* One pass of the recording through variant k from its current state; statuses and
   torques into st, tq when given; with bad != 0, every seventh step gets a NaN rate. */
static double pass(int k, int *st, real *tq, int bad) {
    const variant *v = &VARIANTS[k];
    const wmr_tdroc_config_t *c = config_of(v);
    int i, s;
    real tau[2] = {0, 0}, sink = 0;
    for (i = 0; i < NSTEPS; ++i) {
        const real *in = IN[i];
        real spoiled[5 * NQ];
        if (bad && i % 7 == 3) {
            memcpy(spoiled, in, sizeof spoiled);
            spoiled[NQ + i % NQ] = (real)NAN;
            in = spoiled;
        }
        s = v->step(&states[k], c, in, in + NQ, in + 2 * NQ, in + 3 * NQ, in + 4 * NQ, tau);
        if (st != 0) { st[i] = s; tq[2 * i] = tau[0]; tq[2 * i + 1] = tau[1]; }
        sink += tau[0] + (real)s;
    }
    return (double)sink;
}

/* The bad-input cases: the status each variant returns. */
#define NCFG CONFIG_CASE_COUNT
static void spoil_config(wmr_tdroc_config_t *c, int j) {
    switch (j) {
CONFIG_CASES
    }
}

/* A state stepped over the first steps of the recording (not timed). */
static void warm(int k) {
    int i; real tau[2];
    fresh(k);
    for (i = 0; i < 12 && i < NSTEPS; ++i) {
        const real *in = IN[i];
        (void)VARIANTS[k].step(&states[k], config_of(&VARIANTS[k]), in, in + NQ, in + 2 * NQ,
                               in + 3 * NQ, in + 4 * NQ, tau);
    }
}

/* Statuses of every bad-input case for variant k, into out; returns how many. */
static int bad_cases(int k, int *out) {
    const variant *v = &VARIANTS[k];
    const real vals[3] = {(real)NAN, (real)INFINITY, (real)2e6};
    real in[5 * NQ], tau[2];
    int n = 0, j, i, p;
    if (!v->frozen) {
        for (j = 0; j < NCFG; ++j) {
            wmr_tdroc_config_t c = cfg;
            any_state s;
            spoil_config(&c, j);
            out[n++] = v->init(&s, &c);
            warm(k);
            memcpy(in, IN[12 % NSTEPS], sizeof in);
            out[n++] = v->step(&states[k], &c, in, in + NQ, in + 2 * NQ, in + 3 * NQ, in + 4 * NQ,
                               tau);
        }
    } else {  /* the compiled-in configuration only: the same values elsewhere are refused */
        wmr_tdroc_config_t c = *config_of(v);
        any_state s;
        out[n++] = v->init(&s, &c);
        warm(k);
        memcpy(in, IN[12 % NSTEPS], sizeof in);
        out[n++] = v->step(&states[k], &c, in, in + NQ, in + 2 * NQ, in + 3 * NQ, in + 4 * NQ,
                               tau);
    }
    for (i = 0; i < 5 * NQ; ++i) {
        for (j = 0; j < 3; ++j) {
            warm(k);
            memcpy(in, IN[12 % NSTEPS], sizeof in);
            in[i] = (i % 2 ? -1 : 1) * vals[j];
            out[n++] = v->step(&states[k], config_of(v), in, in + NQ, in + 2 * NQ, in + 3 * NQ,
                               in + 4 * NQ, tau);
        }
    }
    warm(k);
    memcpy(in, IN[12 % NSTEPS], sizeof in);
    for (p = 0; p < 8; ++p) {
        const real *ptr[5] = {in, in + NQ, in + 2 * NQ, in + 3 * NQ, in + 4 * NQ};
        void *st = p == 0 ? 0 : (void *)&states[k];
        const wmr_tdroc_config_t *c = p == 1 ? 0 : config_of(v);
        if (p >= 2 && p < 7) ptr[p - 2] = 0;
        out[n++] = v->step(st, c, ptr[0], ptr[1], ptr[2], ptr[3], ptr[4], p == 7 ? 0 : tau);
    }
    {
        any_state s;
        memset(&s, 0, sizeof s);
        out[n++] = v->step(&s, config_of(v), in, in + NQ, in + 2 * NQ, in + 3 * NQ, in + 4 * NQ,
                           tau);
    }
    return n;
}

int main(int argc, char **argv) {
    long calls = argc > 1 ? atol(argv[1]) : 1000000;
    int repeats = argc > 2 ? atoi(argv[2]) : 5;
    long passes = calls / NSTEPS > 0 ? calls / NSTEPS : 1;
    static int st[NV][NSTEPS], bad[NV][1024];
    static real tq[NV][2 * NSTEPS];
    static double ns[NV][64];
    double scale = 0.0, worst = 0.0, sink = 0.0;
    int k, i, rep, nbad = 0, spoiled;
    long p;
    CONFIG
    /* The bad-input cases against ours (the first run-time and the first frozen variant). */
    for (k = 0; k < NV; ++k) {
        const int ref = VARIANTS[k].frozen ? FIRST_FROZEN : 0;
        const int n = bad_cases(k, bad[k]);
        if (k == ref) { nbad += n; continue; }
        for (i = 0; i < n; ++i) {
            if (bad[k][i] != bad[ref][i]) {
                printf("{\"error\": \"%s: bad-input case %d returns %d, ours %d\"}\n",
                       VARIANTS[k].name, i, bad[k][i], bad[ref][i]);
                return 3;
            }
        }
    }
    /* The recording, and the recording with a bad input every seventh step. */
    for (spoiled = 0; spoiled < 2; ++spoiled) {
        for (k = 0; k < NV; ++k) { fresh(k); pass(k, st[k], tq[k], spoiled); }
        for (k = 1; k < NV; ++k) {
            for (i = 0; i < NSTEPS; ++i) {
                if (st[0][i] != st[k][i]) {
                    printf("{\"error\": \"%s: status %d at step %d, ours %d%s\"}\n",
                           VARIANTS[k].name, st[k][i], i, st[0][i],
                           spoiled ? " (bad input every 7th step)" : "");
                    return 3;
                }
            }
            for (i = 0; i < 2 * NSTEPS; ++i) {
                const double d = fabs((double)tq[k][i] - (double)tq[0][i]);
                if (fabs((double)tq[0][i]) > scale) scale = fabs((double)tq[0][i]);
                if (!(d <= worst)) worst = d;
            }
        }
    }
    printf("{\"check\": {\"steps\": %d, \"bad_input_cases\": %d, \"max_abs_tau_diff\": %.6e, "
           "\"tau_scale\": %.6e}}\n", NSTEPS, nbad, worst, scale);
    if (!(worst <= TOL * (scale > 1.0 ? scale : 1.0))) return 3;
    if (repeats > 64) repeats = 64;
    for (rep = 0; rep < repeats; ++rep) {
        int j;
        for (j = 0; j < NV; ++j) {
            double t = 0.0;
            k = (j + rep) % NV;
            for (p = 0; p < passes; ++p) {
                double t0;
                fresh(k);
                t0 = now_ns();
                sink += pass(k, 0, 0, 0);
                t += now_ns() - t0;
            }
            ns[k][rep] = t / (double)(passes * NSTEPS);
        }
    }
    for (k = 0; k < NV; ++k) {
        printf("{\"function\": \"tdroc_step\", \"variant\": \"%s\", \"ns\": [",
               VARIANTS[k].name);
        for (rep = 0; rep < repeats; ++rep) printf("%s%.4f", rep ? ", " : "", ns[k][rep]);
        printf("], \"checksum\": %.15e}\n", sink);
    }
    return 0;
}
"""


@dataclass(frozen=True)
class StepRobot:
    """A robot the step benchmark times: its generated code, its hand-written step (a
    source in ``csrc`` with a header of the same stem, defining ``hand_tdroc_state_t``
    and ``hand_``/``handfz_tdroc_init``/``_step``), the formulations it has, and the
    configuration cases (C statements on ``c``, a copy of the recorded configuration),
    each a field made invalid or a valid change."""

    label: str  # prefixed to its cases' names ("" for Drishti)
    code: str  # ``load_robot_code``'s name ("" for Drishti)
    hand: str
    fast: str  # the improved competitor (``handfast_``/``handfastfz_``; issue 52)
    formulations: tuple[str, ...]
    config_cases: tuple[str, ...]

    def case(self, formulation: str, precision: str) -> str:
        return f"{self.label}{formulation}/{precision}"


# Invalid values of the fields every TDROC configuration has, then the robot's own.
_COMMON_CONFIG_CASES = (
    "c->formulation = 7;", "c->h = 0;", "c->h = (real)NAN;", "c->k1[2] = -1;",
    "c->k2[0] = 0;", "c->q_pos = (real)INFINITY;", "c->q_vel = (real)1e7;",
    "c->tau_max = 0;", "c->eps = 0;", "c->eps = (real)1e-30;", "c->accel_estimator = 9;",
    "c->rate_window = 2 * c->h;", "c->hold_gain = 2;", "c->held_gain = -1;", "c->n = 1;",
    "c->n = WMR_MAX_WINDOW + 1;", "c->a = 0;", "c->a = (real)1.5;",
)
# Valid changes: two sign flips, a gain, the gain mode.
_CHANGES = ("c->k1[0] = -4; c->k2[0] = -4;", "c->tau_max = -c->tau_max; c->eps = -c->eps;",
            "c->k1[0] *= (real)1.01;", "c->hold_gain = 1 - c->hold_gain;")
STEP_ROBOTS = (
    StepRobot("", "", "hand_tdroc.c", "hand_tdroc_fast.c", FORMULATIONS, (
        *_COMMON_CONFIG_CASES, "c->nominal.m = (real)NAN;", "c->nominal.r = 0;",
        "c->nominal.b = (real)1e-9;",
        "c->nominal.K = 100;",  # m I - K^2 < 0
        "c->nominal.Iw = 0;", *_CHANGES,
        "c->nominal.d = -c->nominal.d;")),  # valid, but changed
    StepRobot("trailer ", "trailer", "hand_trailer_tdroc.c", "hand_trailer_tdroc_fast.c",
              ("minimal",), (
        *_COMMON_CONFIG_CASES, "c->nominal.J_x_tractor = (real)NAN;",
        "c->nominal.radius_right = 0;", "c->nominal.radius_left = (real)1e-9;",
        "c->nominal.K_theta_cart_x_tractor = 1000;",  # beyond its bound / M-hat indefinite
        "c->nominal.J_theta_right = 0;", *_CHANGES,
        # valid, but changed: 0 becomes -0 (another bit pattern)
        "c->nominal.K_theta_cart_x_tractor_2 = -c->nominal.K_theta_cart_x_tractor_2;")),
)


def _config_lines(config: dict[str, Any], fields: list[str]) -> str:
    lines = [f"cfg.nominal.{p} = {v!r};" for p, v in zip(fields, config["params"], strict=True)]
    for name, value in config.items():
        if name == "params":
            continue
        if isinstance(value, list):
            lines += [f"cfg.{name}[{i}] = {x!r};" for i, x in enumerate(value)]
        else:
            lines.append(f"cfg.{name} = {value!r};")
    return "\n    ".join(lines)


def frozen_header(workdir: Path, config: dict[str, Any], float32: bool = False,
                  robot: str = "") -> Path:
    """``wmr freeze`` of the recorded configuration of ``robot``'s TDROC into ``workdir``."""
    from runtime.bindings.generated import load_robot_code
    from runtime.freeze.header import freeze
    from runtime.sim.plant import library_for
    from runtime.tooling.firmware.emulated_run import tdroc_config

    code = load_robot_code(robot)
    lib = library_for(code, float32)
    frozen = freeze(lib, code, "tdroc", tdroc_config(lib.ffi, config, code.prefix))
    path = workdir / frozen.filename
    path.write_text(frozen.text)
    return path


def _variants(float32: bool, pre: str) -> list[tuple[str, str, str, int]]:
    """(name, init symbol, step symbol, frozen: 0 run-time, 1 ours, 2 hand, 3 the improved
    hand) in check order: ours first (the reference of the run-time variants), then the
    first frozen one."""
    rows = [("ours", pre, 0), ("hand", "hand", 0), ("ours_frozen", f"fz_{pre}", 1),
            ("hand_frozen", "handfz", 2)]
    rows.append(("ours_libm", f"lm_{pre}", 0))
    rows += [("hand_fast", "handfast", 0), ("hand_fast_frozen", "handfastfz", 3)]
    return [(name, f"{p}_tdroc_init", f"{p}_tdroc_step", frozen) for name, p, frozen in rows]


def build_step_bench(workdir: Path, config: dict[str, Any], inputs: list[list[list[float]]],
                     float32: bool = False, robot: StepRobot = STEP_ROBOTS[0]) -> Path:
    """Compile ``robot``'s generated controller C (ours; with the configuration frozen,
    renamed ``fz_<prefix>_*``; with ``-D<PREFIX>_LIBM_TRIG``, renamed ``lm_<prefix>_*``),
    its hand-written step (run-time and ``-DHAND_FROZEN``) and the harness with the
    recorded inputs into one executable of that precision; returns its path."""
    from runtime.bindings.generated import load_robot_code
    from runtime.sim.plant import library_for

    code = load_robot_code(robot.code)
    pre, c_dir = code.prefix, code.c_dir
    real = "float" if float32 else "double"
    prec = (f"-D{pre.upper()}_FLOAT32",) if float32 else ()
    variants = _variants(float32, pre)
    rows = ",\n".join("{" + ", ".join(repr(x) for v in step for x in v) + "}" for step in inputs)
    protos = []
    for _, init, step, _ in variants:
        if init.startswith(("fz_", "lm_")):
            protos.append(f"wmr_status_t {init}(wmr_tdroc_state_t *, const wmr_tdroc_config_t *);")
            protos.append(
                f"wmr_status_t {step}(wmr_tdroc_state_t *, const wmr_tdroc_config_t *, "
                "const real *, const real *, const real *, const real *, const real *, real *);")
    protos.append(f"extern const wmr_tdroc_config_t fz_{pre}_tdroc_frozen_config;")
    protos.append("wmr_status_t handfz_tdroc_init(hand_tdroc_state_t *, "
                  "const wmr_tdroc_config_t *);")
    protos.append("wmr_status_t handfz_tdroc_step(hand_tdroc_state_t *, "
                  "const wmr_tdroc_config_t *, const real *, const real *, const real *, "
                  "const real *, const real *, real *);")
    protos.append("extern const wmr_tdroc_config_t handfz_frozen_config;")
    for p in ("handfast", "handfastfz"):
        protos.append(f"wmr_status_t {p}_tdroc_init(hand_tdroc_state_t *, "
                      "const wmr_tdroc_config_t *);")
        protos.append(f"wmr_status_t {p}_tdroc_step(hand_tdroc_state_t *, "
                      "const wmr_tdroc_config_t *, const real *, const real *, const real *, "
                      "const real *, const real *, real *);")
    protos.append("extern const wmr_tdroc_config_t handfastfz_frozen_config;")
    table = ",\n    ".join(f'{{"{n}", (init_fn){i}, (step_fn){s}, {f}}}'
                           for n, i, s, f in variants)
    protos.append(f"#define NV {len(variants)}")
    protos.append(f"#define NSTEPS {len(inputs)}")
    protos.append(f"#define TOL {TORQUE_TOLERANCE['float32' if float32 else 'double']!r}")
    protos.append(f"#define FIRST_FROZEN {next(k for k, v in enumerate(variants) if v[3])}")
    protos.append(f"static const {real} IN[NSTEPS][5 * NQ] = {{\n{rows}\n}};")
    protos.append("struct variant_s;")
    cases = "\n".join(f"    case {j}: {s} break;" for j, s in enumerate(robot.config_cases))
    fields = [name for name, _ in library_for(code, float32).ffi.typeof(
        f"{pre}_params_t").fields]
    body = (HARNESS.replace("PROTOTYPES", "\n".join(protos))
            .replace("CONFIG_CASES", cases)
            .replace("CONFIG_CASE_COUNT", str(len(robot.config_cases)))
            .replace("CONFIG", _config_lines(config, fields))
            .replace("HAND_HEADER", Path(robot.hand).with_suffix(".h").name))
    body = body.replace("static wmr_tdroc_config_t cfg;",
                        "static wmr_tdroc_config_t cfg;\nstatic const variant VARIANTS[NV] = {\n"
                        f"    {table}\n}};")
    body = f"#define NQ {code.nq}\n" + body.replace("wmr_", f"{pre}_").replace(
        "WMR_", f"{pre.upper()}_")
    src = workdir / "step_main.c"
    src.write_text(body)
    sources = [p for p in sorted(c_dir.glob(f"{pre}_*.c")) if p.name != f"{pre}_plant.c"]
    objs: list[str] = []
    for s in sources:  # ours
        obj = workdir / f"d_{s.stem}.o"
        subprocess.run(["gcc", *CFLAGS, *prec, "-c", f"-I{c_dir}", str(s), "-o", str(obj)],
                       check=True)
        objs.append(str(obj))
    objs += renamed_objects(workdir, sources, (*prec, f"-D{pre.upper()}_LIBM_TRIG"), "lm_",
                            include=c_dir, symbols=f"{pre}_")
    frozen_header(workdir, config, float32, robot.code)
    objs += renamed_objects(workdir, sources, (*prec, frozen_define("tdroc", pre),
                                               f"-I{workdir}"), "fz_", include=c_dir,
                            symbols=f"{pre}_")
    for tag, src_name, defines in (
            ("hand", robot.hand, ()), ("handfz", robot.hand, ("-DHAND_FROZEN",)),
            ("handfast", robot.fast, ("-DHAND_FAST",)),
            ("handfastfz", robot.fast, ("-DHAND_FAST", "-DHAND_FROZEN"))):
        obj = workdir / f"{tag}.o"
        subprocess.run(["gcc", *CFLAGS, *prec, *defines, "-c", f"-I{c_dir}",
                        f"-I{workdir}", f"-I{BENCH_CSRC}", str(BENCH_CSRC / src_name),
                        "-o", str(obj)], check=True)
        objs.append(str(obj))
    exe = workdir / "step_bench"
    subprocess.run(["gcc", *CFLAGS, *prec, f"-I{c_dir}", f"-I{BENCH_CSRC}", str(src),
                    *objs, "-lm", "-o", str(exe)], check=True)
    return exe


def step_cases(robots: tuple[StepRobot, ...] = STEP_ROBOTS
               ) -> list[tuple[StepRobot, str, str]]:
    """(robot, formulation, precision) of every case the benchmark times."""
    return [(r, f, p) for r in robots for f in r.formulations for p in PRECISIONS]


def run_steps(calls: int, repeats: int, runs: int = 1,
              cases: list[tuple[StepRobot, str, str]] | None = None) -> dict[str, Any]:
    """For each (robot, formulation, precision): record the closed loop, check the
    variants agree, time them interleaved, ``runs`` times (separate processes).

    Returns {"checks": {case: {...}}, "rows": [{"function", "variant", "case", "ns":
    [...], "run_medians": [...]}, ...]} (a case is "formulation/precision", the trailer's
    prefixed "trailer "). ``ns`` is the median run's: the process whose ratio of medians,
    ours to the hand-written step, is the median of the runs' (the lower middle for an
    even count). On this VM a process can run disturbed throughout (every variant about
    1.5x slower, or one variant alone, as its memory happens to be placed), so pooling the
    runs mixes machines; the median run is robust to one such process either way, and
    chosen by the ratio, not by either side's time. ``run_medians`` is every run's median
    per variant, in order.
    Raises RuntimeError when statuses or torques differ (nothing is timed then).
    """
    from runtime.tooling.firmware.emulated_run import record_closed_loop

    checks: dict[str, Any] = {}
    rows: list[dict[str, Any]] = []
    for robot, formulation, precision in cases or step_cases():
        float32 = precision == "float32"
        case = robot.case(formulation, precision)
        rec = record_closed_loop("tdroc", formulation, eps=0.5, float32=float32,
                                 robot=robot.code)
        per_run: list[dict[str, list[float]]] = []
        with tempfile.TemporaryDirectory() as tmp:
            exe = build_step_bench(Path(tmp), rec.config, rec.inputs, float32, robot)
            for _ in range(runs):
                proc = subprocess.run([str(exe), str(calls), str(repeats)], capture_output=True,
                                      text=True, check=False)
                lines = [json.loads(x) for x in proc.stdout.splitlines() if x.startswith("{")]
                if proc.returncode != 0:
                    raise RuntimeError(f"step benchmark ({case}) refused to time: "
                                       f"{lines or proc.stderr}")
                checks[case] = next(x["check"] for x in lines if "check" in x)
                per_run.append({x["variant"]: x["ns"] for x in lines if "function" in x})
        by_ratio = sorted(per_run,
                          key=lambda r: statistics.median(r["ours"]) / statistics.median(r["hand"]))
        median_run = by_ratio[(len(by_ratio) - 1) // 2]
        rows += [{"function": "tdroc_step", "variant": v, "case": case, "ns": ns,
                  "run_medians": [statistics.median(r[v]) for r in per_run]}
                 for v, ns in median_run.items()]
    return {"checks": checks, "rows": rows}


def summarise_steps(result: dict[str, Any]) -> dict[tuple[str, str], dict[str, float]]:
    """(case "formulation/precision", variant) -> median, min, max ns per step; and
    (case, "ratio:num/den") -> median, min, max of the per-repetition ratios."""
    out: dict[tuple[str, str], dict[str, float]] = {}
    by_case: dict[str, dict[str, list[float]]] = {}
    for r in result["rows"]:
        case = r["case"]
        out[(case, r["variant"])] = spread(r["ns"])
        by_case.setdefault(case, {})[r["variant"]] = r["ns"]
    for case, ns in by_case.items():
        for num, den in RATIOS:
            if num in ns and den in ns:
                out[(case, f"ratio:{num}/{den}")] = spread(
                    [a / b for a, b in zip(ns[num], ns[den], strict=True)])
    return out
