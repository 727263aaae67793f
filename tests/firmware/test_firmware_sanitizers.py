"""The generated C under AddressSanitizer and UndefinedBehaviorSanitizer.

``runtime/tooling/witness/csrc/fuzz_driver.c`` (a seeded xorshift inside C) runs every
controller in both formulations for ``STEPS`` randomised steps (random valid
configurations, re-initialised every 20..400 steps, and now and then invalid
configurations, NaN/Inf/huge/subnormal inputs, NULL arguments, a wrong magic, a corrupted
state with its magic intact: flipped bits, TDROC's ring head or count set to any int) and
``FD_CALLS`` calls to each of ``wmr_forward_dynamics`` and ``wmr_minimal_forward_dynamics``
with random, sometimes extreme, parameters and arguments. The driver checks that every
successful call's outputs (tau within ±tau_max, every real in the state, every
acceleration) are finite and that a failed call leaves the state/outputs untouched with the
right code; it exits 1 on any violation. Built with ``-fsanitize=address,undefined
-fno-sanitize-recover=all``, any sanitizer finding aborts the run. Double and float32
builds, compiled in parallel (about 10 s on two cores).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from runtime.bindings.cbuild import GENERATED_C

CSRC = Path(__file__).resolve().parents[2] / "runtime" / "tooling" / "witness" / "csrc"
DRIVER = CSRC / "fuzz_driver.c"
SANITIZE = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all")
CFLAGS = ("-std=c99", "-O1", "-g", "-fno-omit-frame-pointer", "-Wall", "-Wextra", "-Werror")
STEPS = 100_000  # per controller and formulation
FD_CALLS = 100_000  # per forward-dynamics function
SEED = 20240611
CONTROLLERS = ("tdc", "tdroc", "roc", "asmc")
ENV = {
    **os.environ,
    # No leak check: the generated code has no heap, and LeakSanitizer fails under ptrace.
    "ASAN_OPTIONS": "abort_on_error=0:halt_on_error=1:detect_leaks=0:exitcode=86",
    "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1",
}
SANITIZER_REPORT = re.compile(r"runtime error|AddressSanitizer|LeakSanitizer|UndefinedBehavior")


def _compile(out: Path, sources: list[Path], float32: bool) -> subprocess.Popen[str]:
    cmd = [
        "gcc",
        *CFLAGS,
        *SANITIZE,
        *(["-DWMR_FLOAT32"] if float32 else []),
        f"-I{GENERATED_C}",
        *map(str, sources),
        "-lm",
        "-o",
        str(out),
    ]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _sanitizers_work(tmp: Path) -> str | None:
    """None if gcc links ASan/UBSan here, else the reason."""
    if shutil.which("gcc") is None:
        return "gcc not found"
    src = tmp / "probe.c"
    src.write_text("int main(void) { return 0; }\n")
    proc = _compile(tmp / "probe", [src], False)
    _, err = proc.communicate()
    return None if proc.returncode == 0 else f"gcc cannot build with sanitizers: {err[-300:]}"


@pytest.fixture(scope="module")
def binaries(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("sanitize")
    reason = _sanitizers_work(tmp)
    if reason:
        pytest.skip(reason)
    sources = [*sorted(GENERATED_C.glob("wmr_*.c")), DRIVER]
    procs = {p: _compile(tmp / f"fuzz_{p}", sources, p == "float32") for p in ("double", "float32")}
    for precision, proc in procs.items():
        out, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, f"{precision} build failed:\n{out}{err}"
    return {p: tmp / f"fuzz_{p}" for p in procs}


def test_sanitizers_catch_a_planted_bug(tmp_path: Path) -> None:
    """The sanitizer build really reports: a one-past-the-end read aborts the program."""
    reason = _sanitizers_work(tmp_path)
    if reason:
        pytest.skip(reason)
    src = tmp_path / "bug.c"
    src.write_text(
        "#include <stdlib.h>\n"
        "int main(int argc, char **argv) { (void)argv; double *x = malloc(5 * sizeof *x);\n"
        "  for (int i = 0; i < 5; ++i) x[i] = i;\n"
        "  double s = x[argc + 4]; free(x); return s > 100.0; }\n"
    )
    proc = _compile(tmp_path / "bug", [src], False)
    proc.communicate()
    assert proc.returncode == 0
    run = subprocess.run([str(tmp_path / "bug")], capture_output=True, text=True, env=ENV)
    assert run.returncode != 0
    assert SANITIZER_REPORT.search(run.stderr), run.stderr


def _parse(stdout: str) -> dict[tuple[str, str], dict[str, int]]:
    out = {}
    for line in stdout.splitlines():
        if line.startswith("RESULT "):
            _, name, form, *fields = line.split()
            out[(name, form)] = {k: int(v) for k, v in (f.split("=") for f in fields)}
    return out


@pytest.fixture(scope="module")
def runs(binaries: dict[str, Path]) -> dict[str, subprocess.CompletedProcess[str]]:
    procs = {
        p: subprocess.Popen(
            [str(exe), str(SEED), str(STEPS), str(FD_CALLS)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=ENV,
        )
        for p, exe in binaries.items()
    }
    results = {}
    for p, proc in procs.items():
        out, err = proc.communicate(timeout=600)
        results[p] = subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
    return results


@pytest.mark.parametrize("precision", ["double", "float32"])
def test_fuzz_driver_under_sanitizers(
    runs: dict[str, subprocess.CompletedProcess[str]], precision: str
) -> None:
    run = runs[precision]
    assert not SANITIZER_REPORT.search(run.stderr), run.stderr[-4000:]
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "VIOLATIONS 0" in run.stdout
    stats = _parse(run.stdout)
    for name in CONTROLLERS:
        for form in ("paper", "minimal"):
            s = stats[(name, form)]
            assert s["steps"] >= 100_000, (name, form, s)
            assert s["ok"] + s["errors"] == s["steps"]
            # The mix really happened: successes, saturation, every kind of bad call.
            assert s["ok"] > 0.8 * s["steps"] and s["saturated"] > 0
            for kind in ("bad_config", "bad_input", "wild_input", "null_calls", "magic_calls",
                         "corrupt_calls"):
                assert s[kind] > 100, (name, form, kind, s)
            if name == "tdroc":  # its ring's head or count out of range, refused
                assert s["corrupt_refused"] > 100, (name, form, s)
            assert s["bad_inits"] > 0 and s["reinits"] > 100 and s["stretched"] > 0
    for fn in ("forward_dynamics", "minimal_forward_dynamics"):
        s = stats[(fn, "model")]
        assert s["calls"] >= 100_000
        assert s["ok"] > 0.3 * s["calls"] and s["errors"] > 0.05 * s["calls"]
