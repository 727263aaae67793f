"""``wmr import``: URDF and MJCF in, a bodies-and-wheels robot file out.

* The test robots of tests/robots/imports/ (written for these tests from published
  figures; their sources are in each file's header and in that folder's README.md): the
  URDF and the MJCF of each import to the same robot; the tractor-trailer's composed
  masses, centres of mass and inertias (a chassis and a rotated battery merged, the
  motors' J_r N² added) are the shipped trailer.toml's numbers; the skid-steer is refused
  with the audit's sentence and nothing is written.
* What real public files get wrong, reproduced with their numbers: placeholder inertias
  (ROBOTIS TurtleBot3 Burger, Yujin Kobuki), the spin inertia on the wrong axis (Clearpath
  Husky: a naive import is 44 % low), a wheel tensor no wheel can have (AgileX Scout), a
  transmission naming a joint that does not exist (Clearpath Jackal).
* Bad files refuse with one line naming the file, the element and the value: xacro that
  does not expand, malformed XML, missing or non-physical inertials, a wheel off the ground, a wheel
  cylinder across its joint; an existing output is left as it was.

The pipeline beyond the import (``wmr model``, ``wmr reproduce``) is
tests/robot_files/test_import_pipeline.py.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from modeling.description import RobotDescription, load_description, packaged_description
from modeling.importers import Options, import_robot
from modeling.robot_io import RobotFileError
from runtime.cli import main as wmr

IMPORTS = Path(__file__).resolve().parents[1] / "robots" / "imports"
ROBOTS = ("turtlebot3_like", "kobuki_like", "tractor_trailer")


def numbers(desc: RobotDescription) -> dict[str, float]:
    """Every number of a description, keyed by element name and field."""
    out: dict[str, float] = {}
    for b in desc.bodies:
        out.update({f"{b.name}.mass": float(b.mass), f"{b.name}.yaw_inertia":
                    float(b.yaw_inertia), f"{b.name}.com.x": float(b.com[0]),
                    f"{b.name}.com.y": float(b.com[1])})
    for j in desc.joints:
        for key in ("parent_point", "child_point"):
            for axis, v in zip("xy", getattr(j, key), strict=True):
                out[f"{j.child}.{key}.{axis}"] = float(v)
    for w in desc.wheels:
        for key in ("radius", "spin_inertia", "diameter_inertia", "mass"):
            out[f"{w.name}.{key}"] = float(getattr(w, key))
        out[f"{w.name}.x"], out[f"{w.name}.y"] = (float(v) for v in w.position)
        out[f"{w.name}.driven"] = float(w.driven)
    return out


def flat(text: str) -> str:
    """A robot file's text with its wrapped comment lines joined."""
    return " ".join(line.lstrip("# ") for line in text.splitlines())


def assert_same(a: dict[str, float], b: dict[str, float], rel: float = 1e-9) -> None:
    assert a.keys() == b.keys()
    for k in a:
        assert a[k] == pytest.approx(b[k], rel=rel, abs=1e-12), k


def run(tmp_path: Path, source: Path | str, *args: str, text: str | None = None,
        name: str = "robot.urdf") -> tuple[int, Path]:
    if text is not None:
        source = tmp_path / name
        Path(source).write_text(text)
    out = tmp_path / "robot.toml"
    return wmr(["import", str(source), "--out", str(out), *args]), out


# --------------------------------------------------------------------------- test robots
@pytest.mark.parametrize("robot", ROBOTS)
def test_urdf_and_mjcf_import_to_the_same_robot(robot: str, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    extra = ["--rotor-inertia", "1.405e-4"] if robot == "tractor_trailer" else []
    results = {}
    for fmt in ("urdf", "xml"):
        (tmp_path / fmt).mkdir()
        code, out = run(tmp_path / fmt, IMPORTS / f"{robot}.{fmt}", *extra)
        assert code == 0, capsys.readouterr().err
        results[fmt] = load_description(out)
        text = out.read_text()
        assert text.startswith("# Imported by `wmr import` (wmr-toolchain ")
        assert "# - planar projection: each body keeps its mass" in text
        # A comment on every value line.
        values = [line for line in text.split("\n[[body]]", 1)[1].splitlines()
                  if "=" in line and not line.startswith("#")]
        assert all("#" in line for line in values if not line.startswith(
            ("kind =", "parent =", "child =", "body ="))), values
    urdf, mjcf = (numbers(results[f]) for f in ("urdf", "xml"))
    # The TurtleBot3-like URDF keeps ROBOTIS' rpy="-1.57 0 0" (a 0.046° tilt of the wheel
    # frame), which moves the wheels' diameter inertia by 4e-7 relative.
    assert_same(urdf, mjcf, rel=1e-6 if robot == "turtlebot3_like" else 1e-9)


def test_tractor_trailer_composes_to_the_shipped_trailer(tmp_path: Path) -> None:
    """Chassis 24 kg + battery 6 kg (rotated rpy = (π/2, 0, π/2), so its local y moment is
    the yaw one) → 30 kg, CoM 0.05 m ahead of the axle, I_zz = 0.97125 + 24·0.0625² + 0.06 +
    6·0.25² = 1.5 kg m²; wheels 0.0138 + J_r N² = 1.405e-4 · 20² = 0.07 kg m²: the numbers of
    modeling/robots/trailer/trailer.toml, whose derivation the suite already checks."""
    imported = import_robot(IMPORTS / "tractor_trailer.urdf", Options(rotor_inertia=1.405e-4))
    shipped = packaged_description("trailer")
    rename = {"tractor": "tractor", "cart": "cart", "wheel_right": "right",
              "wheel_left": "left", "cart_right": "cart_right", "cart_left": "cart_left"}
    got = {}
    for key, v in numbers(imported.description).items():
        owner, field = key.split(".", 1)
        got[f"{rename[owner]}.{field}"] = v
    want = numbers(shipped)
    want["right.diameter_inertia"] = want["left.diameter_inertia"] = 0.007
    assert_same(got, want)
    assert [w.name for w in imported.description.wheels] == list(rename)[2:]
    assert imported.description.warnings == ()
    text = flat(imported.text)
    assert "gear_ratio = 20.0" in text and "rotor_inertia = 0.0001405" in text
    assert "joint): tractor: tractor_link, battery_link" in text
    assert "massless frames dropped: base_footprint, imu_link, lidar_link" in text
    assert 'gazebo <sensor name="lidar" type="ray"> on link' in text
    assert "positive joint rotation rolls backward: θ = −(joint angle)" in text  # the right


def test_mjcf_armature_and_gear_are_the_motor(tmp_path: Path) -> None:
    imported = import_robot(IMPORTS / "tractor_trailer.xml")
    right = imported.description.wheels[0]
    assert right.spin_inertia == pytest.approx(0.07)
    assert "J_r = armature / N^2 (armature = J_r N^2 = 0.0562 kg m^2)" in imported.text


def test_caster_is_a_body_on_a_revolute_joint() -> None:
    imported = import_robot(IMPORTS / "turtlebot3_like.urdf")
    d = imported.description
    assert [b.name for b in d.bodies] == ["base", "caster_fork"]
    (j,) = d.joints
    assert (j.parent, j.child, j.parent_point, j.child_point) == (
        "base", "caster_fork", (-0.081, 0.0), (0.0, 0.0))
    caster = d.wheels[-1]
    assert (caster.name, caster.body, caster.position, caster.driven) == (
        "caster_wheel", "caster_fork", (-0.015, 0.0), False)
    assert "a caster swivel" in imported.text
    assert [w.name for w in d.wheels if w.driven] == ["wheel_left", "wheel_right"]
    assert '<plugin filename="libgazebo_ros_diff_drive.so">' in imported.text


def test_fixed_casters_are_supports_and_sensors_are_dropped() -> None:
    text = flat(import_robot(IMPORTS / "kobuki_like.urdf").text)
    assert ("supports on the ground without a wheel model (no constraint: treated as "
            "frictionless, e.g. ball casters or sliders): link 'caster_front_link' "
            "<collision> (cylinder), link 'caster_back_link' <collision> (cylinder)") in text
    assert "massless frames dropped: base_footprint, cliff_sensor_left_link" in text
    mjcf = import_robot(IMPORTS / "kobuki_like.xml").text
    assert "MuJoCo's inertiafromgeom" in mjcf  # the base's inertia from its geoms
    assert '<sensor><rangefinder name="cliff_left"' in flat(mjcf)


@pytest.mark.parametrize("fmt", ["urdf", "xml"])
def test_skid_steer_is_refused_and_nothing_is_written(
    fmt: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out = run(tmp_path, IMPORTS / f"skid_steer.{fmt}")
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"error: {IMPORTS / f'skid_steer.{fmt}'}: body 'base' (body[0]) has fixed wheels " \
           "on 2 axles" in err
    assert ("a skid-steer or other over-constrained layout is not supported: under pure "
            "rolling") in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_a_refused_import_leaves_the_existing_file(tmp_path: Path) -> None:
    out = tmp_path / "robot.toml"
    out.write_text("mine\n")
    assert wmr(["import", str(IMPORTS / "skid_steer.urdf"), "--out", str(out)]) == 2
    assert out.read_text() == "mine\n" and sorted(tmp_path.iterdir()) == [out]


def test_driven_flag_and_its_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out = run(tmp_path, IMPORTS / "kobuki_like.urdf", "--driven",
                    "wheel_left_link,wheel_right")
    assert code == 0
    assert [w.name for w in load_description(out).wheels] == ["wheel_left", "wheel_right"]
    assert "--driven on the command line" in out.read_text()
    out.unlink()
    code, _ = run(tmp_path, IMPORTS / "kobuki_like.urdf", "--driven", "castor")
    assert code == 2 and not out.exists()
    assert "--driven castor: no wheel, wheel joint or wheel link of that name (wheels: " \
           "wheel_left, wheel_right)" in capsys.readouterr().err
    code, _ = run(tmp_path, IMPORTS / "kobuki_like.urdf", "--rotor-inertia", "1e-6")
    assert code == 2 and "--rotor-inertia needs a gear ratio" in capsys.readouterr().err
    code, out = run(tmp_path, IMPORTS / "kobuki_like.urdf", "--rotor-inertia", "1e-6",
                    "--gear-ratio", "49.6")
    assert code == 0
    assert load_description(out).warnings == ()
    assert wmr(["import", str(IMPORTS / "kobuki_like.urdf"), "--out", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err


# --------------------------------------------------------------------------- real files
def urdf(*parts: str, name: str = "r") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n' + "\n".join(parts) + "\n</robot>\n"


def link(name: str, mass: float | None = None, inertia: str = "", collision: str = "",
         origin: str = "") -> str:
    inertial = "" if mass is None else (
        f'<inertial><origin xyz="{origin or "0 0 0"}"/><mass value="{mass}"/>'
        f"<inertia {inertia}/></inertial>")
    return f'<link name="{name}">{inertial}{collision}</link>'


def joint(name: str, kind: str, parent: str, child: str, xyz: str = "0 0 0", rpy: str = "0 0 0",
          axis: str = "0 0 1") -> str:
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/></joint>')


def cylinder(radius: float, length: float, rpy: str = "0 0 0", xyz: str = "0 0 0") -> str:
    return (f'<collision><origin xyz="{xyz}" rpy="{rpy}"/><geometry><cylinder radius="{radius}" '
            f'length="{length}"/></geometry></collision>')


def box(size: str, xyz: str = "0 0 0") -> str:
    return f'<collision><origin xyz="{xyz}"/><geometry><box size="{size}"/></geometry></collision>'


def diag(xx: float, yy: float, zz: float) -> str:
    return f'ixx="{xx}" ixy="0" ixz="0" iyy="{yy}" iyz="0" izz="{zz}"'


def drive(*joints: str) -> str:
    return "".join(f'<transmission name="t_{j}"><joint name="{j}"/></transmission>'
                   for j in joints)


def burger_wheels(parent: str = "base_link", z: float = 0.023) -> list[str]:
    """The TurtleBot3 Burger's wheels as in ROBOTIS' turtlebot3_burger.urdf."""
    tensor = ('ixx="1.1175580e-05" ixy="-4.2369783e-11" ixz="-5.9381719e-09" '
              'iyy="1.1192413e-05" iyz="-1.4400107e-11" izz="2.0712558e-05"')
    out = []
    for side, y in (("left", 0.08), ("right", -0.08)):
        out += [joint(f"wheel_{side}_joint", "continuous", parent, f"wheel_{side}_link",
                      f"0 {y} {z}", "-1.57 0 0"),
                link(f"wheel_{side}_link", 2.8498940e-02, tensor, cylinder(0.033, 0.018))]
    return out


BURGER_BASE = [
    link("base_footprint"),
    joint("base_joint", "fixed", "base_footprint", "base_link", "0 0 0.010"),
    link("base_link", 8.2573504e-01,
         'ixx="2.2124416e-03" ixy="-1.2294101e-05" ixz="3.4938785e-05" iyy="2.1193702e-03" '
         'iyz="-5.0120904e-06" izz="2.0064271e-03"', box("0.140 0.140 0.143", "-0.032 0 0.070")),
    drive("wheel_left_joint", "wheel_right_joint"),
]


def test_turtlebot3_burger_placeholders_nearly_double_its_yaw_inertia(tmp_path: Path) -> None:
    """ROBOTIS' turtlebot3_burger.urdf: the LDS (base_scan, 114 g) and the slider
    (caster_back_link, 5 g) carry ixx = iyy = izz = 0.001 kg m²: a 5 g part 30 × 20 mm with
    the yaw inertia of a 0.45 m radius of gyration. Merged into the base, the two
    placeholders are half of its yaw inertia: 0.002 of 0.0041 kg m² (base_link's own tensor
    has 0.0020)."""
    placeholder = diag(0.001, 0.001, 0.001)
    text = urdf(*BURGER_BASE, *burger_wheels(),
                joint("caster_back_joint", "fixed", "base_link", "caster_back_link",
                      "-0.081 0 -0.004", "-1.57 0 0"),
                link("caster_back_link", 0.005, placeholder, box("0.030 0.009 0.020",
                                                                 "0 0.001 0")),
                joint("scan_joint", "fixed", "base_link", "base_scan", "-0.032 0 0.172"),
                link("base_scan", 0.114, placeholder, cylinder(0.055, 0.0315,
                                                               xyz="0.015 0 -0.0065")),
                name="turtlebot3_burger")
    (tmp_path / "burger.urdf").write_text(text)
    imported = import_robot(tmp_path / "burger.urdf")
    base = imported.description.bodies[0]
    findings = imported.robot.findings
    for part in ("caster_back_link", "base_scan"):
        assert any(f.startswith(f"link '{part}': ixx = iyy = izz = 0.001 kg m^2 with no "
                                "products of inertia") for f in findings), part
    caster = next(f for f in findings if f.startswith("link 'caster_back_link': a principal"))
    assert "can have more than m R^2 = 1.917e-06 kg m^2" in caster  # 522 × less than 0.001
    shares = [f for f in findings if "contributes" in f]
    assert len(shares) == 2
    assert base.yaw_inertia == pytest.approx(4.14e-3, rel=0.01)
    placeholder_part = 0.002 / float(base.yaw_inertia)
    assert 0.45 < placeholder_part < 0.55
    assert any("ball casters or sliders): link 'caster_back_link'" in line
               for line in [" ".join(imported.text.split())])


def test_kobuki_placeholders_are_found(tmp_path: Path) -> None:
    """Yujin's kobuki.urdf.xacro (expanded): the 2.4 kg base has 1e-4 kg m² on each axis
    (a uniform 0.176 m radius cylinder of that mass has 0.029-0.037: the file's tensor has
    0.3 % of their sum) and each
    10 g wheel 0.001 kg m² (74 × what any 10 g inside its cylinder can have)."""
    wheel_tensor = diag(0.001, 0.001, 0.001)
    parts = [link("base_footprint"),
             joint("base_joint", "fixed", "base_footprint", "base_link", "0 0 0.0102"),
             link("base_link", 2.4, diag(0.0001, 0.0001, 0.0001),
                  cylinder(0.176, 0.10938, xyz="0 0 0.05949"))]
    for side, y, r in (("left", 0.115, 0.0352), ("right", -0.115, 0.0350)):
        parts += [joint(f"wheel_{side}_joint", "continuous", "base_link", f"wheel_{side}_link",
                        f"0 {y} 0.025", f"{-math.pi / 2} 0 0"),
                  link(f"wheel_{side}_link", 0.01, wheel_tensor, cylinder(r, 0.0206))]
    parts.append(drive("wheel_left_joint", "wheel_right_joint"))
    (tmp_path / "kobuki.urdf").write_text(urdf(*parts, name="kobuki"))
    imported = import_robot(tmp_path / "kobuki.urdf")
    findings = imported.robot.findings
    base = next(f for f in findings if f.startswith("link 'base_link': inertia tensor"))
    assert "is 0.00312 × what a uniform 2.4 kg body filling its collision cylinder has" in base
    wheel = next(f for f in findings if f.startswith("link 'wheel_left_link': a principal"))
    assert "no 0.01 kg inside its collision cylinder" in wheel
    # The audit of the written file: a 10 g wheel cannot have 0.001 about a diameter.
    assert any("field 'wheel[0].diameter_inertia'" in w and "no wheel of that mass and radius"
               in w for w in imported.description.warnings)


HUSKY_WHEEL = diag(0.02467, 0.02467, 0.04411)  # husky_description/urdf/wheel.urdf.xacro


def husky_like(tensor: str = HUSKY_WHEEL) -> str:
    """Two Husky wheels (joint axis y, cylinder turned onto y, the file's tensor) on a base:
    a differential drive, so that the audit judges the wheels, not the layout."""
    parts = [link("base_link", 46.034, diag(0.6022, 1.7386, 2.0296), box("0.9874 0.5709 0.2")),
             link("base_footprint"),
             joint("base_footprint_joint", "fixed", "base_link", "base_footprint",
                   "0 0 -0.13228")]
    for side, y in (("left", 0.2854), ("right", -0.2854)):
        parts += [joint(f"{side}_wheel", "continuous", "base_link", f"{side}_wheel_link",
                        f"0 {y} 0.03282", axis="0 1 0"),
                  link(f"{side}_wheel_link", 2.637, tensor,
                       cylinder(0.1651, 0.1143, rpy=f"{math.pi / 2} 0 0"))]
    parts.append(drive("left_wheel", "right_wheel"))
    return urdf(*parts, name="husky_like")


def test_husky_spin_inertia_on_the_wrong_axis(tmp_path: Path) -> None:
    """Clearpath's wheel.urdf.xacro: the joint axis is y and the collision cylinder is turned
    onto y, but the tensor's symmetric moment 0.04411 is about z: a naive import (about the
    axle) reads 0.02467, 44 % low. The importer takes the symmetric moment."""
    (tmp_path / "husky.urdf").write_text(husky_like())
    imported = import_robot(tmp_path / "husky.urdf")
    wheel = imported.description.wheels[0]
    assert wheel.spin_inertia == pytest.approx(0.04411)
    assert wheel.diameter_inertia == pytest.approx(0.02467)
    finding = next(f for f in imported.robot.findings if "wrong axis" in f)
    assert finding.startswith("wheel 'left_wheel' (joint 'left_wheel', link 'left_wheel_link'): "
                              "the spin inertia is on the wrong axis: the tensor's symmetric "
                              "moment 0.04411 kg m^2 is about the link's z axis")
    assert "about which the tensor gives 0.02467 kg m^2: a naive import is 44 % low" in finding
    # The same wheel with the moment on its axle: no finding, the same numbers.
    (tmp_path / "fixed.urdf").write_text(husky_like(diag(0.02467, 0.04411, 0.02467)))
    fixed = import_robot(tmp_path / "fixed.urdf")
    assert not any("wrong axis" in f for f in fixed.robot.findings)
    assert fixed.description.wheels[0].spin_inertia == pytest.approx(0.04411)


def test_scout_wheel_tensor_no_wheel_can_have(tmp_path: Path) -> None:
    """AgileX's scout_wheel_type1.xacro: a 3 kg wheel of radius 0.1646 m with 0.7171 kg m²
    about its diameters (a uniform wheel of that size has 0.024) and 0.1361 about its axle
    (more than m r² = 0.081: not even a ring)."""
    (tmp_path / "scout.urdf").write_text(husky_like(diag(0.7171, 0.1361, 0.7171)).replace(
        'radius="0.1651" length="0.1143"', 'radius="0.16459" length="0.11653"').replace(
        'value="2.637"', 'value="3"'))
    imported = import_robot(tmp_path / "scout.urdf")
    finding = next(f for f in imported.robot.findings if f.startswith("link 'left_wheel_link'"))
    assert "a principal moment of 0.7171 kg m^2, but no 3 kg inside its collision cylinder" \
        in finding
    assert any("field 'wheel[0].diameter_inertia' (wheel 'left_wheel') = 0.7171 kg m^2 is 8.82 "
               "m r^2" in w for w in imported.description.warnings)


def test_jackal_transmission_naming_a_missing_joint(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """Clearpath's jackal.urdf.xacro: the transmissions name joints '<prefix>_wheel' but the
    joints are '<prefix>_wheel_joint'. Ignored with a note; no driven wheel is left, so the
    import asks for --driven."""
    text = husky_like().replace('<joint name="left_wheel"/>', '<joint name="left_wheel_x"/>') \
        .replace('<joint name="right_wheel"/>', '<joint name="right_wheel_x"/>')
    code, out = run(tmp_path, "", text=text)
    assert code == 2 and not out.exists()
    assert ("no driven wheel: the file has no <transmission>, <ros2_control> joint, drive "
            "plugin or actuator on a wheel joint; name them with --driven NAME,NAME (wheels: "
            "left_wheel, right_wheel)") in capsys.readouterr().err
    code, out = run(tmp_path, tmp_path / "robot.urdf", "--driven", "left_wheel,right_wheel")
    assert code == 0
    assert "names joint 'left_wheel_x', which does not exist: ignored" in flat(out.read_text())


# --------------------------------------------------------------------------- bad files
def simple(wheel_z: float = 0.033, tensor: str = diag(1.1e-5, 1.1e-5, 2.1e-5),
           base_tensor: str = diag(0.002, 0.002, 0.002), extra: str = "",
           wheel_rpy: str = "-1.5707963267948966 0 0", axis: str = "0 0 1") -> str:
    parts = [link("base_footprint"),
             joint("base_joint", "fixed", "base_footprint", "base_link", "0 0 0.01"),
             link("base_link", 1.0, base_tensor, box("0.14 0.14 0.14", "0 0 0.07"))]
    for side, y in (("left", 0.08), ("right", -0.08)):
        parts += [joint(f"{side}_joint", "continuous", "base_link", f"{side}_link",
                        f"0 {y} {wheel_z - 0.01}", wheel_rpy, axis),
                  link(f"{side}_link", 0.03, tensor, cylinder(0.033, 0.018))]
    parts += [drive("left_joint", "right_joint"), extra]
    return urdf(*parts)


@pytest.mark.parametrize("name, text, message", [
    ("r.urdf", simple().replace('value="1.0"', 'value="${base_mass}"'),
     "r.urdf: xacro could not expand it: name 'base_mass' is not defined"),
    ("r.urdf", simple()[:-20], "r.urdf: not well-formed XML: "),
    ("r.urdf", simple().replace('<mass value="1.0"/>', ""),
     "r.urdf: link 'base_link' <inertial>: missing <mass value=...>"),
    ("r.urdf", simple().replace('<mass value="1.0"/>', '<mass value="1,0"/>'),
     "r.urdf: link 'base_link' <inertial> <mass>: attribute value=\"1,0\" must be 1 finite "
     "number(s)"),
    ("r.urdf", simple(base_tensor=diag(0.1, 0.1, 0.3)),
     "r.urdf: link 'base_link' <inertia>: principal moments (0.1, 0.1, 0.3) kg m^2 break the "
     "triangle inequality (0.3 > 0.1 + 0.1): no body has this inertia"),
    ("r.urdf", simple(base_tensor=diag(0.1, -0.1, 0.1)),
     "r.urdf: link 'base_link' <inertia>: principal moments (-0.1, 0.1, 0.1) kg m^2 include a "
     "negative one"),
    ("r.urdf", simple(wheel_z=0.06), "r.urdf: wheel 'left' (joint 'left_joint', link "
     "'left_link'): its lowest point is 27.0 mm above the ground plane (z = 0 m, the massless "
     "frame link 'base_footprint')"),
    ("r.urdf", simple(wheel_rpy="0 0 0", axis="0 1 0"), "r.urdf: joint 'left_joint': its axis "
     "(0, 1, 0) (in link 'left_link'; (0, 1, 0) in the world) is at 90.0° to the axis of link "
     "'left_link' <collision>: a wheel spins about its cylinder's axis"),
    ("r.urdf", simple().replace('<parent link="base_link"/><child link="left_link"/>',
                                '<parent link="susp"/><child link="left_link"/>').replace(
        "</robot>", link("susp", 0.1, diag(1e-5, 1e-5, 1e-5)) + joint(
            "suspension", "prismatic", "base_link", "susp") + "</robot>"),
     "r.urdf: joint 'suspension' (prismatic, axis (0, 0, 1) in the world) carries wheels: "
     "only revolute joints about the vertical (hitches, caster swivels) may"),
    ("r.urdf", simple().replace('<cylinder radius="0.033" length="0.018"/>',
                                '<mesh filename="wheel.stl"/>', 1),
     "r.urdf: joint 'left_joint' (continuous, horizontal axis, driven): its child link "
     "'left_link' has no collision cylinder, so the wheel's radius is unknown"),
    ("r.xml", "<mujoco><include file='x.xml'/></mujoco>",
     "r.xml: <include file=\"x.xml\"> is not supported by this importer"),
    ("r.xml", "<mujoco><worldbody><body name='b'><freejoint/><geom type='mesh' mesh='m'/>"
     "</body></worldbody></mujoco>", "r.xml: geom 1 of body 'b': a mesh's mass and inertia "
     "come from its mesh file"),
    ("r.txt", "<sdf/>", "r.txt: neither URDF (<robot>) nor MJCF (<mujoco>)"),
])
def test_bad_files_refuse_with_one_line(name: str, text: str, message: str, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    code, out = run(tmp_path, "", text=text, name=name)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith(f"error: {tmp_path / name}: ") or err.startswith(f"error: {out}: ")
    assert err.count("\n") == 1, err
    assert message.split(": ", 1)[1] in err, err
    assert not out.exists()


def test_a_urdf_in_millimetres_is_refused(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    """A CAD export in millimetres: every length × 1000 (inertias in kg mm² too)."""
    def scale(match: re.Match[str]) -> str:
        values = " ".join(f"{1000 * float(v):g}" for v in match.group(2).split())
        return f'{match.group(1)}="{values}"'

    text = re.sub(r'\b(xyz|size|radius|length)="([^"]*)"', scale,
                  (IMPORTS / "kobuki_like.urdf").read_text())
    text = re.sub(r'\b(i[xyz]{2})="([^"]*)"', lambda m: f'{m.group(1)}="'
                  f'{1e6 * float(m.group(2)):g}"', text)
    code, out = run(tmp_path, "", text=text, name="kobuki_mm.urdf")
    assert code == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err == (f"error: {tmp_path / 'kobuki_mm.urdf'}: field 'wheel[0].radius' = 35.0 m: a "
                   "wheel radius above 5 m is implausible for a wheeled robot; lengths in "
                   "millimetres? Give lengths in metres\n")


def test_a_plain_urdf_declaring_the_xacro_namespace_is_read() -> None:
    """ROBOTIS' turtlebot3_burger.urdf declares xmlns:xacro and uses none of it."""
    assert 'xmlns:xacro="http://ros.org/wiki/xacro"' in (
        IMPORTS / "turtlebot3_like.urdf").read_text()
    assert import_robot(IMPORTS / "turtlebot3_like.urdf").description.name == "turtlebot3_like"


def test_point_mass_and_slightly_lifted_wheel_are_warnings(tmp_path: Path) -> None:
    sensor = (joint("imu_joint", "fixed", "base_link", "imu_link", "0 0 0.05")
              + link("imu_link", 0.01, diag(0, 0, 0)))
    (tmp_path / "r.urdf").write_text(simple(wheel_z=0.035, extra=sensor))
    findings = import_robot(tmp_path / "r.urdf").robot.findings
    assert "link 'imu_link': a point mass (0.01 kg with a zero inertia tensor)" in "\n".join(
        findings)
    assert any(f.startswith("wheel 'left' (joint 'left_joint', link 'left_link'): not on the "
                            "ground plane") and "(lowest point +2.0 mm)" in f for f in findings)


def test_mjcf_angles_default_to_degrees(tmp_path: Path) -> None:
    """The Kobuki-like MJCF turns its wheel bodies with euler="-90 0 0" in degrees (MuJoCo's
    default unit): read as radians (-90 rad ≈ 243°), the wheels' axles are not horizontal,
    so nothing is a wheel."""
    text = (IMPORTS / "kobuki_like.xml").read_text()
    assert "<compiler" not in text and 'euler="-90 0 0"' in text
    radians = text.replace("<mujoco model=\"kobuki_like\">",
                           '<mujoco model="kobuki_like"><compiler angle="radian"/>')
    (tmp_path / "r.xml").write_text(radians)
    with pytest.raises(RobotFileError, match=r"r\.xml: no wheels found"):
        import_robot(tmp_path / "r.xml")


def test_mjcf_reader_agrees_with_mujoco() -> None:
    """Where MuJoCo is installed: every test MJCF compiles, and MuJoCo's body masses,
    centres of mass, inertias, poses and joint axes are the importer's (MuJoCo is not a
    dependency today: checked by hand with MuJoCo 4.0.0, to 1e-14)."""
    mujoco = pytest.importorskip("mujoco")
    import numpy as np

    from modeling.importers import read_mechanism
    from modeling.importers.planar import _Builder

    for path in sorted(IMPORTS.glob("*.xml")):
        mech = read_mechanism(path)
        world = _Builder(mech, Options()).world
        model = mujoco.MjModel.from_xml_path(str(path))
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        for name, link in mech.links.items():
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            np.testing.assert_allclose(data.xpos[i], world[name].origin, atol=1e-12)
            np.testing.assert_allclose(data.xmat[i].reshape(3, 3), world[name].rotation,
                                       atol=1e-12)
            if link.inertial is None:
                continue
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, model.body_iquat[i])
            rot = rot.reshape(3, 3)
            tensor = rot @ np.diag(model.body_inertia[i]) @ rot.T
            assert model.body_mass[i] == pytest.approx(link.inertial.mass, rel=1e-12)
            np.testing.assert_allclose(model.body_ipos[i], link.inertial.com, atol=1e-12)
            np.testing.assert_allclose(tensor, link.inertial.tensor,
                                       atol=1e-12 * float(np.abs(tensor).max()))
        for j in mech.joints:
            if j.kind != "fixed":
                k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.name)
                np.testing.assert_allclose(data.xaxis[k], world[j.child].vector(j.axis),
                                           atol=1e-12)
