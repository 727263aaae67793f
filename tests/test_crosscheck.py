"""The crosscheck: generated Python, C (double, float32) and CasADi against the hand-written
equations (runtime/handwritten), and that it would notice a deviating implementation."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from runtime.handwritten import controllers as hc
from runtime.handwritten import model as hw
from runtime.tooling.crosscheck import command as crosscheck
from runtime.tooling.crosscheck.deviation import IMPLS, Deviation

HANDWRITTEN = Path(hw.__file__).resolve().parent


def test_crosscheck_passes(capsys: pytest.CaptureFixture[str]) -> None:
    status = crosscheck.main([])
    out = capsys.readouterr().out
    assert status == 0, out
    assert "PASSED" in out
    for name in ("tdroc/paper", "asmc/minimal", "M (14)", "kinematics (31)"):
        assert name in out


def test_crosscheck_exercises_every_branch() -> None:
    report = crosscheck.crosscheck(quick=True)
    assert not report.failing()
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
def test_crosscheck_detects_a_deviating_implementation(impl: str, key: str, factor: float) -> None:
    report = crosscheck.crosscheck(quick=True, perturb={impl: {key: factor}})
    failing = report.failing()
    assert failing, report.render()
    # only the perturbed implementation fails, and it fails somewhere in the controllers too
    assert {i for _, i in failing} == {impl}, report.render()
    assert any(row in {r.name for r in report.ctrl_rows} for row, _ in failing)


def test_cli_exit_status_on_deviation(capsys: pytest.CaptureFixture[str]) -> None:
    assert crosscheck.main(["--quick", "--perturb", "c64:b=1.00001"]) == 1
    assert "FAILED" in capsys.readouterr().out


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
                    assert name.startswith("runtime.handwritten"), (path, name)


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
