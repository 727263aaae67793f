"""The paper's experiments (issue 4): references, experiment files, and the claims.

Each claim is tested with its threshold stated. Where the paper's claim does not
reproduce with the paper's ε = 0.1, the test asserts what does happen (documented in
docs/reproduction/REPORT.md), and a second test asserts the claim at ε = 0.5, where TDROC
is stable.
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from runtime import references
from runtime.experiment import Experiment, ExperimentFileError, parse_experiment
from runtime.generated_modules import robot
from runtime.reproduce import Reproduction, claims, reproduce

ROOT = Path(__file__).resolve().parent.parent
PARAMS = dict(robot.PARAMS)


@pytest.fixture(scope="module")
def paper() -> Reproduction:
    return reproduce(Experiment())


@pytest.fixture(scope="module")
def wide_layer() -> Reproduction:
    exp = Experiment()
    return reproduce(replace(exp, controller=replace(exp.controller, eps=0.5)))


def rms(rep: Reproduction, ctrl: str, path: str, form: str = "paper") -> float:
    e = rep.runs[(ctrl, form, path)].position_error
    return float(np.sqrt(np.mean(e**2)))


@pytest.mark.parametrize("path", ["circle", "lawnmower"])
def test_references_satisfy_the_constraints(path: str) -> None:
    ref = (references.circle if path == "circle" else references.lawnmower)(PARAMS, 0.1, 30.0)
    x, y, th = ref.q[:, 0], ref.q[:, 1], ref.q[:, 2]
    xd, yd, thd, wr, wl = ref.qdot.T
    r, b, d = PARAMS["r"], PARAMS["b"], PARAMS["d"]
    # (6)–(8) typed from the paper (signs restored), to 1e-12.
    assert np.abs(-xd * np.sin(th) + yd * np.cos(th) - d * thd).max() < 1e-12
    assert np.abs(xd * np.cos(th) + yd * np.sin(th) + b / 2 * thd - r * wr).max() < 1e-12
    assert np.abs(xd * np.cos(th) + yd * np.sin(th) - b / 2 * thd - r * wl).max() < 1e-12
    # q̇_d is the derivative of q_d and q̈_d of q̇_d: central differences, whose O(h²)
    # error peaks in the 0.3 s tanh ramps (≈ h²/6 · max|q⃛| ≈ 0.03 rad/s, 0.3 rad/s²).
    dq = (ref.q[2:] - ref.q[:-2]) / 0.2
    assert np.abs(dq - ref.qdot[1:-1]).max() < 0.05
    ddq = (ref.qdot[2:] - ref.qdot[:-2]) / 0.2
    assert np.abs(ddq - ref.qddot[1:-1]).max() < 0.5
    del x, y


def test_circle_reference_puts_c_on_radius_r1() -> None:
    ref = references.circle(PARAMS, 0.1, 40.0)
    steady = ref.q[ref.t > 5.0, :2]
    # Centre of the circle through three points far apart.
    (x1, y1), (x2, y2), (x3, y3) = steady[0], steady[len(steady) // 3], steady[2 * len(steady) // 3]
    a = np.array([[x2 - x1, y2 - y1], [x3 - x1, y3 - y1]])
    rhs = 0.5 * np.array([x2**2 - x1**2 + y2**2 - y1**2, x3**2 - x1**2 + y3**2 - y1**2])
    centre = np.linalg.solve(a, rhs)
    radii = np.linalg.norm(steady - centre, axis=1)
    assert np.abs(radii - references.R1).max() < 1e-6


def test_tdc_tracks_to_millimetres(paper: Reproduction) -> None:
    for path in ("circle", "lawnmower"):
        assert rms(paper, "tdc", path) < 5e-3, path


def test_claim_asmc_gain_grows_monotonically(paper: Reproduction) -> None:
    """Reproduces: k̂ never decreases (threshold: every step change ≥ 0)."""
    for key, run in paper.runs.items():
        if key[0] == "asmc":
            assert np.diff(run.gain).min() >= 0.0, key
            assert run.gain[-1] > run.gain[10], key
    assert [c.holds for c in claims(paper)][1]


def test_claim_tdroc_best_does_not_reproduce_at_paper_eps(paper: Reproduction) -> None:
    """With ε = 0.1 TDROC's boundary layer gain k̂/ε destabilises the sampled loop:
    asserted as RMS error above 10× TDC's and more than 100 saturated steps per run."""
    for path in ("circle", "lawnmower"):
        run = paper.runs[("tdroc", "paper", path)]
        assert rms(paper, "tdroc", path) > 10 * rms(paper, "tdc", path)
        assert run.saturated > 100
        assert np.median(run.gain) > 50
    holds = [c.holds for c in claims(paper)]
    assert holds == [False, True, False]


def test_claims_hold_with_a_wider_boundary_layer(wide_layer: Reproduction) -> None:
    """With ε = 0.5: TDROC is within 10 % of TDC (the best), better than ROC and ASMC by
    at least 2×, and its median switching gain is the lowest of TDROC, ROC, ASMC."""
    for path in ("circle", "lawnmower"):
        e_tdroc = rms(wide_layer, "tdroc", path)
        assert e_tdroc < 1.1 * rms(wide_layer, "tdc", path)
        assert 2 * e_tdroc < rms(wide_layer, "roc", path)
        assert 2 * e_tdroc < rms(wide_layer, "asmc", path)
        gains = {c: float(np.median(wide_layer.runs[(c, "paper", path)].gain))
                 for c in ("tdroc", "roc", "asmc")}
        assert min(gains, key=lambda c: gains[c]) == "tdroc", gains
        assert wide_layer.runs[("tdroc", "paper", path)].saturated == 0


def test_payload_changes_the_true_mass(paper: Reproduction) -> None:
    mass = paper.runs[("tdc", "paper", "lawnmower")].payload
    assert set(np.round(np.unique(mass), 6)) == {PARAMS["m"] + 6.0, PARAMS["m"] + 9.0}


def test_reproduction_is_fast(paper: Reproduction) -> None:
    """Issue 4 goal: the whole reproduction ≤ 30 s (16 runs + 8 sweep runs here)."""
    assert paper.seconds < 30.0


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("[controler]\nh = 0.1", "controler"),
        ("[controller]\nhh = 0.1", "controller.hh"),
        ("[controller]\nh = -0.1", "controller.h"),
        ("[controller]\nh = nan", "controller.h"),
        ("[controller]\nh = 'fast'", "controller.h"),
        ("[controller]\nn = 2.5", "controller.n"),
        ("[controller]\nn = 9", "controller.n"),
        ("[controller]\na = 1.5", "controller.a"),
        ("[controller]\nuncertainty = 1.0", "controller.uncertainty"),
        ("[plant]\nsubsteps = 0", "plant.substeps"),
        ("[plant]\ncoulomb = -1.0", "plant.coulomb"),
        ("[plant]\nextra_payload = true", "plant.extra_payload"),
        ("[paths]\ncircle_duration = inf", "paths.circle_duration"),
        ("paths = 3", "paths"),
        ("[paths\n", "TOML"),
    ],
)
def test_bad_experiment_file_names_the_field(text: str, field: str) -> None:
    with pytest.raises(ExperimentFileError) as err:
        parse_experiment(text, "exp.toml")
    assert field in str(err.value) and "exp.toml" in str(err.value)


def test_experiment_file_overrides_fields() -> None:
    exp = parse_experiment("[controller]\neps = 0.5\nn = 6\n[plant]\nviscous = 0.0\n")
    assert (exp.controller.eps, exp.controller.n, exp.plant.viscous) == (0.5, 6, 0.0)
    assert exp.controller.h == 0.1  # untouched fields keep the paper's values


def test_reproduce_cli_rejects_a_bad_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[controller]\neps = 0\n")
    proc = subprocess.run([sys.executable, "-m", "runtime", "reproduce", "--experiment",
                           str(bad), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert "controller.eps" in proc.stderr and "positive" in proc.stderr
    assert not (tmp_path / "out").exists()  # nothing written


def test_reproduce_cli_writes_the_report(tmp_path: Path) -> None:
    exp = tmp_path / "short.toml"
    exp.write_text("[paths]\ncircle_duration = 5.0\nlawnmower_duration = 5.0\n")
    proc = subprocess.run([sys.executable, "-m", "runtime", "reproduce", "--experiment",
                           str(exp), "--out", str(tmp_path / "out"), "--no-plots"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    table = (tmp_path / "out" / "metrics.csv").read_text().splitlines()
    assert len(table) == 1 + 16
    assert "claim" in proc.stdout


def test_experiment_errors_are_value_errors() -> None:
    assert issubclass(ExperimentFileError, ValueError)


def test_tdc_stays_within_its_ultimate_bound(paper: Reproduction) -> None:
    """(21) with the measured TDE bound k̄ holds for TDC (stable): measured ≤ bound. For
    TDROC at ε = 0.1 the sampled loop is unstable and (30) — a continuous-time bound — is
    exceeded, which the report states."""
    from runtime.reproduce import stability

    rows = {(s.controller, s.path): s for s in stability(paper)}
    for path in ("circle", "lawnmower"):
        tdc = rows[("tdc", path)]
        assert 0 < tdc.measured <= tdc.ultimate_bound
        assert rows[("tdroc", path)].measured > rows[("tdroc", path)].ultimate_bound


def test_wheel_switching_terms_are_bounded_by_the_gain(paper: Reproduction) -> None:
    """|Δu_a,j| = k |s_j| / max(‖s‖, ε) ≤ k for every wheel and step (ASMC: the gain
    before that step's adaptation, which is ≤ the recorded one)."""
    for (ctrl, _form, _path), run in paper.runs.items():
        if ctrl == "tdc":
            assert not run.wheel_switching.any()
            continue
        assert np.all(np.abs(run.wheel_switching) <= run.gain[:, None] * (1 + 1e-9) + 1e-12)
