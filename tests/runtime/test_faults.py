"""Fault injection in the closed loop (runtime.experiment.faults, runtime.sim.loop) and the fault
table (runtime.fault_table, docs/FAULTS.md)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from runtime import fault_table as ft
from runtime.bindings.generated import load_robot_code
from runtime.commands import faults as faults_command
from runtime.experiment.faults import Fault, FaultSpecError, schedule
from runtime.experiment.settings import Experiment, ExperimentFileError, parse_experiment
from runtime.sim import loop, paths
from runtime.sim.loop import NOT_CALLED, Run
from runtime.sim.reference import Reference
from runtime.stability.checks import check_configuration

ROOT = Path(__file__).resolve().parents[2]
EXP = Experiment()
CODE = load_robot_code("")  # the paper's robot
ROBOT = dict(CODE.params)
H = EXP.controller.h
START = 3.0
K0 = round(START / H)


def run(ctrl: str, form: str, ref: Reference, robot: dict[str, float], exp: Experiment,
        faults: list[Fault] | None = None) -> Run:
    """The checked closed loop on the paper's robot."""
    check_configuration(CODE, ctrl, form, robot, exp)
    return loop.run(CODE, ctrl, form, ref, robot, exp, faults=faults or ())


@pytest.fixture(scope="module")
def ref() -> Reference:
    return paths.circle(CODE, ROBOT, replace(EXP, paths=replace(EXP.paths, circle_duration=8.0)))


@pytest.fixture(scope="module")
def base(ref: Reference) -> Run:
    return run("tdc", "paper", ref, ROBOT, EXP)


def faulted(ref: Reference, fault: Fault) -> Run:
    return run("tdc", "paper", ref, ROBOT, EXP, faults=[fault])


def cpr() -> float:
    return EXP.sensing.counts_per_wheel_rev() / (2 * math.pi)


def counts_off(r: Run) -> np.ndarray:
    """Measured minus quantised rolling wheel angle, in counts, per sample (right, left)."""
    rolling = np.floor(r.q[:, 3:5] * cpr())
    return np.asarray(np.round(r.q_meas[:, 3:5] * cpr() - rolling))


def test_no_fault_changes_nothing(ref: Reference, base: Run) -> None:
    again = run("tdc", "paper", ref, ROBOT, EXP, faults=[])
    assert np.array_equal(again.q, base.q) and np.array_equal(again.tau, base.tau)
    assert np.array_equal(base.tau, base.tau_applied)
    assert not np.any(base.status == NOT_CALLED)


def test_encoder_miscount_persists(ref: Reference, base: Run) -> None:
    r = faulted(ref, Fault("encoder-glitch", START, 0.0, 50, "right"))
    off = counts_off(r)
    assert np.all(off[:K0] == 0)
    assert np.all(off[K0:, 0] == 50) and np.all(off[K0:, 1] == 0)
    assert np.array_equal(r.q[: K0 + 1], base.q[: K0 + 1])  # the plant is untouched until then
    assert not np.allclose(r.q[-1], base.q[-1])


def test_encoder_read_error_is_transient(ref: Reference) -> None:
    r = faulted(ref, Fault("encoder-glitch", START, 2 * H, -7, "left"))
    off = counts_off(r)
    assert list(off[K0 - 1 : K0 + 3, 1]) == [0, -7, -7, 0]
    assert np.all(off[:, 0] == 0)


def test_dropped_samples_hold_the_torque(ref: Reference, base: Run) -> None:
    r = faulted(ref, Fault("dropped-sample", START, 3 * H))
    assert list(np.nonzero(r.status == NOT_CALLED)[0]) == [K0, K0 + 1, K0 + 2]
    for k in (K0, K0 + 1, K0 + 2):
        assert np.array_equal(r.tau[k], base.tau[K0 - 1])
    assert not np.allclose(r.q[K0 + 3 :], base.q[K0 + 3 :])


def test_repeated_sample_delivers_the_previous_measurement(
    ref: Reference, base: Run
) -> None:
    r = faulted(ref, Fault("repeated-sample", START))
    assert np.array_equal(r.q_meas[K0], r.q_meas[K0 - 1])
    assert np.array_equal(r.qdot_meas[K0], r.qdot_meas[K0 - 1])
    assert not np.array_equal(r.q_meas[K0 + 1], r.q_meas[K0])  # fresh again
    assert not np.array_equal(r.tau[K0], base.tau[K0])


def test_traction_loss_spins_the_wheel(ref: Reference, base: Run) -> None:
    r = faulted(ref, Fault("traction-loss", START, 0.3, 1.0, "right"))
    off = counts_off(r)
    assert np.all(off[: K0 + 1] == 0)
    spin = slice(K0 + 1, K0 + 4)  # samples taken while the wheel slips
    assert np.abs(off[spin, 0]).max() > 10 and np.all(off[:, 1] == 0)  # counted by the encoder
    # The slip angle stays in the count (±1 count: it is not a whole number of counts).
    assert abs(off[K0 + 4, 0]) > 10 and np.abs(off[K0 + 4 :, 0] - off[K0 + 4, 0]).max() <= 1
    # The drive reads the spinning wheel, not the rolling one.
    assert np.abs(r.qdot_meas[spin, 3] - base.qdot_meas[spin, 3]).max() > 0.5
    assert not np.allclose(r.q[K0 + 1, :3], base.q[K0 + 1, :3])


def test_torque_saturation_limits_the_delivered_torque(
    ref: Reference, base: Run
) -> None:
    limit = 0.3
    r = faulted(ref, Fault("torque-saturation", START, 1.0, limit, "both"))
    window = slice(K0, K0 + 10)
    assert np.all(np.abs(r.tau_applied[window]) <= limit)
    assert np.any(np.abs(r.tau[window]) > limit)  # commanded more than it got
    outside = np.r_[0:K0, K0 + 10 : len(r.t)]
    assert np.array_equal(r.tau_applied[outside], r.tau[outside])
    assert np.array_equal(r.tau[:K0], base.tau[:K0])


def test_schedule_combines_faults() -> None:
    s = schedule(
        [
            Fault("encoder-glitch", 0.25, 0.0, 3, "both"),
            Fault("encoder-glitch", 0.5, 0.0, -1, "left"),
            Fault("torque-saturation", 0.3, 0.2, 2.0, "left"),
            Fault("torque-saturation", 0.3, 0.1, 1.0, "both"),
        ],
        0.1,
        8,
    )
    assert s.encoder_offset[:, 0].tolist() == [0, 0, 0, 3, 3, 3, 3, 3]
    assert s.encoder_offset[:, 1].tolist() == [0, 0, 0, 3, 3, 2, 2, 2]
    assert s.torque_limit[3].tolist() == [1.0, 1.0] and s.torque_limit[4].tolist() == [np.inf, 2.0]
    assert np.all(np.isinf(s.torque_limit[5:]))


def test_recovery_count_on_a_synthetic_signal() -> None:
    base = np.full(100, 1e-3)
    tol = 1.1 * 1e-3 + ft.SLACK
    err = base.copy()
    err[10:15] = 10e-3  # out of the band on samples 10..14
    assert ft.recovery_samples(err, base, k_end=12) == 3
    assert ft.recovery_samples(err, base, k_end=15) == 0
    err2 = base.copy()
    err2[40] = tol * 1.001  # just outside once
    assert ft.recovery_samples(err2, base, k_end=12) == 29
    err2[40] = tol * 0.999  # just inside
    assert ft.recovery_samples(err2, base, k_end=12) == 0
    late = base.copy()
    late[90] = 1.0  # back only 9 samples before the end: not recovered
    assert ft.recovery_samples(late, base, k_end=12) is None
    assert ft.recovery_samples(base + 5e-3, base, k_end=12) is None  # a lasting offset
    assert ft.recovery_samples(base[:60], base, k_end=12) is None  # the run stopped
    # The band follows the fault-free envelope over ±WINDOW samples.
    bumpy = base.copy()
    bumpy[50] = 20e-3
    err3 = base.copy()
    err3[50 + ft.WINDOW] = 20e-3
    assert ft.recovery_samples(err3, bumpy, k_end=12) == 0
    err3[50 + ft.WINDOW + 1] = 20e-3
    assert ft.recovery_samples(err3, bumpy, k_end=12) == 50 + ft.WINDOW + 2 - 12


GOOD = '[[fault]]\nkind = "encoder-glitch"\nstart = 8.0\nmagnitude = 50\nwheel = "left"\n'


def test_fault_tables_are_parsed() -> None:
    exp = parse_experiment(GOOD + '[[fault]]\nkind = "dropped-sample"\nstart = 1\nduration = 0.2\n')
    assert exp.faults == (
        Fault("encoder-glitch", 8.0, 0.0, 50, "left"),
        Fault("dropped-sample", 1.0, 0.2),
    )
    assert parse_experiment("").faults == ()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('[[fault]]\nkind = "glitch"\nstart = 1\n', "[[fault]] #1: field 'kind' must be one of"),
        ("[[fault]]\nstart = 1\n", "[[fault]] #1: field 'kind' is missing"),
        ('[[fault]]\nkind = "dropped-sample"\n', "field 'start' is missing"),
        (
            GOOD + '[[fault]]\nkind = "dropped-sample"\nstart = 1\nwhen = 2\n',
            "[[fault]] #2: unknown field 'when'",
        ),
        ('[[fault]]\nkind = "dropped-sample"\nstart = 0\n', "field 'start' must be positive"),
        (
            '[[fault]]\nkind = "dropped-sample"\nstart = 1\nduration = -1\n',
            "field 'duration' must be non-negative",
        ),
        ('[[fault]]\nkind = "dropped-sample"\nstart = "1"\n', "field 'start' must be a number"),
        ('[[fault]]\nkind = "dropped-sample"\nstart = nan\n', "field 'start' must be finite"),
        (
            '[[fault]]\nkind = "dropped-sample"\nstart = 1\nmagnitude = 2\n',
            "field 'magnitude' is not used by 'dropped-sample'",
        ),
        (
            '[[fault]]\nkind = "repeated-sample"\nstart = 1\nwheel = "left"\n',
            "field 'wheel' is not used by 'repeated-sample'",
        ),
        (
            '[[fault]]\nkind = "encoder-glitch"\nstart = 1\nmagnitude = 2.5\n',
            "must be a non-zero whole number of counts",
        ),
        ('[[fault]]\nkind = "encoder-glitch"\nstart = 1\n', "non-zero whole number"),
        (
            '[[fault]]\nkind = "traction-loss"\nstart = 1\nduration = 1\nmagnitude = 1.5\n',
            "must be in (0, 1]",
        ),
        (
            '[[fault]]\nkind = "traction-loss"\nstart = 1\nmagnitude = 1\n',
            "field 'duration' of 'traction-loss' must be positive",
        ),
        (
            '[[fault]]\nkind = "torque-saturation"\nstart = 1\nduration = 1\nmagnitude = 0\n',
            "must be a positive torque",
        ),
        (
            '[[fault]]\nkind = "torque-saturation"\nstart = 1\nduration = 1\nmagnitude = 1\n'
            'wheel = "front"\n',
            "field 'wheel' must be one of",
        ),
        ('[fault]\nkind = "dropped-sample"\nstart = 1\n', "must be an array of tables"),
    ],
)
def test_bad_fault_specs_are_rejected(text: str, message: str) -> None:
    with pytest.raises(ExperimentFileError) as info:
        parse_experiment(text, "f.toml")
    assert message in str(info.value)
    assert str(info.value).startswith("f.toml: ") and "\n" not in str(info.value)


def test_fault_checks_apply_to_code_too() -> None:
    with pytest.raises(FaultSpecError, match="field 'magnitude' of 'torque-saturation'"):
        Fault("torque-saturation", 1.0, 1.0, -2.0)


@pytest.fixture(scope="module")
def table() -> ft.FaultTable:
    return ft.fault_table(EXP)


def test_committed_fault_table_is_the_commands_output(table: ft.FaultTable) -> None:
    assert (ROOT / "docs" / "FAULTS.md").read_text(encoding="utf-8") == ft.markdown(table)
    assert (ROOT / "docs" / "faults.csv").read_text(encoding="utf-8") == ft.csv_text(table)


def test_nothing_diverges_and_nothing_is_silent(table: ft.FaultTable) -> None:
    assert len(table.rows) == len(ft.DEFAULT_FAULTS) * len(CODE.runs())
    for r in table.rows:
        assert not r.diverged, r
        assert math.isfinite(r.peak_error) and r.peak_torque <= EXP.controller.tau_max
        assert r.statuses or r.flags, f"{r.fault.label()} {r.controller}/{r.formulation}: silent"
        assert r.false_alarms == 0


def test_verdicts_tell_a_refused_step_from_divergence(table: ft.FaultTable) -> None:
    row = table.rows[0]
    stopped = replace(row, stopped_at=8.1, stop_status="WMR_ERR_BAD_MEASUREMENT", recovery=None)
    diverged = replace(row, stopped_at=8.1, stop_status=None, recovery=None)
    assert stopped.verdict(H).startswith("stopped: step returned `WMR_ERR_BAD_MEASUREMENT`")
    assert not stopped.diverged and diverged.diverged
    assert diverged.verdict(H) == "diverged: non-finite state at 8.1 s"
    late = replace(row, recovery=None, last_outside=29.9, end_error=0.0123, base_end_error=0.001)
    assert late.verdict(H) == (
        "bounded, not recovered: outside the tolerance until 29.9 s; 12.3 mm at the end "
        "(fault-free 1.0)"
    )


def test_command_runs_the_experiments_faults(tmp_path: Path) -> None:
    exp_file = tmp_path / "e.toml"
    exp_file.write_text(
        '[paths]\ncircle_duration = 6.0\n[[fault]]\nkind = "repeated-sample"\nstart = 2.0\n',
        encoding="utf-8",
    )
    assert faults_command.main(["--experiment", str(exp_file), "--out", str(tmp_path / "out")]) == 0
    text = (tmp_path / "out" / "FAULTS.md").read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if line.startswith("| repeated-sample")]
    assert len(rows) == len(CODE.runs())
    assert "encoder-glitch" not in text.split("## Faults")[1].split("## How")[0]


def test_command_rejects_a_bad_experiment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    exp_file = tmp_path / "e.toml"
    exp_file.write_text('[[fault]]\nkind = "dropped"\nstart = 1\n', encoding="utf-8")
    assert faults_command.main(["--experiment", str(exp_file), "--out", str(tmp_path)]) == 2
    assert "[[fault]] #1: field 'kind'" in capsys.readouterr().err


def test_experiment_default_has_no_faults() -> None:
    assert replace(EXP).faults == ()


def test_a_controller_that_cannot_run_is_reported_not_crashed(tmp_path: Path) -> None:
    """The small robot users tried: ROC's bounds over its box refuse its paper-form
    configuration (init, before any sample). ``wmr faults`` said "zero-size array to
    reduction operation maximum" and wrote nothing; the table now names the controller, its
    formulation and the reason, injects no fault into it and runs the others."""
    from runtime.cli import main as wmr

    small = ROOT / "tests" / "robots" / "small_robot.toml"
    out = tmp_path / "faults"
    assert wmr(["faults", "--robot", str(small), "--out", str(out)]) == 0
    text = (out / "FAULTS.md").read_text(encoding="utf-8")
    not_run = text.split("Not run (", 1)[1].split("## Findings", 1)[0]
    assert "ROC / paper: the fault-free run stopped at 0 s: init refused the configuration: " \
        "WMR_ERR_BAD_BOUNDS" in not_run
    rows = (out / "faults.csv").read_text(encoding="utf-8").splitlines()[1:]
    assert rows and not any(",roc,paper," in r for r in rows)
    assert any(",tdroc,paper," in r for r in rows) and any(",roc,minimal," in r for r in rows)
