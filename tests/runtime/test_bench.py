"""The benchmark harness (issue 6) measures the same functions in every variant.

Timing is not tested (that is `make bench`); what is tested is that the harness builds and
that every variant computes the same thing on the same inputs, so the comparison is fair:
the checksums (sum of outputs over 2000 varied calls) of our double C (also through the
prepare-parameters API), CasADi's C, plain SymPy C and the hand-written C agree to 1e-9
relative, our float32 build to 1e-4.
"""

from __future__ import annotations

import math
import shutil
import statistics
from collections import defaultdict
from pathlib import Path

import pytest

from runtime.tooling.bench.c_bench import run_c, uses_trig
from runtime.tooling.bench.c_variants import MODEL_FUNCTIONS, STEP_KERNELS, specs_by_name
from runtime.tooling.bench.op_counts import casadi_op_count
from runtime.tooling.bench.step_bench import run_steps


@pytest.fixture(scope="module")
def checksums() -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = defaultdict(dict)
    for row in run_c(2000, 1):
        out[row["function"]][row["variant"]] = row["checksum"]
    return out


def test_every_function_has_every_variant(checksums: dict[str, dict[str, float]]) -> None:
    specs = specs_by_name()
    for name in MODEL_FUNCTIONS:  # all of them evaluate sin and cos of the heading
        expected = {"ours", "ours_float32", "casadi", "sympy", "hand", "ours_libm"}
        if name == "forward_dynamics":  # the one with validation and a prepare API
            expected |= {"ours_unchecked", "hand_checked", "hand_checked_float32",
                         "ours_prepared"}
        assert set(checksums[name]) == expected
    for kernels in STEP_KERNELS.values():
        for k in kernels:
            libm = {"ours_libm"} if uses_trig(specs[k]) else set()
            assert set(checksums[k]) == {"ours", "ours_float32", "casadi", "sympy"} | libm
    assert uses_trig(specs["paper_tde"]) and not uses_trig(specs["paper_tde_trig"])


def test_variants_agree(checksums: dict[str, dict[str, float]]) -> None:
    for name, by_variant in checksums.items():
        ref = by_variant["ours"]
        scale = max(abs(ref), 1.0)
        for variant, value in by_variant.items():
            tol = 1e-4 if variant.endswith("float32") else 1e-9
            assert abs(value - ref) <= tol * scale, (name, variant, value, ref)


def test_full_step_benchmark_checks_before_timing() -> None:
    """The complete ``wmr_tdroc_step`` and the hand-written step, each also with the
    configuration compiled in (and ours with libm's sin/cos), in both
    formulations and precisions: the bad-input statuses are equal, on the recorded closed
    loop every status is equal and the torques agree (else nothing is timed), and all are
    timed; the ratios are per repetition."""
    from runtime.tooling.bench.step_bench import STEP_ROBOTS, step_cases, summarise_steps

    result = run_steps(601, 2, cases=step_cases(STEP_ROBOTS[:1]))
    assert set(result["checks"]) == {f"{f}/{p}" for f in ("paper", "minimal")
                                     for p in ("double", "float32")}
    for case, check in result["checks"].items():
        assert check["steps"] > 100 and check["tau_scale"] > 0.1
        assert check["bad_input_cases"] > 100
        tol = 1e-4 if case.endswith("float32") else 1e-9
        assert check["max_abs_tau_diff"] <= tol * check["tau_scale"], case
    for r in result["rows"]:
        assert len(r["ns"]) == 2 and min(r["ns"]) > 0.0
    variants = {(r["case"], r["variant"]) for r in result["rows"]}
    assert ("paper/double", "ours_libm") in variants
    assert ("minimal/float32", "ours_libm") in variants
    assert ("minimal/float32", "hand_frozen") in variants
    # the improved competitor (issue 52), run-time and frozen, checked like the old one
    for case in result["checks"]:
        assert (case, "hand_fast") in variants and (case, "hand_fast_frozen") in variants
    st = summarise_steps(result)
    assert st[("paper/double", "ratio:ours/hand")]["median"] > 0.0
    assert st[("minimal/float32", "ratio:ours_frozen/hand_fast_frozen")]["median"] > 0.0


def test_trailer_step_benchmark_checks_before_timing() -> None:
    """The trailer's ``trailer_tdroc_step`` (minimal formulation, M-hat depending on the
    hitch angle) against its hand-written step (``csrc/hand_trailer_tdroc.c``), both
    precisions, run-time and frozen: the same statuses on every bad-input case and over
    the recorded closed loop (with and without a bad input every seventh step), the
    torques within the tolerance, then timed."""
    from runtime.tooling.bench.step_bench import STEP_ROBOTS, step_cases, summarise_steps

    trailer = [r for r in STEP_ROBOTS if r.code == "trailer"]
    result = run_steps(601, 2, runs=2, cases=step_cases(tuple(trailer)))
    assert set(result["checks"]) == {"trailer minimal/double", "trailer minimal/float32"}
    # two processes: each variant's times are the median run's (the lower of the two
    # ratios ours / hand), and every process's median is kept
    for case in result["checks"]:
        rows = {r["variant"]: r for r in result["rows"] if r["case"] == case}
        ratios = [a / b for a, b in zip(rows["ours"]["run_medians"], rows["hand"]["run_medians"],
                                        strict=True)]
        chosen = ratios.index(min(ratios))
        for r in rows.values():
            assert len(r["run_medians"]) == 2
            assert statistics.median(r["ns"]) == r["run_medians"][chosen]
    for case, check in result["checks"].items():
        assert check["steps"] > 100 and check["tau_scale"] > 0.1
        # ours run-time: 28 configuration cases (at _init and at a step), 40 inputs x 3
        # values, 8 NULL pointers, a state never initialised; ours frozen: its one
        # configuration (twice), the inputs, the pointers, the state
        assert check["bad_input_cases"] == (2 * 28 + 40 * 3 + 9) + (2 + 40 * 3 + 9)
        tol = 1e-4 if case.endswith("float32") else 1e-9
        assert check["max_abs_tau_diff"] <= tol * check["tau_scale"], case
    st = summarise_steps(result)
    for v in ("ours", "hand", "ours_frozen", "hand_frozen", "hand_fast", "hand_fast_frozen"):
        assert st[("trailer minimal/float32", v)]["median"] > 0.0
    for p in ("double", "float32"):
        assert st[(f"trailer minimal/{p}", "ratio:ours_libm/hand")]["median"] > 0.0


def test_step_benchmark_refuses_a_competitor_with_another_status(tmp_path: Path) -> None:
    """A hand-written step that returns another status on one bad-input case is caught
    before any timing: the comparison cannot be flattered by a step that skips a check."""
    import shutil
    import subprocess

    from runtime.tooling.bench import step_bench
    from runtime.tooling.firmware.emulated_run import record_closed_loop

    csrc = tmp_path / "csrc"
    shutil.copytree(step_bench.BENCH_CSRC, csrc)
    src = csrc / "hand_tdroc.c"
    text = src.read_text()
    check = "    if (c->n < 2 || c->n > WMR_MAX_WINDOW) {"
    assert check in text
    src.write_text(text.replace(check, "    if (c->n < 1 || c->n > WMR_MAX_WINDOW) {"))
    rec = record_closed_loop("tdroc", "paper", eps=0.5, float32=False)
    original = step_bench.BENCH_CSRC
    step_bench.BENCH_CSRC = csrc
    try:
        exe = step_bench.build_step_bench(tmp_path, rec.config, rec.inputs[:60])
    finally:
        step_bench.BENCH_CSRC = original
    proc = subprocess.run([str(exe), "600", "1"], capture_output=True, text=True, check=False)
    assert proc.returncode == 3
    assert "bad-input case" in proc.stdout and '"ns"' not in proc.stdout


def test_step_benchmark_refuses_a_competitor_with_other_torques(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A hand-written step whose torque is off by one part in a million (every status
    right) is refused by the harness before any timing, and ``run_steps`` raises: the
    benchmark never times a competitor that computes something else."""
    from runtime.tooling.bench import step_bench

    csrc = tmp_path / "csrc"
    shutil.copytree(step_bench.BENCH_CSRC, csrc)
    src = csrc / "hand_tdroc.c"
    text = src.read_text()
    write = "    tau[0] = t0;\n    tau[1] = t1;\n    return st;"
    assert text.count(write) == 1
    src.write_text(text.replace(write, "    tau[0] = t0 * (1.0 + 1e-6);\n"
                                       "    tau[1] = t1;\n    return st;"))
    monkeypatch.setattr(step_bench, "BENCH_CSRC", csrc)
    case = [(step_bench.STEP_ROBOTS[0], "paper", "double")]
    with pytest.raises(RuntimeError, match=r"refused to time: \[\{'check'") as caught:
        step_bench.run_steps(601, 1, cases=case)
    assert "max_abs_tau_diff" in str(caught.value) and "'ns'" not in str(caught.value)


@pytest.mark.parametrize(("robot", "source", "edit", "refusal"), [
    # a torque off by one part in a million (Drishti's paper form: u rows 4, 5)
    (0, "hand_tdroc_fast.c",
     ("    return commit(st, cfg, pushed, head, count, dnew, H1, qdot, sth, cth, gain, sn, "
      "udisc,\n                  u[3], u[4], tau);",
      "    return commit(st, cfg, pushed, head, count, dnew, H1, qdot, sth, cth, gain, sn, "
      "udisc,\n                  u[3] * (1.0 + 1e-6), u[4], tau);"), "max_abs_tau_diff"),
    # a status out of order: the ring's bound checked before the inputs
    (1, "hand_trailer_tdroc_fast.c",
     ("    if (((meas | ref) & TOP_BIT) != 0u) {",
      "    if (((meas | ref) & TOP_BIT) != 0u && state->steps > 100000u) {"),
     "hand_fast: bad-input case"),
])
def test_step_benchmark_refuses_an_improved_competitor_that_diverges(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, robot: int, source: str,
        edit: tuple[str, str], refusal: str) -> None:
    """The improved competitors (issue 52: ``csrc/hand_tdroc_fast.c``,
    ``hand_trailer_tdroc_fast.c``) are checked against the generated step like the old
    ones: one whose torque or whose status on a bad input differs is refused before any
    timing."""
    from runtime.tooling.bench import step_bench

    csrc = tmp_path / "csrc"
    shutil.copytree(step_bench.BENCH_CSRC, csrc)
    src = csrc / source
    text = src.read_text()
    assert text.count(edit[0]) == 1
    src.write_text(text.replace(*edit))
    monkeypatch.setattr(step_bench, "BENCH_CSRC", csrc)
    r = step_bench.STEP_ROBOTS[robot]
    case = [(r, r.formulations[0], "double")]
    with pytest.raises(RuntimeError, match="refused to time") as caught:
        step_bench.run_steps(601, 1, cases=case)
    assert refusal in str(caught.value) and "'ns'" not in str(caught.value)


def test_casadi_op_counts_are_counted() -> None:
    spec = specs_by_name()["forward_dynamics"]
    counts = casadi_op_count(spec)
    assert counts["mul"] > 10 and counts["add"] > 10 and counts["sin/cos"] == 2


def test_make_bench_needs_the_cross_compiler_before_writing(tmp_path: Path) -> None:
    """Without arm-none-eabi-gcc, ``make bench`` stops with a sentence before it rewrites
    BENCHMARKS.md."""
    import shutil
    import subprocess

    root = Path(__file__).resolve().parents[2]
    stamp = root / ".venv" / ".installed"
    if not stamp.is_file() or stamp.stat().st_mtime < (root / "pyproject.toml").stat().st_mtime:
        pytest.skip("the .venv stamp is missing or stale: make would install first")
    for tool in ("make", "sh"):
        found = shutil.which(tool)
        if found is None:
            pytest.skip(f"{tool} not found")
        (tmp_path / tool).symlink_to(found)
    before = (root / "BENCHMARKS.md").read_bytes()
    result = subprocess.run(["make", "-s", "bench"], cwd=root, capture_output=True, text=True,
                            env={"PATH": str(tmp_path)}, check=False)
    assert result.returncode != 0
    assert "arm-none-eabi-gcc not found" in result.stderr
    assert (root / "BENCHMARKS.md").read_bytes() == before


def test_the_readme_ratio_tables_are_those_of_benchmarks_md() -> None:
    """`make bench` writes the ratio tables into BENCHMARKS.md and, between two markers,
    into the README: the README's block must be BENCHMARKS.md's lines, as they are."""
    from runtime.tooling.bench.report import README_BEGIN, README_END

    root = Path(__file__).resolve().parents[2]
    readme = (root / "README.md").read_text()
    start, end = readme.find(README_BEGIN), readme.find(README_END)
    assert 0 <= start < end, "the README lost the markers of make bench's ratio tables"
    block = readme[start + len(README_BEGIN):end].strip("\n")
    assert "| ratio |" in block and "forward dynamics ratio" in block
    assert block in (root / "BENCHMARKS.md").read_text()


def test_sync_readme_replaces_only_the_marked_block(tmp_path: Path) -> None:
    from runtime.tooling.bench.report import README_BEGIN, README_END, sync_readme

    readme = tmp_path / "README.md"
    readme.write_text(f"before\n{README_BEGIN}\nold\n{README_END}\nafter\n")
    assert sync_readme(readme, ["| new |"])
    assert readme.read_text() == f"before\n{README_BEGIN}\n| new |\n{README_END}\nafter\n"
    assert not sync_readme(tmp_path / "missing.md", ["x"])


def test_every_shipped_robot_is_benchmarked_against_casadi_on_the_same_inputs() -> None:
    """The trailer's forward dynamics (both formulations) and its TDROC step's kernels,
    ours in double and float32 against CasADi's C of the same specs in double and float,
    and the forward dynamics against the hand-written C (csrc/hand_trailer.c, derived by
    hand from the robot's kinetic energy: an independent route to the same numbers):
    built into one executable that checks every variant against ours before it times
    (else it refuses, and this raises), the checksums agreeing, the ratios summarised."""
    from runtime.tooling.bench.robot_c_bench import (
        FUNCTIONS,
        HAND_VARIANTS,
        VARIANTS,
        robot_functions,
        run_robot,
        summarise,
    )

    rows = run_robot("trailer", 300, 2)
    names = {s.name for s in robot_functions("trailer").specs}
    # M-hat depends on q: the step's kernels are M-hat's and those reading it
    assert set(FUNCTIONS) <= names and {"minimal_mhat", "minimal_minv_norm_mhat"} <= names
    assert {(r["function"], r["variant"]) for r in rows} == {
        (n, v) for n in names for v in VARIANTS} | {
        (n, v) for n in FUNCTIONS for v in HAND_VARIANTS}
    by = {(r["function"], r["variant"]): r for r in rows}
    for (name, variant), row in by.items():
        ref = by[(name, "ours")]["checksum"]
        tol = 1e-4 if variant.endswith("float32") else 1e-9
        assert abs(row["checksum"] - ref) <= tol * max(abs(ref), 1.0), (name, variant)
        assert len(row["ns"]) == 2 and min(row["ns"]) > 0.0
    s = summarise(rows)
    step = s[("trailer", "tdroc_step_kernels", "ours")]["median"]
    assert step > s[("trailer", "minimal_tdroc_law_mhat", "ours")]["median"]
    assert s[("trailer", "forward_dynamics", "ours_float32/casadi_float32")]["median"] > 0.0
    assert s[("trailer", "minimal_forward_dynamics", "ours_float32/hand_float32")]["median"] > 0


def test_a_parameter_struct_read_in_place_must_have_the_specs_layout(tmp_path: Path) -> None:
    """The harness passes our parameters struct as a pointer into the flat inputs (as the
    competitors read theirs); a struct whose members are in another order than the spec's
    fields, or of another size, does not compile."""
    import subprocess

    import sympy as sp

    from codegen.spec import Argument, Field
    from runtime.tooling.bench.c_variants import params_in_place

    a, b = sp.symbols("a b")
    arg = Argument("p", "params", fields=(Field("a", (a,)), Field("b", (b,))))
    _, checks = params_in_place(arg, "pair_t", "double", 0, "t")
    for struct, compiles in (("double a; double b;", True), ("double b; double a;", False),
                             ("double a; double b; double c;", False)):
        src = tmp_path / "layout.c"
        src.write_text(f"#include <stddef.h>\ntypedef struct {{ {struct} }} pair_t;\n{checks}")
        proc = subprocess.run(["gcc", "-std=c99", "-fsyntax-only", str(src)],
                              capture_output=True, text=True)
        assert (proc.returncode == 0) == compiles, (struct, proc.stderr)


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_hand_written_trailer_forward_dynamics_keeps_our_contract(tmp_path: Path) -> None:
    """The trailer's hand-written competitor (csrc/hand_trailer.c) under our contract: on
    every bad input (each input it reads NaN or infinite, each positive parameter zero or
    negative, a mass matrix made indefinite, torques that overflow) the status of
    trailer_forward_dynamics and trailer_minimal_forward_dynamics, and on good ones and
    on inputs neither reads (NaN there) their results (1e-12): a faster competitor that
    skipped a check would not be comparable."""
    import subprocess

    from runtime.tooling.bench.c_bench import BENCH_CSRC
    from runtime.tooling.bench.robot_c_bench import nominal_values, robot_functions

    rf = robot_functions("trailer")
    specs = {s.name: s for s in rf.specs}
    nominal = nominal_values(rf.model)
    harness = ['#include <math.h>', '#include <stdio.h>', '#include "trailer_model.h"']
    checked = []
    for name in ("forward_dynamics", "minimal_forward_dynamics"):
        spec = specs[name]
        symbols = [str(s) for s in spec.input_symbols()]
        base = [nominal.get(s, 0.3 + 0.1 * k) for k, s in enumerate(symbols)]
        cases = [base]
        for k, s in enumerate(symbols):
            for bad in (math.nan, math.inf, -math.inf):
                cases.append([*base[:k], bad, *base[k + 1:]])
            if s in nominal:
                for bad in (0.0, -nominal[s]):
                    cases.append([*base[:k], bad, *base[k + 1:]])
        k4 = symbols.index("K_theta_tractor_x_tractor_2")
        cases.append([*base[:k4], 1e3, *base[k4 + 1:]])  # M-bar indefinite
        cases.append([*base[:-2], 1e308, -1e308])  # torques whose accelerations overflow
        n_in, n_out = len(symbols), sum(len(a.exprs) for a in spec.outputs)
        rows = ", ".join("{" + ", ".join(repr(x).replace("nan", "NAN").replace("inf", "INFINITY")
                                         for x in c) + "}" for c in cases)
        offs = [0]
        for a in spec.inputs:
            offs.append(offs[-1] + len(a.all_symbols()))
        args = ["(const trailer_params_t *)in"] + [f"in + {o}" for o in offs[1:-1]]
        harness += [
            f"int hand_trailer_{name}(const double *in, double *out);",
            f"static const double cases_{name}[{len(cases)}][{n_in}] = {{{rows}}};",
            f"static void run_{name}(void) {{",
            f"    for (int c = 0; c < {len(cases)}; ++c) {{",
            f"        const double *in = cases_{name}[c];",
            f"        double a[{n_out}], b[{n_out}], worst = 0.0;",
            f"        int sa = trailer_{name}({', '.join(args)}, a);",
            f"        int sb = hand_trailer_{name}(in, b);",
            f"        for (int k = 0; sa == 0 && sb == 0 && k < {n_out}; ++k)",
            "            worst = fmax(worst, fabs(a[k] - b[k]) / fmax(1.0, fabs(a[k])));",
            f'        printf("{name} %d %d %.3e\\n", sa, sb, worst);',
            "    }",
            "}",
        ]
        checked.append(name)
    harness.append("int main(void) { " + " ".join(f"run_{n}();" for n in checked)
                   + " return 0; }")
    src = tmp_path / "contract.c"
    src.write_text("\n".join(harness) + "\n")
    exe = tmp_path / "contract"
    subprocess.run(["gcc", "-std=c99", "-O2", f"-I{rf.c_dir}", str(src),
                    str(rf.c_dir / "trailer_model.c"), str(BENCH_CSRC / "hand_trailer.c"),
                    "-lm", "-o", str(exe)], check=True)
    lines = subprocess.run([str(exe)], capture_output=True, text=True,
                           check=True).stdout.split("\n")
    results = [line.split() for line in lines if line]
    for name, ours, hand, worst in results:
        assert ours == hand, (name, ours, hand)
        assert float(worst) <= 1e-12, (name, worst)
    for name in checked:  # not vacuous: every status of the contract occurs
        assert {r[1] for r in results if r[0] == name} == {"0", "-2", "-3", "-4"}, name
