"""The physics audit (``modeling.audit``) on every kind of robot file: each finding has a
case that triggers it, errors refuse with one line naming the file, the field and the
value before any work (no derivation, no simulation, nothing written), warnings are
logged, carried (``Robot.warnings``, ``RobotDescription.warnings``) and written into
MODEL.md, and the shipped robots pass clean.

The importer's 3D checks (placeholders, triangle inequality, the spin axis, the ground
plane) are in tests/robot_files/test_import.py.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import pytest

from modeling import audit
from modeling.description import load_description, parse_description
from modeling.robot_file import (
    RobotFileError,
    load_robot,
    load_robot_model,
    shipped_robot_file,
    shipped_robot_files,
)
from modeling.robots.drishti.robot_file import parse_robot

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "tests" / "robots" / "small_robot.toml"

# The case users tried (tests/robots/small_robot.toml), in millimetres and in grams.
SMALL_MM = """name = "small_mm"
[lumped]
m = 2.0
I = 16654.0
K = 136.0
Iw = 54.0
r = 33.0
b = 160.0
d = 50.0
"""
SMALL_G = """name = "small_g"
[lumped]
m = 2000.0
I = 16.654
K = 136.0
Iw = 0.054
r = 0.033
b = 0.16
d = 0.05
"""
# docs/TUTORIAL.md's robot: Iw is the bare wheel's (the file says why).
TUTORIAL_PHYSICAL = (ROOT / "tests" / "robots" / "tutorial_physical.toml").read_text(
    encoding="utf-8")


def one_line(exc: pytest.ExceptionInfo[BaseException]) -> str:
    text = str(exc.value)
    assert "\n" not in text, text
    return text


def diff_drive(**fields: str) -> str:
    """A bodies-and-wheels differential drive (TurtleBot-sized), with fields replaced."""
    values = {"mass": "1.0", "yaw_inertia": "0.005", "radius": "0.033", "x": "0.0",
              "spin": "0.002", "wheel_mass": "0.03", "diameter": "8e-06", "motor": ""}
    values.update(fields)
    wheels = ""
    for name, y in (("right", -0.08), ("left", 0.08)):
        wheels += f"""
[[wheel]]
name = "{name}"
body = "base"
position = [{values['x']}, {y}]
radius = {values['radius']}
spin_inertia = {values['spin']}
diameter_inertia = {values['diameter']}
mass = {values['wheel_mass']}
driven = true
{values['motor']}
"""
    return f"""name = "dd"
[[body]]
name = "base"
mass = {values['mass']}
yaw_inertia = {values['yaw_inertia']}
com = [-0.02, 0.0]
{wheels}"""


# --------------------------------------------------------------------------- lumped files
def test_lengths_in_millimetres_are_refused_naming_the_field() -> None:
    with pytest.raises(RobotFileError) as exc:
        parse_robot(SMALL_MM, "small_mm.toml")
    assert one_line(exc) == (
        "small_mm.toml: field 'lumped.r' = 33.0 m: a wheel radius above 5 m is implausible "
        "for a wheeled robot; lengths in millimetres? Give lengths in metres")


def test_masses_in_grams_are_refused_by_density() -> None:
    with pytest.raises(RobotFileError) as exc:
        parse_robot(SMALL_G, "small_g.toml")
    text = one_line(exc)
    assert text.startswith("small_g.toml: field 'lumped.m' = 2000.0 kg in a robot of size "
                           "0.16 m is 488,281 kg/m^3")
    assert "denser than osmium" in text and "masses in grams" in text


def test_masses_in_tonnes_are_lighter_than_air() -> None:
    tonnes = SMALL.read_text().replace("m  = 2.0", "m  = 0.002").replace("K  = 0.136",
                                                                          "K  = 0.0")
    with pytest.raises(RobotFileError, match="lighter than air"):
        parse_robot(tonnes, "t.toml")


def test_a_total_mass_above_five_tonnes_is_grams() -> None:
    heavy = SMALL.read_text().replace("m  = 2.0", "m  = 6000.0").replace("b  = 0.16", "b  = 4.0")
    with pytest.raises(RobotFileError, match=r"field 'lumped.m' = 6000.0 kg: a total mass "
                       r"above 5,000 kg"):
        parse_robot(heavy, "heavy.toml")


def test_lumped_yaw_inertia_far_from_mass_and_size_is_a_warning() -> None:
    odd = SMALL.read_text().replace("I  = 0.016654", "I  = 20.0")
    robot = parse_robot(odd, "odd.toml")
    assert len(robot.warnings) == 1
    assert "field 'lumped.I' less K^2/m" in robot.warnings[0]
    assert "placeholder, or another unit" in robot.warnings[0]


def test_physical_file_without_the_motor_is_asked_for_it() -> None:
    robot = parse_robot(TUTORIAL_PHYSICAL, "my_robot.toml")
    (warning,) = robot.warnings
    assert warning.startswith("field 'physical.Iw' (each driven wheel): spin inertia 0.00015 "
                              "kg m^2 is what the wheel alone has")
    assert "add J_r N^2 to Iw" in warning
    # The size of the omission for the assumed gearmotor: 2.5e-3 / 1.5e-4.
    assert "J_r N^2 = 0.0025 kg m^2) the inertia left out is 16.7 × the one given" in warning


# A 6 kg chassis (0.3 m track) on 28 g wheels of r = 0.033 m, every number in kg and m.
CHASSIS = TUTORIAL_PHYSICAL.replace("m_P = 4.0", "m_P = 6.0").replace(
    "I_P = 0.05", "I_P = 0.08").replace("m_w = 0.3", "m_w = 0.028").replace(
    "Iw = 1.5e-4", "Iw = 2.07e-5").replace("Im = 8e-5", "Im = 1e-5").replace(
    "r = 0.05", "r = 0.033").replace("b = 0.25", "b = 0.3")


@pytest.mark.parametrize("field, typed, message", [
    # kg mm^2 typed as kg m^2: 1.48e5 × m L^2; in kg mm^2 it is 0.08 kg m^2, a chassis's.
    ("I_P = 0.08", "I_P = 80000.0", "field 'physical.I_P' = 80000.0 kg m^2 is 1.48e+05 × the "
     "most a body of m = 6 kg and size L = 0.3 m (m L^2) can have (0.54 kg m^2): no body has "
     "it; an inertia in kg mm^2 typed as kg m^2? (8e+04 kg mm^2 = 0.08 kg m^2"),
    # g cm^2 typed as kg m^2: 3.1e4 × what the wheel with any rotor can have.
    ("Iw = 2.07e-5", "Iw = 207.0", "field 'physical.Iw' = 207.0 kg m^2 is 3.14e+04 × the most "
     "a wheel of m = 0.028 kg and r = 0.033 m about its axle, with its motor's rotor, on a "
     "6.056 kg robot (M r^2) can have (0.006595 kg m^2): no body has it; an inertia in g cm^2 "
     "typed as kg m^2? (207 g cm^2 = 2.07e-05 kg m^2"),
    ("Im = 1e-5", "Im = 100.0", "field 'physical.Im' = 100.0 kg m^2 is 2.19e+06 × the most a "
     "wheel of m = 0.028 kg and r = 0.033 m about a diameter (1.5 m r^2) can have"),
])
def test_inertia_unit_slips_are_refused_naming_the_unit(field: str, typed: str,
                                                        message: str) -> None:
    assert parse_robot(CHASSIS, "chassis.toml").warnings is not None  # in kg m^2: accepted
    with pytest.raises(RobotFileError) as exc:
        parse_robot(CHASSIS.replace(field, typed), "chassis.toml")
    assert one_line(exc).startswith(f"chassis.toml: {message}"), one_line(exc)


def test_inertia_unit_slip_threshold_in_a_description() -> None:
    """1,000 × m L^2 is the line: below it a warning (a placeholder), at it an error. The
    1 kg base's size is 0.16 m (its wheels' spread): m L^2 = 0.0256 kg m^2."""
    below = parse_description(diff_drive(yaw_inertia="25.5"), "dd.toml")
    assert any("is 996 m L^2" in w for w in below.warnings)
    with pytest.raises(RobotFileError) as exc:
        parse_description(diff_drive(yaw_inertia="25.6"), "dd.toml")
    assert "field 'body[0].yaw_inertia' (body 'base') = 25.6 kg m^2 is 1e+03 × the most" in (
        one_line(exc))
    with pytest.raises(RobotFileError, match=r"an inertia in kg mm\^2 typed as kg m\^2"):
        parse_description(diff_drive(yaw_inertia="5000.0"), "dd.toml")


def test_shipped_and_test_robots_pass_clean() -> None:
    for path in [*shipped_robot_files(), SMALL, ROOT / "tests" / "robots" / "drishti_bodies.toml"]:
        if "[[body]]" in path.read_text():
            assert load_description(path).warnings == (), path
        else:
            assert load_robot(path).warnings == (), path
    assert load_robot(None).warnings == ()


def test_stability_refuses_a_millimetre_file_instead_of_crashing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before the audit: ``ValueError: math domain error`` from deep in the analysis."""
    from runtime.cli import main as wmr

    robot = tmp_path / "small_mm.toml"
    robot.write_text(SMALL_MM)
    assert wmr(["stability", "--robot", str(robot), "--no-measure"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert "field 'lumped.r' = 33.0 m" in err


def test_reproduce_refuses_a_gram_file_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before the audit: 88 m tracking errors reported as results."""
    from runtime.cli import main as wmr

    robot = tmp_path / "small_g.toml"
    robot.write_text(SMALL_G)
    out = tmp_path / "results"
    assert wmr(["reproduce", "--robot", str(robot), "--out", str(out), "--no-plots"]) == 2
    assert "denser than osmium" in capsys.readouterr().err
    assert not out.exists()


def test_warnings_are_logged_once_per_file(caplog: pytest.LogCaptureFixture) -> None:
    odd = SMALL.read_text().replace("I  = 0.016654", "I  = 21.0")
    with caplog.at_level(logging.WARNING, logger="wmr.audit"):
        parse_robot(odd, "logged.toml")
        parse_robot(odd, "logged.toml")
    lines = [r.getMessage() for r in caplog.records if r.name == "wmr.audit"]
    assert len(lines) == 1 and lines[0].startswith("warning: logged.toml: field 'lumped.I'")


def test_the_paper_robot_report_lists_the_warnings() -> None:
    from modeling.robots.drishti.report import model_report_context, render_model_report

    robot = load_robot(None)
    context = model_report_context(robot.lumped, "x", None, {}, ("field 'lumped.I': a finding",))
    section = render_model_report(context).split("## Physics audit of the robot file", 1)[1]
    assert "- field 'lumped.I': a finding" in section
    assert "## Physics audit" not in render_model_report({**context, "warnings": []})


# --------------------------------------------------------------------------- described files
def test_description_in_millimetres_is_refused(tmp_path: Path) -> None:
    with pytest.raises(RobotFileError) as exc:
        parse_description(diff_drive(radius="33.0"), "dd.toml")
    assert one_line(exc).startswith("dd.toml: field 'wheel[0].radius' = 33.0 m: a wheel "
                                    "radius above 5 m")
    with pytest.raises(RobotFileError, match=r"field 'wheel\[0\].position.y' = -80.0 m"):
        parse_description(diff_drive().replace("-0.08]", "-80.0]"), "dd.toml")


def test_description_in_grams_is_refused() -> None:
    with pytest.raises(RobotFileError, match=r"the total mass \(bodies and wheels\) = 1060.0 "
                       r"kg in a robot of size 0.16 m .* denser than osmium"):
        parse_description(diff_drive(mass="1000.0", wheel_mass="30.0"), "dd.toml")


def test_a_train_is_judged_by_its_bodies_not_by_the_cube_of_its_length() -> None:
    """The tractor with three trailers is 2.6 m long and 88.5 kg: over the cube of its
    length it would be lighter than foam (4.9 kg/m³); over its bodies' cubes it is not.
    The same train with its lengths a tenth (decimetres read as metres) is denser than
    osmium over its bodies' cubes."""
    path = shipped_robot_file("trailer3")
    assert load_description(path).warnings == ()

    def tenth(m: re.Match[str]) -> str:
        return f"{float(m.group(0)) / 10!r}"

    lengths = r"^((?:position|com|parent_point|child_point|radius) = )(.*?)(#|$)"
    shrunk = re.sub(lengths, lambda m: m.group(1) + re.sub(r"-?[0-9]+\.[0-9]+", tenth,
                                                            m.group(2)) + m.group(3),
                    path.read_text(), flags=re.M)
    with pytest.raises(RobotFileError, match=r"over its bodies' cubed sizes, denser than "
                       r"osmium"):
        parse_description(shrunk, "train.toml")


def test_yaw_inertia_placeholder_is_a_warning() -> None:
    desc = parse_description(diff_drive(yaw_inertia="10.0"), "dd.toml")
    (warning,) = [w for w in desc.warnings if "yaw_inertia" in w]
    assert warning.startswith("field 'body[0].yaw_inertia' (body 'base') = 10 kg m^2 is 391 "
                              "m L^2")


def test_wheel_inertias_no_wheel_can_have_are_warnings() -> None:
    desc = parse_description(diff_drive(diameter="0.005", spin="1e-9",
                                        motor="rotor_inertia = 0.0\ngear_ratio = 1.0"), "dd.toml")
    text = "\n".join(desc.warnings)
    assert "field 'wheel[0].diameter_inertia' (wheel 'right') = 0.005 kg m^2" in text
    assert "no wheel of that mass and radius has more than about 1.5 m r^2" in text
    assert "field 'wheel[1].spin_inertia' (wheel 'left') = 1e-09 kg m^2" in text


def test_driven_wheel_without_its_motor_is_asked_for_it_and_the_motor_is_folded_in() -> None:
    bare = parse_description(diff_drive(spin="1.6e-05"), "dd.toml")
    rotor = [w for w in bare.warnings if "without its motor" in w]
    assert len(rotor) == 2 and rotor[0].startswith("wheel[0] (driven wheel 'right'): spin "
                                                   "inertia 1.6e-05 kg m^2")
    assert "the inertia left out is 156 × the one given" in rotor[0]
    given = parse_description(diff_drive(spin="1.6e-05", motor="rotor_inertia = 1e-06\n"
                                         "gear_ratio = 50.0"), "dd.toml")
    assert given.warnings == ()
    assert given.wheels[0].spin_inertia == pytest.approx(1.6e-05 + 1e-06 * 50.0**2)


@pytest.mark.parametrize("motor, message", [
    ("rotor_inertia = 1e-06", "field 'wheel[0].rotor_inertia' needs 'wheel[0].gear_ratio' too"),
    ("rotor_inertia = 1e-06\ngear_ratio = 0.0", "field 'wheel[0].gear_ratio' must be positive"),
])
def test_motor_fields_are_checked(motor: str, message: str) -> None:
    with pytest.raises(RobotFileError, match=re.escape(message)):
        parse_description(diff_drive(motor=motor), "dd.toml")
    passive = diff_drive(motor="rotor_inertia = 1e-06\ngear_ratio = 50.0").replace(
        "driven = true", "driven = false", 1)
    with pytest.raises(RobotFileError, match="wheel 0 is not driven"):
        parse_description(passive, "dd.toml")


SKID_STEER = """name = "skid"
[[body]]
name = "base"
mass = 46.0
yaw_inertia = 2.03
com = [0.0, 0.0]
""" + "".join(f"""
[[wheel]]
name = "{n}"
body = "base"
position = [{x}, {y}]
radius = 0.1651
spin_inertia = 0.04411
diameter_inertia = 0.02467
mass = 2.637
driven = {'true' if x > 0 else 'false'}
""" for n, x, y in (("fl", 0.256, 0.2854), ("fr", 0.256, -0.2854), ("rl", -0.256, 0.2854),
                    ("rr", -0.256, -0.2854)))


def test_skid_steer_is_refused_before_any_derivation(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import modeling.robot_model

    def never(*args: object) -> None:
        raise AssertionError("derived a robot the audit refuses")

    monkeypatch.setattr(modeling.robot_model, "described_model", never)
    path = tmp_path / "skid.toml"
    path.write_text(SKID_STEER)
    with pytest.raises(RobotFileError) as exc:
        load_robot_model(path)
    text = one_line(exc)
    assert text.startswith(f"{path}: body 'base' (body[0]) has fixed wheels on 2 axles "
                           "('fl' (x = 0.256 m), 'fr' (x = 0.256 m), 'rl' (x = -0.256 m), "
                           "'rr' (x = -0.256 m)): a skid-steer or other over-constrained "
                           "layout is not supported")
    assert "force the body's yaw rate to zero" in text


def test_caster_without_trail_is_refused() -> None:
    caster = diff_drive() + """
[[body]]
name = "fork"
mass = 0.01
yaw_inertia = 4e-07
com = [0.0, 0.0]

[[joint]]
parent = "base"
child = "fork"
parent_point = [-0.08, 0.0]
child_point = [0.0, 0.0]

[[wheel]]
name = "caster"
body = "fork"
position = [0.0, 0.0]
radius = 0.0125
spin_inertia = 7.8e-07
diameter_inertia = 4.7e-07
mass = 0.01
driven = false
"""
    with pytest.raises(RobotFileError, match=r"joint\[0\] \(child 'fork'\): the wheels of "
                       r"'fork' sit on its hitch point .* \(a caster without trail\)"):
        parse_description(caster, "caster.toml")
    with_trail = caster.replace("position = [0.0, 0.0]", "position = [-0.015, 0.0]")
    assert parse_description(with_trail, "caster.toml").bodies[1].name == "fork"


def test_import_findings_in_a_file_become_its_warnings() -> None:
    text = diff_drive(spin="0.002").replace(
        'name = "dd"', 'name = "dd"\n[import]\nsource = "dd.urdf"\nfindings = ["link x: odd"]')
    desc = parse_description(text, "dd.toml")
    assert desc.warnings == ("import of dd.urdf: link x: odd",)
    with pytest.raises(RobotFileError, match=re.escape("field 'import.findings' must be an "
                                                        "array of strings")):
        parse_description(text.replace('["link x: odd"]', "3"), "dd.toml")


def test_thresholds_are_what_the_docstring_says() -> None:
    doc = audit.__doc__ or ""
    for number in ("5 m", "20 m", "5,000 kg", "22,600 kg/m³", "[0.01, 100] m L²", "1.5 m r²",
                   "J_r = 1e-6 kg m²", "N = 50", "2.5e-3 kg m²"):
        assert number in doc, number
    assert (audit.RADIUS_MAX, audit.LENGTH_MAX, audit.MASS_MAX, audit.DENSITY_MAX) == (
        5.0, 20.0, 5000.0, 22_600.0)
    assert audit.YAW_RATIO == (0.01, 100.0)
    assert audit.UNIT_SLIP == 1e3 and "1,000 ×" in doc
    assert dict(audit.INERTIA_UNITS)["kg mm^2"] == 1e6 and "1e6 kg mm²" in doc
    assert dict(audit.INERTIA_UNITS)["g cm^2"] == 1e7 and "1e7 g cm²" in doc
    reflected = audit.TYPICAL_ROTOR_INERTIA * audit.TYPICAL_GEAR_RATIO**2
    assert reflected == pytest.approx(2.5e-3)


def test_a_wheel_mass_in_grams_is_named() -> None:
    """The 28 g wheel typed as m_w = 28: its Iw = 2.07e-5 kg m^2 is 0.0014 × the disc of a
    28 kg wheel, 1.4 × that of a 28 g one: the warning names grams."""
    robot = parse_robot(CHASSIS.replace("m_w = 0.028", "m_w = 28.0"), "grams.toml")
    (spin,) = [w for w in robot.warnings if w.startswith("field 'physical.Iw' = ")]
    assert spin.endswith("a placeholder, or another unit; or the wheel's mass in grams: m = "
                         "0.028 kg gives 1.4 × a disc")
    placeholder = parse_robot(CHASSIS.replace("Iw = 2.07e-5", "Iw = 1e-9"), "p.toml")
    assert not any("in grams" in w for w in placeholder.warnings)
