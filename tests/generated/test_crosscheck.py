"""The crosscheck: for the paper's robot, generated Python, C (double, float32) and CasADi
against the hand-written equations (runtime/tooling/witness); for every generated robot, C and
CasADi against its generated NumPy and the C controllers against its Python classes; and
that each comparison would notice a deviating implementation."""

from __future__ import annotations

import ast
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from runtime.bindings.generated import GENERATED
from runtime.tooling.crosscheck import command as crosscheck
from runtime.tooling.crosscheck import generated_functions
from runtime.tooling.crosscheck.deviation import (
    CONTROLLER_IMPLS,
    FUNCTION_IMPLS,
    IMPLS,
    Deviation,
    generated_tolerance,
)
from runtime.tooling.crosscheck.report import CrosscheckReport
from runtime.tooling.crosscheck.targets import Target, all_targets, resolve, target_of
from runtime.tooling.witness import controllers as hc
from runtime.tooling.witness import model as hw

HANDWRITTEN = Path(hw.__file__).resolve().parent
TRAILER = GENERATED / "trailer"
needs_trailer = pytest.mark.skipif(not (TRAILER / "python" / "robot.py").is_file(),
                                   reason="no trailer generated")


@pytest.fixture(scope="module")
def drishti() -> Target:
    return resolve("drishti")


@pytest.fixture(scope="module")
def all_robots() -> CrosscheckReport:
    """The default selection (every generated robot), quick sample counts."""
    return crosscheck.crosscheck(quick=True)


def test_crosscheck_passes(all_robots: CrosscheckReport) -> None:
    out = all_robots.render()
    assert not all_robots.failing(), out
    assert "PASSED" in out
    for name in ("tdroc/paper", "asmc/minimal", "M (14)", "kinematics (31)"):
        assert name in out
    assert {r.name for r in all_robots.robots} == {t.name for t in all_targets()}
    for robot in all_robots.robots:
        assert f"Robot {robot.name} (" in out  # the report names each robot
    # no shipped robot draws an audit warning: no audit section (a robot that draws them:
    # tests/runtime/test_audit_warnings_travel.py)
    assert "Robot file audit" not in out


def test_crosscheck_exercises_every_branch(all_robots: CrosscheckReport) -> None:
    report = all_robots.robot("drishti").handwritten
    assert report is not None and not report.failing()
    for branch, count in report.cover.items():
        assert count > 0, branch
    # every implementation is compared for every function and controller × formulation
    assert len(report.ctrl_rows) == len(hc.KINDS) * len(hc.FORMULATIONS)
    for row in (*report.model_rows, *report.ctrl_rows):
        assert set(row.cells) == set(IMPLS)


@pytest.mark.parametrize(
    ("impl", "key", "factor"),
    [
        ("python", "d", 1.000001),
        ("c64", "K", 1.0001),
        ("casadi", "Iw", 1.000001),
        ("c32", "m", 1.01),  # float32 is checked to 1e-4: a 1 % error must show
    ],
)
def test_crosscheck_detects_a_deviating_implementation(
    drishti: Target, impl: str, key: str, factor: float
) -> None:
    report = crosscheck.handwritten_crosscheck(drishti, quick=True, perturb={impl: {key: factor}})
    failing = report.failing()
    assert failing, report.render()
    # only the perturbed implementation fails, and it fails somewhere in the controllers too
    assert {i for _, i in failing} == {impl}, report.render()
    assert any(row in {r.name for r in report.ctrl_rows} for row, _ in failing)


def test_cli_exit_status_on_deviation(capsys: pytest.CaptureFixture[str]) -> None:
    assert crosscheck.main(["--robot", "drishti", "--quick", "--perturb", "c64:b=1.00001"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "Robot drishti (" in out and "Robot trailer" not in out


# ------------------------------------------------------------------ any generated robot
@needs_trailer
def test_trailer_checks_every_generated_function_and_controller(
    all_robots: CrosscheckReport,
) -> None:
    """No hand-written reference: every function of the generated model, laws and plant
    (enumerated from the generated modules; the C prepared forward dynamics against the
    NumPy one) in C double, float32 and CasADi at ≥ 100 random states, and the five C
    controllers in both precisions, every branch taken."""
    robot = all_robots.robot("trailer")
    assert robot.handwritten is None
    report = robot.generated
    code = resolve("trailer").code
    expected = {n for m in (code.model, code.laws, code.plant) for n in m.__all__}
    expected.add("forward_dynamics_prepared")
    assert {r.name for r in report.function_rows} == expected
    assert len(expected) >= 15 and report.n_samples >= 100
    for row in report.function_rows:
        assert set(row.cells) == set(FUNCTION_IMPLS)
    assert [r.name for r in report.ctrl_rows] == [
        f"{k}/minimal" for k in ("tdc", "tdroc", "roc", "asmc", "pi")]
    for row in report.ctrl_rows:
        assert set(row.cells) == set(CONTROLLER_IMPLS)
    assert report.n_steps >= 200
    for branch, count in report.cover.items():
        assert count > 0, branch
    assert not robot.failing(), robot.render()


@needs_trailer
def test_trailer_header_sizes_match_the_robot() -> None:
    """The function enumeration reads argument sizes from the generated header."""
    target = resolve("trailer")
    fns = {f.name: f for f in generated_functions.functions(target)}
    fd = fns["forward_dynamics"]
    assert [(a.name, a.size) for a in fd.inputs if not a.struct] == [
        ("q", target.code.nq), ("qdot", target.code.nq), ("tau", target.code.nu)]
    assert fd.returns_status and [a.name for a in fd.outputs] == ["qddot"]
    assert fns["plant_state_derivative"].outputs[0].size == target.code.nq + target.code.nu


@needs_trailer
def test_prepared_functions_are_compared_with_their_numpy_function() -> None:
    """``<prefix>_forward_dynamics_prepared`` is a row of its own, against the NumPy and
    CasADi ``forward_dynamics``, its struct filled by ``<prefix>_model_prepare`` from the
    sample's parameters; the prepare function itself is not a row."""
    for name in ("drishti", "trailer"):
        target = resolve(name)
        fns = {f.name: f for f in generated_functions.functions(target)}
        assert "model_prepare" not in fns
        fd = fns["forward_dynamics_prepared"]
        assert fd.reference == "forward_dynamics"
        assert fd.python is target.code.model.forward_dynamics
        assert [a.name for a in fd.inputs] == ["prepared", "q", "qdot", "tau"]
        assert [a.name for a in fd.value_inputs()] == ["p", "q", "qdot", "tau"]
        assert [p.name for _, p in fd.prepares] == ["model_prepare"]


@needs_trailer
@pytest.mark.parametrize(("impl", "key", "factor"),
                         [("casadi", "J_x_tractor", 1.000001), ("c32", "J_theta_tractor", 1.01)])
def test_trailer_crosscheck_detects_a_deviating_implementation(
    impl: str, key: str, factor: float
) -> None:
    target = resolve("trailer")
    perturb = {impl: {key: factor}}
    if impl == "casadi":  # CasADi has no controller: its laws are compared as functions
        samples = generated_functions.random_samples(target, np.random.default_rng(1), 100)
        rows = generated_functions.check_functions(target, samples, perturb)
        failing = {(r.name, i) for r in rows for i, d in r.cells.items()
                   if not d.value <= generated_tolerance(i)}
        assert failing and {i for _, i in failing} == {impl}
        return
    report = crosscheck.generated_crosscheck(target, quick=True, perturb=perturb)
    failing = report.failing()
    assert failing, "\n".join(report.sections())
    assert {i for _, i in failing} == {impl}
    assert any(row in {r.name for r in report.ctrl_rows} for row, _ in failing)


@needs_trailer
def test_trailer_crosscheck_fails_on_a_modified_c_function(tmp_path: Path) -> None:
    """A copy of the trailer's generated code whose C ``trailer_minimal_tdc_law_mhat``
    (the TDC law kernel the step calls, with the M-hat the step evaluated once) scales u[0]
    by 1 + 1e-6, and so does the TDC step (both through ``trailer_k_minimal_tdc_law_mhat``):
    the crosscheck of that folder fails for C double, in that function's row and in the
    TDC controller, and nowhere else."""
    copy = tmp_path / "trailer"
    shutil.copytree(TRAILER / "python", copy / "python")
    shutil.copytree(TRAILER / "c", copy / "c")
    (copy / "casadi").symlink_to(TRAILER / "casadi", target_is_directory=True)
    # the kernel is written once (trailer_kernels.h): the laws function wraps it
    kernels = copy / "c" / "trailer_kernels.h"
    text = kernels.read_text()
    start = text.index("TRAILER_KERNEL_INLINE void trailer_k_minimal_tdc_law_mhat(")
    end = text.index("\n}\n", start)
    kernels.write_text(text[:end] + "\n    u[0] *= TRAILER_LIT(1.000001);" + text[end:])
    out_file = tmp_path / "report.txt"
    status = crosscheck.main(["--robot", str(copy), "--quick", "--out", str(out_file)])
    out = out_file.read_text()
    assert status == 1, out
    assert "Robot trailer (" in out and "FAILED" in out
    failing = [ln.split()[0] for ln in out.splitlines() if re.search(r"\bFAIL\b", ln)]
    assert failing == ["minimal_tdc_law_mhat", "tdc/minimal"], out
    for ln in out.splitlines():
        if ln.startswith(("minimal_tdc_law_mhat ", "tdc/minimal")):
            assert ln.count("FAIL") == 1, ln  # C double only: 1e-6 is float32 rounding
    # The unmodified folder passes (the failure is the modification, not the copy).
    assert not crosscheck.generated_crosscheck(target_of(TRAILER), quick=True).failing()


def test_unknown_robot_is_refused() -> None:
    with pytest.raises(SystemExit, match="not a generated robot"):
        crosscheck.main(["--robot", "no-such-robot"])


def test_deviation_flags_mismatch_and_nan() -> None:
    d = Deviation()
    d.add("x", [np.array([1.0, 2.0])], [np.array([1.0, 2.0])])
    assert d.value == 0.0
    d.add("y", [np.array([1.0, 2.0 + 1e-6])], [np.array([1.0, 2.0])])
    assert d.value == pytest.approx(5e-7) and d.worst == "y"
    d.add("z", [np.array([np.nan])], [np.array([1.0])])
    assert d.value == np.inf and d.worst == "z"


def test_handwritten_is_independent_of_modeling_and_codegen() -> None:
    for path in HANDWRITTEN.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            for name in names:
                root = name.split(".")[0]
                assert root not in {"modeling", "codegen", "generated", "sympy"}, (path, name)
                if root == "runtime":
                    assert name.startswith("runtime.tooling.witness"), (path, name)


def test_printed_31_violates_the_rolling_constraints() -> None:
    """The erratum in (31): with b (as printed) instead of b/2, (7)-(8) do not hold."""
    p = hw.DRISHTI
    q = np.array([0.3, -0.2, 0.7, 1.0, 2.0])
    eta = np.array([2.0, 1.0])
    a = hw.constraint_matrix(q, p)
    fixed = np.concatenate([hw.kinematics_31(q, eta, p), eta])
    printed = np.concatenate([hw.kinematics_31_as_printed(q, eta, p), eta])
    assert np.abs(a @ fixed).max() < 1e-14
    assert np.abs(a @ printed).max() > 0.1


def test_mass_matrix_14_is_not_symmetric() -> None:
    """M(4,1) = −k1, M(4,2) = −k3, M(4,3) = +k5 while M(1,4) = k1, M(2,4) = k3, M(3,4) = −k5."""
    q = np.array([0.0, 0.0, 0.4, 0.0, 0.0])
    m = hw.mass_matrix_14(q, hw.DRISHTI)
    k1, k2, k3, k4, k5 = hw.coupling_k(q, hw.DRISHTI)
    assert m[3, 0] == -m[0, 3] == -k1 and m[3, 1] == -m[1, 3] == -k3
    assert m[4, 0] == -k2 and m[4, 1] == -k4
    assert m[3, 2] == k5 == -m[2, 3] and m[4, 2] == -k5 == -m[2, 4]


def test_out_naming_a_folder_fails_before_any_work(tmp_path: Path) -> None:
    from runtime.tooling.crosscheck.command import main as crosscheck_main

    with pytest.raises(SystemExit, match="is a folder; name the report file"):
        crosscheck_main(["--out", str(tmp_path)])
