"""A configuration frozen into the firmware (``wmr freeze``, issue 12): a build with
``-D<PREFIX>_<NAME>_FROZEN`` and the header ``wmr freeze`` wrote must behave exactly as the
run-time build given that configuration (state bytes after _init and after every step,
statuses, torques, error details), take that configuration only, and refuse to compile
against a header made for the other precision or formulation. The command itself: a refused
configuration names its field and writes nothing; ``--check`` tells a stale header.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from codegen.backends.c.files import CODE_ID_UNSET, stamp_code_id
from runtime.bindings import cbuild
from runtime.bindings.config import controller_config
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.commands.freeze import main as freeze_main
from runtime.experiment.settings import Experiment
from runtime.freeze.header import (
    FROZEN_STATE_OMITS,
    FreezeError,
    freeze,
    frozen_macro,
    initializer_lines,
    real_literal,
)

STEPS = 60
STRICT = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wdouble-promotion",
          "-Wfloat-equal", "-Wconversion", "-Werror")


def _frozen_pair(tmp: Path, code: RobotCode, name: str, formulation: str, float32: bool,
                 changes: dict[str, Any] | None = None,
                 ) -> tuple[cbuild.CLibrary, Any, cbuild.CLibrary, Any]:
    """(run-time build, its config, frozen build, its compiled-in config); ``changes`` set
    configuration fields after the experiment's defaults."""
    lib = cbuild.build(float32, c_dir=code.c_dir, prefix=code.prefix)
    config = controller_config(lib, code, name, formulation, code.params, Experiment())
    for key, value in (changes or {}).items():
        setattr(config, key, value)
    frozen = freeze(lib, code, name, config, ["test"])
    header = tmp / frozen.filename
    header.write_text(frozen.text)
    flib = cbuild.build(float32, c_dir=code.c_dir, prefix=code.prefix,
                        flags=(f"-D{frozen_macro(code.prefix, name)}",),
                        extra_headers=(header,))
    fcfg = flib.ffi.addressof(flib.lib, f"{code.prefix}_{name}_frozen_config")
    return lib, config, flib, fcfg


def _inputs(nq: int, steps: int, seed: int) -> list[list[np.ndarray]]:
    """Smooth measured and reference trajectories with a few bad samples (NaN rate, huge
    reference) so that error paths are compared too."""
    rng = np.random.default_rng(seed)
    t = 0.1 * np.arange(steps)[:, None]
    amp, freq = rng.uniform(0.2, 1.0, nq), rng.uniform(0.3, 1.5, nq)
    q_des, qdot_des = amp * np.sin(freq * t), amp * freq * np.cos(freq * t)
    qddot_des = -amp * freq**2 * np.sin(freq * t)
    q = q_des + rng.normal(0.0, 0.05, (steps, nq))
    qdot = qdot_des + rng.normal(0.0, 0.2, (steps, nq))
    out = [[q[k], qdot[k], q_des[k], qdot_des[k], qddot_des[k]] for k in range(steps)]
    out[7][1] = out[7][1].copy()
    out[7][1][0] = np.nan
    out[19][2] = out[19][2] * 1e12
    return out


def _state_fields(lib: cbuild.CLibrary, state: Any) -> list[str]:
    """Every field's exact value (padding bytes differ: _init copies a local) but the run-time
    build's copy of the configuration, which a frozen build's state does not have."""
    return initializer_lines(lib.ffi, state, lib.float32, omit=FROZEN_STATE_OMITS)


def _run(lib: cbuild.CLibrary, pre: str, name: str, cfg: Any, nq: int, nu: int,
         inputs: list[list[np.ndarray]]) -> list[tuple[int, int, int, list[float], list[str]]]:
    """Status, detail, torques and every state field after _init and after each step (a
    _reset two thirds of the way through)."""
    ffi = lib.ffi
    state = ffi.new(f"{pre}_{name}_state_t *")
    assert getattr(lib.lib, f"{pre}_{name}_init")(state, cfg) == 0
    step = getattr(lib.lib, f"{pre}_{name}_step_detail")
    detail = ffi.new(f"{pre}_error_detail_t *")
    tau = ffi.new(f"{pre}_real_t[{nu}]")
    rows = [(0, 0, 0, [0.0] * nu, _state_fields(lib, state))]
    for k, args in enumerate(inputs):
        if k == 2 * len(inputs) // 3:
            assert getattr(lib.lib, f"{pre}_{name}_reset")(state) == 0
        arrays = [ffi.new(f"{pre}_real_t[{nq}]", [float(x) for x in a]) for a in args]
        status = int(step(state, cfg, *arrays, tau, detail))
        rows.append((status, int(detail.field), int(detail.index), list(tau),
                     _state_fields(lib, state)))
    return rows


CENTRAL = {"accel_estimator": 1}  # WMR_ACCEL_CENTRAL


@pytest.mark.parametrize(("name", "formulation", "float32", "changes"), [
    ("tdc", "paper", False, None), ("tdroc", "paper", False, None),
    ("roc", "paper", False, None), ("asmc", "paper", False, None),
    ("tdroc", "minimal", False, None), ("tdroc", "paper", True, None),
    ("tdroc", "minimal", True, None), ("asmc", "minimal", True, None),
    ("tdc", "minimal", True, CENTRAL), ("roc", "minimal", True, None),
    ("asmc", "paper", False, {"gain0": 0.5, "gamma": 7.0}),
    ("tdroc", "paper", True, {"hold_gain": 1, "held_gain": 3.0, **CENTRAL}),
    ("tdroc", "minimal", False, {"accel_estimator": 0, "n": 8, "a": 0.6}),
])
def test_frozen_build_equals_run_time_build(tmp_path: Path, name: str, formulation: str,
                                            float32: bool, changes: dict[str, Any] | None
                                            ) -> None:
    code = load_robot_code("")
    lib, cfg, flib, fcfg = _frozen_pair(tmp_path, code, name, formulation, float32, changes)
    inputs = _inputs(code.nq, STEPS, seed=len(name) + 7 * float32)
    run = _run(lib, code.prefix, name, cfg, code.nq, code.nu, inputs)
    frozen = _run(flib, code.prefix, name, fcfg, code.nq, code.nu, inputs)
    statuses = {row[0] for row in run}
    assert 0 in statuses and any(s < 0 for s in statuses)  # both paths compared
    for k, (a, b) in enumerate(zip(run, frozen, strict=True)):
        assert a == b, f"step {k}: run-time build {a[:4]}, frozen build {b[:4]}"


def test_trailer_frozen_build_equals_run_time_build(tmp_path: Path) -> None:
    """Another robot (prefix trailer_, ‖M̂⁻¹‖ evaluated at q in every step)."""
    code = load_robot_code("trailer")
    lib, cfg, flib, fcfg = _frozen_pair(tmp_path, code, "tdroc", "minimal", False)
    inputs = _inputs(code.nq, 25, seed=3)
    run = _run(lib, code.prefix, "tdroc", cfg, code.nq, code.nu, inputs)
    assert _run(flib, code.prefix, "tdroc", fcfg, code.nq, code.nu, inputs) == run


def test_frozen_build_takes_its_configuration_only(tmp_path: Path) -> None:
    code = load_robot_code("")
    _, _, flib, fcfg = _frozen_pair(tmp_path, code, "tdroc", "paper", False)
    ffi, c = flib.ffi, flib.lib
    status = load_robot_code("").controllers.STATUS
    fields = load_robot_code("").controllers.FIELDS
    copy = ffi.new("wmr_tdroc_config_t *")
    ffi.memmove(copy, fcfg, ffi.sizeof("wmr_tdroc_config_t"))  # same bytes, other object
    state = ffi.new("wmr_tdroc_state_t *")
    ffi.memmove(state, b"\x5a" * ffi.sizeof(state[0]), ffi.sizeof(state[0]))
    before = bytes(ffi.buffer(state))
    assert c.wmr_tdroc_init(state, copy) == status["WMR_ERR_CONFIG_CHANGED"]
    assert c.wmr_tdroc_init(state, ffi.NULL) == status["WMR_ERR_NULL_POINTER"]
    assert bytes(ffi.buffer(state)) == before
    assert c.wmr_tdroc_init(state, fcfg) == status["WMR_OK"]
    after_init = bytes(ffi.buffer(state))
    arrays = [ffi.new("wmr_real_t[5]", [0.1] * 5) for _ in range(5)]
    tau = ffi.new("wmr_real_t[2]", [7.0, 7.0])
    detail = ffi.new("wmr_error_detail_t *")
    assert c.wmr_tdroc_step_detail(state, copy, *arrays, tau, detail) == \
        status["WMR_ERR_CONFIG_CHANGED"]
    assert (detail.field, detail.index) == (fields["CONFIG"], -1)
    assert bytes(ffi.buffer(state)) == after_init and list(tau) == [7.0, 7.0]
    # _check_config still validates any configuration in a frozen build.
    copy.n = 99
    assert c.wmr_tdroc_check_config(copy) == status["WMR_ERR_BAD_WINDOW"]
    assert c.wmr_tdroc_check_config(fcfg) == status["WMR_OK"]


def test_frozen_state_is_what_init_leaves() -> None:
    """The header's state is the bytes _init writes (P, weights, ‖M̂⁻¹‖) without the copy of
    the configuration a run-time state keeps (the frozen build's is a constant)."""
    code = load_robot_code("")
    lib = cbuild.build(False)
    cfg = controller_config(lib, code, "tdroc", "paper", code.params, Experiment())
    text = freeze(lib, code, "tdroc", cfg).text
    state = lib.ffi.new("wmr_tdroc_state_t *")
    assert lib.lib.wmr_tdroc_init(state, cfg) == 0
    assert f".minv_norm = {real_literal(state.minv_norm, False)}" in text
    assert ".config = " not in text and ".config = {" in "\n".join(
        initializer_lines(lib.ffi, state, False))
    assert ".p12 = {" + ", ".join(real_literal(x, False) for x in state.p12) + "}" in text


def test_refused_configuration_names_its_field() -> None:
    code = load_robot_code("")
    lib = cbuild.build(True)
    cfg = controller_config(lib, code, "tdroc", "paper", code.params, Experiment())
    cfg.a = 1.5
    with pytest.raises(FreezeError, match=r"WMR_ERR_BAD_DISCOUNT \(field a\)"):
        freeze(lib, code, "tdroc", cfg)
    cfg.a = 0.9
    cfg.k2[3] = -1.0
    with pytest.raises(FreezeError, match=r"WMR_ERR_BAD_GAINS \(field k2\[3\]\)"):
        freeze(lib, code, "tdroc", cfg)


def test_real_literals_are_exact() -> None:
    for x in (0.1, -3.5e-310, 1e300, 0.0, np.float32(0.1)):
        assert float.fromhex(real_literal(float(x), False)) == float(x)
    assert real_literal(float(np.float32(0.1)), True) == "0x1.99999ap-4f"
    with pytest.raises(FreezeError, match="not finite"):
        real_literal(float("nan"), False)


def _compile(tmp: Path, header_dir: Path, defines: list[str]) -> subprocess.CompletedProcess[str]:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not available")
    return subprocess.run(
        [gcc, *STRICT, "-c", "-DWMR_TDROC_FROZEN", *defines, f"-I{cbuild.GENERATED_C}",
         f"-I{header_dir}", str(cbuild.GENERATED_C / "wmr_tdroc.c"), "-o", str(tmp / "t.o")],
        capture_output=True, text=True)


def test_header_refuses_the_other_precision_and_formulation(tmp_path: Path) -> None:
    assert freeze_main(["--controller", "tdroc", "--formulation", "minimal", "--float32",
                        "--out", str(tmp_path)]) == 0
    assert _compile(tmp_path, tmp_path, ["-DWMR_FLOAT32"]).returncode == 0
    double = _compile(tmp_path, tmp_path, [])
    assert double.returncode != 0 and "frozen for float32 builds" in double.stderr
    other = _compile(tmp_path, tmp_path,
                     ["-DWMR_FLOAT32", "-DWMR_FORMULATION_ONLY=WMR_FORMULATION_PAPER"])
    assert other.returncode != 0 and "other formulation" in other.stderr


def test_header_refuses_other_generated_code(tmp_path: Path) -> None:
    """A header made for this code does not compile beside regenerated code (another
    WMR_CODE_ID), even a copy of the generated C in a firmware tree."""
    assert freeze_main(["--controller", "tdroc", "--out", str(tmp_path / "fw")]) == 0
    copy = tmp_path / "c"
    shutil.copytree(cbuild.GENERATED_C, copy)
    gcc = shutil.which("gcc")
    assert gcc is not None

    def compile_copy() -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [gcc, *STRICT, "-c", "-DWMR_TDROC_FROZEN", f"-I{copy}", f"-I{tmp_path / 'fw'}",
             str(copy / "wmr_tdroc.c"), "-o", str(tmp_path / "t.o")],
            capture_output=True, text=True)

    assert compile_copy().returncode == 0
    types = copy / "wmr_types.h"
    text = types.read_text()
    code_id = re.search(r"#define WMR_CODE_ID (0x[0-9a-f]{8}u)", text)
    assert code_id is not None
    types.write_text(text.replace(code_id.group(1), "0x12345678u"))
    stale = compile_copy()
    assert stale.returncode != 0 and "made for other generated code" in stale.stderr


def test_code_id_is_the_generated_code_s(tmp_path: Path) -> None:
    """WMR_CODE_ID hashes every generated C file but the example, with the value unset:
    recomputed here from the files on disk."""
    files = {p.name: p.read_text() for p in cbuild.GENERATED_C.iterdir()
             if p.suffix in (".c", ".h") and not p.name.endswith("_frozen.h")}
    stamped = files["wmr_types.h"]
    code_id = re.search(r"#define WMR_CODE_ID (0x[0-9a-f]{8}u)", stamped)
    assert code_id is not None
    files["wmr_types.h"] = stamped.replace(code_id.group(1), CODE_ID_UNSET)
    assert stamp_code_id(files, "wmr_types.h", "WMR_CODE_ID",
                         exclude=("example_main.c",)) == code_id.group(1)
    files["wmr_types.h"] = stamped.replace(code_id.group(1), CODE_ID_UNSET)
    files["wmr_laws.c"] += "\n"  # any change to the code changes the identity
    assert stamp_code_id(files, "wmr_types.h", "WMR_CODE_ID",
                         exclude=("example_main.c",)) != code_id.group(1)


def test_command_check_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "fw"
    args = ["--controller", "roc", "--out", str(out)]
    assert freeze_main([*args, "--check"]) == 1  # missing
    assert freeze_main(args) == 0
    header = out / "wmr_roc_frozen.h"
    good = header.read_text()
    assert freeze_main([*args, "--check"]) == 0
    assert freeze_main([*args, "--nominal", "m=40", "--check"]) == 1  # stale
    capsys.readouterr()
    # Refused: the error names the field, and the header written before is left as it was.
    assert freeze_main([*args, "--nominal", "m=-5"]) == 2
    assert "WMR_ERR_BAD_NOMINAL" in capsys.readouterr().err
    assert freeze_main([*args, "--nominal", "mass=5"]) == 2
    assert "--nominal mass: not a parameter" in capsys.readouterr().err
    assert freeze_main([*args, "--nominal", "m=heavy"]) == 2
    assert "not a number" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[controller]\nn = 99\nbogus = 1\n")
    assert freeze_main([*args, "--experiment", str(bad)]) == 2
    assert "bogus" in capsys.readouterr().err
    assert header.read_text() == good
    assert [p.name for p in out.iterdir()] == ["wmr_roc_frozen.h"]  # no temporary left
    # ROC's bounds sample the model: a nominal model the C refuses is named, not a crash.
    for bad_value in ("m=0", "b=0", "d=1e300"):
        assert freeze_main([*args, "--nominal", bad_value]) == 2
        assert "WMR_ERR_BAD_NOMINAL" in capsys.readouterr().err
    assert freeze_main(["--controller", "roc", "--robot", "nosuch", "--out",
                        str(tmp_path / "never")]) == 2
    assert "nosuch" in capsys.readouterr().err and not (tmp_path / "never").exists()
    assert header.read_text() == good


def test_command_sets_fields_and_checks_them(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "fw"
    base = ["--controller", "asmc", "--out", str(out)]
    assert freeze_main([*base, "--set", "gain0=0.5", "--set", "k1=4,4,4,2,2"]) == 0
    text = (out / "wmr_asmc_frozen.h").read_text()
    assert ".gain0 = 0x1p-1," in text and ".k1 = {0x1p+2, 0x1p+2, 0x1p+2, 0x1p+1, 0x1p+1}" in text
    assert ".gain0 = 0x1p-1," in text.split("_STATE")[-1]  # _init copied it into the state
    for item, message in (("bogus=1", "not a field"), ("k1=1,2", "2 values for 5"),
                          ("gain0=x", "not a number"), ("gamma=inf", "not finite"),
                          ("gain0=-1", "WMR_ERR_BAD_BOUNDS (field gain0)"),
                          ("nominal=1", "not a field")):
        assert freeze_main([*base, "--set", item]) == 2, item
        assert message in capsys.readouterr().err, item
    assert freeze_main(["--controller", "tdroc", "--set", "n=2.5", "--out", str(out)]) == 2
    assert "an integer field" in capsys.readouterr().err


def test_command_writes_a_readable_header_and_checks_only_what_matters(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The header gets the umask's permissions (not mkstemp's 0600) and keeps an existing
    one's; --check compares the configuration, state and code identity, not the provenance
    comment (the experiment's path as typed); a path with */ cannot end that comment."""
    exp_dir = tmp_path / "exp*"
    exp_dir.mkdir()
    (exp_dir / "x*.toml").write_text("[controller]\nh = 0.05\n")
    out = tmp_path / "fw"
    monkeypatch.chdir(tmp_path)
    old = os.umask(0o022)
    try:
        assert freeze_main(["--controller", "tdroc", "--experiment", "exp*/x*.toml",
                            "--out", str(out)]) == 0
        header = out / "wmr_tdroc_frozen.h"
        assert header.stat().st_mode & 0o777 == 0o644
        header.chmod(0o664)
        assert freeze_main(["--controller", "tdroc", "--experiment",
                            str(exp_dir / "x*.toml"), "--out", str(out)]) == 0
        assert header.stat().st_mode & 0o777 == 0o664
    finally:
        os.umask(old)
    assert freeze_main(["--controller", "tdroc", "--experiment", "./exp*/x*.toml",
                        "--out", str(out), "--check"]) == 0
    assert freeze_main(["--controller", "tdroc", "--out", str(out), "--check"]) == 1  # h
    assert _compile(tmp_path, out, []).returncode == 0


@pytest.mark.parametrize("name", ["tdc", "tdroc", "roc", "asmc"])
def test_frozen_builds_pass_the_strict_compilers(tmp_path: Path, name: str) -> None:
    """Each controller's frozen build (float32; double for TDROC) under gcc's strict flags
    and clang -Weverything with the documented exclusions (docs/STATIC_CHECKS.md)."""
    from test_controller_contract import CLANG_EXCLUSIONS

    compilers = [(c, flags) for c, flags in (("gcc", STRICT), ("clang", (
        "-std=c99", "-Weverything", "-Werror", *CLANG_EXCLUSIONS))) if shutil.which(c)]
    if not compilers:
        pytest.skip("neither gcc nor clang installed")
    for float32 in (True, False) if name == "tdroc" else (True,):
        out = tmp_path / ("f32" if float32 else "f64")
        assert freeze_main(["--controller", name, "--out", str(out),
                            *(["--float32"] if float32 else [])]) == 0
        for compiler, flags in compilers:
            proc = subprocess.run(
                [compiler, *flags, "-fsyntax-only", f"-DWMR_{name.upper()}_FROZEN",
                 *(["-DWMR_FLOAT32"] if float32 else []), f"-I{cbuild.GENERATED_C}",
                 f"-I{out}", str(cbuild.GENERATED_C / f"wmr_{name}.c")],
                capture_output=True, text=True)
            assert proc.returncode == 0 and not proc.stderr.strip(), (compiler, proc.stderr)


SMALL_ROBOT = Path(__file__).resolve().parents[1] / "robots" / "small_robot.toml"


@pytest.fixture(scope="module")
def small_robot_code(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The generated code of tests/robots/small_robot.toml (a TurtleBot-sized robot whose
    paper formulation `wmr stability` predicts unstable)."""
    from codegen.__main__ import main as model_main

    out = tmp_path_factory.mktemp("small_robot_code")
    assert model_main(["--robot", str(SMALL_ROBOT), "--out", str(out)]) == 0
    return out / "small_robot"  # its own folder and prefix (modeling.robot_file.KINDS)


def test_freeze_refuses_what_stability_calls_unstable(
        tmp_path: Path, small_robot_code: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 25: the small robot's paper formulation is predicted unstable (spectral radius
    1.057 > 1 on its scaled circle, as `wmr stability --robot` says): asked for, it is
    refused in one line that names the verdict and the stable formulation, and nothing is
    written; without --formulation the minimal one is frozen, with its verdict in the
    header; --force freezes the unstable one and says so."""
    out = tmp_path / "fw"
    base = ["--controller", "tdroc", "--robot", str(small_robot_code), "--out", str(out)]
    capsys.readouterr()
    assert freeze_main([*base, "--formulation", "paper"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "tdroc/paper UNSTABLE: spectral radius 1.057" in err
    assert "tdroc/minimal is predicted stable (spectral radius 0.863)" in err
    assert "--formulation minimal" in err and "--force" in err
    assert not out.exists()
    assert freeze_main(base) == 0
    assert "freezing the minimal formulation" in capsys.readouterr().err
    text = (out / "small_robot_tdroc_frozen.h").read_text()
    assert "--formulation minimal" in text and ".formulation = 1," in text
    assert "Sampled-data verdict: tdroc/minimal stable: spectral radius 0.863" in text
    assert freeze_main([*base, "--formulation", "paper", "--force"]) == 0
    assert "frozen anyway (--force)" in capsys.readouterr().err
    text = (out / "small_robot_tdroc_frozen.h").read_text()
    assert ".formulation = 0," in text and "UNSTABLE" in text and "(frozen with --force)" in text


def test_freeze_keeps_drishti_s_paper_formulation(tmp_path: Path) -> None:
    """Drishti's paper formulation is predicted stable: the default stays paper, with the
    verdict (spectral radius below 1) in the header; a robot of bodies and wheels (the
    trailer, its one formulation) gets its verdict the same way (issue 29)."""
    assert freeze_main(["--controller", "tdc", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "wmr_tdc_frozen.h").read_text()
    assert ".formulation = 0," in text
    found = re.search(r"Sampled-data verdict: tdc/paper stable: spectral radius (\S+) ", text)
    assert found is not None and float(found.group(1)) < 1.0
    assert freeze_main(["--controller", "tdc", "--robot", "trailer", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "trailer_tdc_frozen.h").read_text()
    found = re.search(r"Sampled-data verdict: tdc/minimal stable: spectral radius (\S+) ", text)
    assert found is not None and float(found.group(1)) < 1.0
