"""``reproduce --robot ROBOT``: the paper's experiment scaled to any robot.

What is checked: the robot's sizes measured on its generated code equal the file's
numbers; the scaling rules; the scaled references are motions the robot can make (q̇ and
q̈ agree with finite differences of q and q̇, the root drives the circle it was asked to);
odometry from the encoders follows the true motion; every controller closes the loop
through the robot's generated C; the command runs end to end for a lumped robot file and
for a described one (the trailer) and names every problem with a file before any work.
"""

from __future__ import annotations

import hashlib
import re
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from runtime.bindings.generated import GENERATED, RobotCode, load_robot_code
from runtime.bindings.robots import RobotSourceError, resolve
from runtime.bindings.uncertainty import body_yaws, inertial_keys
from runtime.commands.reproduce import main
from runtime.experiment.settings import Experiment, parse_experiment
from runtime.setting.scale import RobotScale, paper_scale, robot_scale, scaled_experiment
from runtime.sim.paths import circle, lawnmower
from runtime.sim.sensors import Sensors

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "tests" / "robots" / "small_robot.toml"  # a case users tried
TRAILER = next((ROOT / "modeling" / "robots").rglob("trailer.toml"))
SHORT = "[paths]\ncircle_duration = 6.0\nlawnmower_duration = 8.0\n"
DRISHTI = load_robot_code("").params
DRISHTI_MASS = DRISHTI["m"] + 2 * DRISHTI["Iw"] / DRISHTI["r"] ** 2  # m + 2 I_w / r²


def scaled(code: RobotCode, h: float, circle_s: float, lawn_s: float) -> Experiment:
    """The paper's setting scaled to the robot, at ``h`` with these path durations."""
    exp = scaled_experiment(Experiment(), robot_scale(code, code.params))[0]
    return replace(exp, controller=replace(exp.controller, h=h),
                   paths=replace(exp.paths, circle_duration=circle_s,
                                 lawnmower_duration=lawn_s))


def test_scale_measured_on_generated_code_equals_the_files_numbers() -> None:
    drishti = load_robot_code("")
    s = robot_scale(drishti, drishti.params)
    assert s.wheel_radius == pytest.approx(0.096, rel=1e-12)
    assert s.track == pytest.approx(0.414, rel=1e-12)
    assert s.mass == pytest.approx(DRISHTI_MASS, rel=1e-12)
    assert s.offset == pytest.approx(0.12, rel=1e-12)  # d: C ahead of the axle
    assert paper_scale() == s  # the paper's setting is written for Drishti
    trailer = load_robot_code("trailer")
    t = robot_scale(trailer, trailer.params)
    # 30 + 15 + 4 wheels (3, 3, 1.25, 1.25) kg, plus spin inertias over r²
    expected = 53.5 + 2 * 0.07 / 0.096**2 + 2 * 0.004 / 0.08**2
    assert (t.wheel_radius, t.track) == pytest.approx((0.096, 0.414), rel=1e-12)
    assert t.mass == pytest.approx(expected, rel=1e-12)


def test_inertial_keys_are_what_the_kinematics_ignores() -> None:
    drishti = load_robot_code("")
    assert inertial_keys(drishti, drishti.params) == ("m", "I", "K", "Iw")
    trailer = load_robot_code("trailer")
    keys = inertial_keys(trailer, trailer.params)
    assert set(keys) == {k for k in trailer.params if not k.startswith("radius_")}


def test_scaling_keeps_what_an_experiment_sets_and_scales_the_rest() -> None:
    half = RobotScale(0.048, 0.207, 0.06, DRISHTI_MASS / 4)  # half the size, 1/4 the heft
    exp = parse_experiment("[controller]\ntau_max = 7.0\n")
    out, lines = scaled_experiment(exp, half)
    assert out.controller.tau_max == 7.0  # set by the file
    assert any("tau_max = 7 (set by the experiment; kept)" in line for line in lines)
    torque = 0.25 * 0.5 * 0.5
    assert out.plant.coulomb == pytest.approx(0.3 * torque)
    assert out.plant.fixed_payload == pytest.approx(6.0 / 4)
    assert out.plant.extra_payload_x == pytest.approx(0.10 / 2)
    assert out.paths.circle_radius == pytest.approx(1.5 / 2)
    # wheel rates for Drishti's speeds times the size: the same rates on half-size wheels
    assert out.paths.lawnmower_fast == pytest.approx(3.0)
    assert out.controller.roc_max_rate == pytest.approx(8.0)
    assert out.controller.pi_ky == pytest.approx(8.0 * 4)  # 1/m²
    same, _ = scaled_experiment(Experiment(), paper_scale())
    assert same == Experiment()  # Drishti's own size changes nothing, bit for bit


@pytest.mark.parametrize("folder", ["", "trailer"])
def test_scaled_references_are_consistent_motions(folder: str) -> None:
    code = load_robot_code(folder)
    h = 0.01
    exp = scaled(code, h, 12.0, 30.0)
    for ref in (circle(code, code.params, exp), lawnmower(code, code.params, exp)):
        dq = (ref.q[2:] - ref.q[:-2]) / (2 * h)
        ddq = (ref.qdot[2:] - ref.qdot[:-2]) / (2 * h)
        assert np.max(np.abs(dq - ref.qdot[1:-1])) < 1e-3 * max(1.0, np.abs(ref.qdot).max())
        assert np.max(np.abs(ddq - ref.qddot[1:-1])) < 2e-2 * max(1.0, np.abs(ref.qddot).max())
    ref = circle(code, code.params, scaled(code, 0.05, 40.0, 1.0))
    late = ref.t > 15.0  # after the start-up ramp: on the circle of radius R1 · size
    centre = np.array([np.mean(ref.q[late, 0]), np.mean(ref.q[late, 1])])
    radius = np.linalg.norm(ref.q[late, :2] - centre, axis=1)
    assert np.ptp(radius) < 0.02 * radius.mean()
    size = robot_scale(code, code.params).track / paper_scale().track
    assert radius.mean() == pytest.approx(1.5 * size, rel=0.05)
    assert ref.scale == pytest.approx(1.5 * size, rel=1e-12)


def test_trailer_starts_with_a_straight_hitch() -> None:
    code = load_robot_code("trailer")
    assert body_yaws(code) == (code.robot.COORDINATES.index("theta_cart"),)
    ref = circle(code, code.params, scaled(code, 0.1, 1.0, 1.0))
    assert ref.q[0, 3] == ref.q[0, 2]


@pytest.mark.parametrize("velocity", ["sample-instant", "encoder-average"])
def test_odometry_follows_the_true_motion(velocity: str) -> None:
    """Fed the reference's own wheel angles, odometry reproduces the whole configuration
    (pose, hitch, passive wheels) to within the encoder resolution's effect."""
    code = load_robot_code("trailer")
    h = 0.02
    ref = lawnmower(code, code.params, scaled(code, h, 1.0, 20.0))
    exp = parse_experiment(f'[sensing]\nvelocity = "{velocity}"\nencoder_ppr = 100000\n'
                           f"[controller]\nh = {h}\n")
    odo = Sensors(code, ref.q[0], exp, code.params)
    act = list(code.actuated)
    worst_q, worst_rate = 0.0, 0.0
    for k in range(1, len(ref.t)):
        q, qdot = odo.measure(ref.q[k, act], ref.qdot[k, act], None)
        worst_q = max(worst_q, float(np.max(np.abs(q - ref.q[k]))))
        if velocity == "sample-instant":
            worst_rate = max(worst_rate, float(np.max(np.abs(qdot[act] - ref.qdot[k, act]))))
            worst_q = max(worst_q, float(np.max(np.abs(qdot - ref.qdot[k]))))
    assert worst_q < 2e-3, worst_q
    assert worst_rate == 0.0  # the driven wheels' rates are passed through


def _run_cli(tmp_path: Path, *args: str, experiment: str = "") -> tuple[int, Path]:
    exp = tmp_path / "short.toml"
    exp.write_text(SHORT + experiment)
    out = tmp_path / "out"
    code = main(["--experiment", str(exp), "--sensing", "sample-instant", "--out", str(out),
                 *args])
    return code, out


def test_lumped_robot_end_to_end(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The small robot, with a ±10 % uncertainty box (over the default ±30 % box the TDE
    condition fails for its TDC and TDROC, which the reproduction then refuses): the paper
    formulation is refused as predicted unstable on this robot (docs/CONTROLLERS.md), the
    minimal one runs and TDC tracks."""
    code, out = _run_cli(tmp_path, "--robot", str(SMALL), "--no-plots",
                         experiment="[controller]\nuncertainty = 0.1\n")
    assert code == 0
    printed = capsys.readouterr().out
    assert "controller.tau_max = 0.2179 (paper 40 x 0.005448, torque)" in printed
    report = (out / "REPORT.md").read_text()
    assert "robot 'small_robot'" in report and "τ_max = 0.2179 N m" in report
    rows = [line.split(",") for line in (out / "metrics.csv").read_text().splitlines()[1:]]
    assert len(rows) == 2 * len(load_robot_code("").runs())  # paths × (formulation, ctrl)
    assert all((r[12] == "refused") == (r[2] == "paper") for r in rows)
    assert "predicted unstable on this robot" in report
    # the grip verdict travels into the report (issue 45): the saturation column is
    # stability's torque, wind-up and grip verdict at the experiment's friction
    assert "| not checked |" not in report and "grip margin" in report
    minimal_tdc = [r for r in rows if r[2] == "minimal" and r[3] == "tdc"]
    assert all(float(r[4]) < 0.01 for r in minimal_tdc)  # metres


def test_trailer_end_to_end_with_plot(tmp_path: Path) -> None:
    """The trailer, with a ±20 % uncertainty box: over the default ±30 % its lumped
    coefficients fail the TDE condition for TDC and TDROC, which the reproduction refuses
    (a statement about robustness, tests/reproduction/test_reproduce_refusal.py)."""
    code, out = _run_cli(tmp_path, "--robot", str(TRAILER),
                         experiment="[controller]\nuncertainty = 0.2\n")
    assert code == 0
    rows = [line.split(",") for line in (out / "metrics.csv").read_text().splitlines()[1:]]
    assert len(rows) == 2 * len(load_robot_code("trailer").runs())
    assert all(r[2] == "minimal" for r in rows)
    assert all(r[11] == "" for r in rows)  # no run failed
    assert all(r[12] == "ok" for r in rows)  # and none left its path
    tdroc = [float(r[4]) for r in rows if r[3] == "tdroc"]
    assert max(tdroc) < 0.01
    assert (out / "tracking.png").stat().st_size > 10_000


def test_experiment_file_names_its_robot(tmp_path: Path) -> None:
    exp = tmp_path / "exp.toml"
    robot = tmp_path / "robots" / "small.toml"
    robot.parent.mkdir()
    shutil.copy(SMALL, robot)
    exp.write_text('robot = "robots/small.toml"\n' + SHORT)
    out = tmp_path / "out"
    assert main(["--experiment", str(exp), "--sensing", "sample-instant", "--no-plots",
                 "--out", str(out)]) == 0
    assert "robot 'small_robot'" in (out / "REPORT.md").read_text()


def test_bad_robot_files_are_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "nope.toml"
    assert _run_cli(tmp_path, "--robot", str(missing))[0] == 2
    assert "robot file not found" in capsys.readouterr().err
    other = tmp_path / "other.toml"
    other.write_text(TRAILER.read_text().replace('name = "trailer"', 'name = "other"'))
    assert _run_cli(tmp_path, "--robot", str(other))[0] == 2
    err = capsys.readouterr().err
    assert "no generated code for robot 'other'" in err and "wmr model --robot" in err
    assert "python -m codegen" not in err
    edited = tmp_path / "trailer.toml"
    edited.write_text(TRAILER.read_text().replace("mass = 15.0", "mass = 16.0"))
    assert _run_cli(tmp_path, "--robot", str(edited))[0] == 2
    assert "another version of this file" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing ran, nothing written


def test_generated_folder_outside_the_repository(tmp_path: Path) -> None:
    copy = tmp_path / "gen"
    shutil.copytree(GENERATED / "trailer", copy / "trailer")
    setup = resolve(TRAILER, copy)
    assert setup.code.folder == (copy / "trailer").resolve()
    assert setup.code.c_dir.is_dir()
    with pytest.raises(RobotSourceError, match="holds robot 'trailer'"):
        resolve(SMALL, copy / "trailer")  # a lumped file needs the paper robot's code


def test_stability_analyses_a_robot_of_bodies(capsys: pytest.CaptureFixture[str]) -> None:
    """The trailer (issue 29): every controller in its one formulation, with the scaling
    printed as `reproduce` prints it."""
    from runtime.commands import stability

    assert stability.main(["--robot", str(TRAILER), "--no-measure", "--no-delay",
                           "--no-saturation"]) == 0
    out = capsys.readouterr().out
    assert "robot 'trailer' from" in out and "robot scale:" in out
    assert all(f"| {c} | minimal |" in out for c in ("TDC", "TDROC", "ROC", "ASMC", "PI"))


def test_runtime_names_a_generated_folder_of_another_robot(tmp_path: Path) -> None:
    """generated/ regenerated for another robot: the paper robot's runtime stops with a
    sentence naming the robot it found and what to run, not an ImportError."""
    import subprocess
    import sys

    shutil.copytree(ROOT / "runtime", tmp_path / "runtime",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "generated").mkdir()
    (tmp_path / "generated" / "__init__.py").write_text("")
    shutil.copytree(GENERATED / "trailer" / "python", tmp_path / "generated" / "python",
                    ignore=shutil.ignore_patterns("__pycache__"))
    probe = ("import runtime.bindings.generated as g\n"
             "assert g.load_robot_code('').name == 'trailer'\n"
             "import runtime.reproduction.driver  # the one driver needs no paper "
             "robot\n"
             "from runtime.bindings.generated import wmr_model\n")
    result = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True,
                            text=True, check=False)
    assert result.returncode == 1
    assert "holds robot 'trailer' (prefix trailer_)" in result.stderr
    assert "make model" in result.stderr


def test_running_a_robot_needs_neither_sympy_nor_codegen() -> None:
    """The runtime reads generated code and robot files; SymPy and codegen are tooling."""
    import subprocess
    import sys

    probe = (
        "import sys\nfrom pathlib import Path\n"
        "import runtime.commands.reproduce, runtime.reproduction.driver\n"
        "from runtime.bindings.robots import resolve\n"
        f"resolve(Path({str(SMALL)!r})); resolve(Path({str(TRAILER)!r}))\n"
        "print(sorted(m for m in ('sympy', 'codegen', 'casadi') if m in sys.modules))\n"
    )
    result = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True,
                            text=True, check=True)
    assert result.stdout.strip() == "[]"


# SHA-256 of small_robot.toml below its two header lines: the file exactly as users tried it.
SMALL_AS_TRIED = "66fcb9b236fd2a48512f25974d52f5950573d6035e699580809349e8c5b26d66"


def test_small_robot_is_the_case_users_tried() -> None:
    """The case must keep working as given: a change to its numbers would test another robot."""
    as_tried = SMALL.read_text(encoding="utf-8").split("\n", 2)[2]
    assert hashlib.sha256(as_tried.encode("utf-8")).hexdigest() == SMALL_AS_TRIED


def test_output_folder_is_checked_before_any_run(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    a_file = tmp_path / "taken"
    a_file.write_text("")
    assert main(["--out", str(a_file)]) == 2  # the paper reproduction
    assert "exists and is not a folder" in capsys.readouterr().err
    assert main(["--robot", str(SMALL), "--out", str(a_file)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    # A folder that cannot be made, for every user (root writes into read-only folders):
    # one under a file.
    assert main(["--robot", str(SMALL), "--out", str(a_file / "sub")]) == 2
    assert "cannot write there (Not a directory)" in capsys.readouterr().err
    assert not (a_file / "sub").exists() and a_file.read_text() == ""


def test_a_tiny_sampling_time_is_refused_with_its_field() -> None:
    from runtime.experiment.settings import ExperimentFileError

    with pytest.raises(ExperimentFileError, match=re.escape("'controller.h' = 1e-09 s gives 3e")):
        parse_experiment("[controller]\nh = 1e-9\n")


def test_wheel_profile_derivative_over_a_long_path() -> None:
    """The tanh steps' derivative once overflowed (math.cosh) 710 ramps after a switch, so a
    circle of 150 s crashed the reproduction; it is the rates' derivative everywhere."""
    from runtime.sim.reference import RAMP, WheelProfile

    profile = WheelProfile((1.0, 4.0), ((2.0, 1.0), (-1.0, 0.5)))
    for t in (0.0, 1.0, 1.0 + RAMP, 3.9, 5.0, 300.0, 1e6):
        dt = 1e-6
        numeric = (profile.rates(t + dt) - profile.rates(t - dt)) / (2 * dt)
        assert np.all(np.isfinite(profile.accels(t)))
        np.testing.assert_allclose(profile.accels(t), numeric, rtol=1e-6, atol=1e-9)
