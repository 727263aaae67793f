"""``wmr import`` on description files as they are published (issue 47).

* ROBOTIS' TurtleBot3 files, verbatim (tests/robots/public/turtlebot3/, Apache-2.0): the
  2019 Burger, a plain URDF with a commented-out ``<xacro:include>``, is read, not refused
  as xacro; the 2025 Burger and Waffle (``<xacro:arg>`` and ``${namespace}`` in every
  name) go through the built-in xacro expansion; all give the files' own masses and tracks
  (Burger 1.00173 kg, 0.160 m; Waffle 1.55391 kg, 0.288 m). Their ``base_link`` centre of
  mass, left at the link origin, is flagged.
* xacro's ``$(find PKG)`` resolves above the file, or under ``--package-path``; a package
  found nowhere, or a template that does not expand, is one line naming the file, with no
  suggested command that would overwrite it.
* Bad input stays clean: one driven wheel, an unwritable output folder: one line, exit 2,
  nothing written. The written file has a new file's permissions under the umask.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from modeling.importers import import_robot
from modeling.robot_io import RobotFileError
from runtime.cli import main as wmr

TB3 = Path(__file__).resolve().parents[1] / "robots" / "public" / "turtlebot3"


def total_mass_and_track(path: Path) -> tuple[float, float, tuple[str, ...]]:
    desc = import_robot(path).description
    mass = sum(float(b.mass) for b in desc.bodies) + sum(float(w.mass) for w in desc.wheels)
    ys = [float(w.position[1]) for w in desc.wheels]
    return mass, max(ys) - min(ys), desc.warnings


@pytest.mark.parametrize("name, mass, track", [
    ("turtlebot3_burger_2019.urdf", 1.0017329, 0.160),
    ("turtlebot3_burger.urdf", 1.0017329, 0.160),
    ("turtlebot3_waffle.urdf", 1.5539071, 0.288),
    ("turtlebot3_waffle_pi.urdf", 1.5539071, 0.288),
])
def test_turtlebot3_imports_verbatim(name: str, mass: float, track: float) -> None:
    text = (TB3 / name).read_text()
    assert "xmlns:xacro" in text and "<!-- <xacro:include" in text  # as published
    got_mass, got_track, warnings = total_mass_and_track(TB3 / name)
    assert got_mass == pytest.approx(mass, rel=1e-6)
    assert got_track == pytest.approx(track, rel=1e-12)
    joined = "\n".join(warnings)
    assert "link 'base_link': its centre of mass is exactly at the link origin" in joined
    assert "driven wheels wheel_left and wheel_right assumed" in joined


def test_the_2019_burger_needs_no_expansion_and_the_2025_one_does(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The 2019 file's only xacro is in a comment: it is read without xacro; the 2025 one
    names every link ${namespace}...: without xacro it could not be read."""
    import modeling.importers as importers

    def no_xacro(*args: object) -> str:
        raise AssertionError("expanded")

    monkeypatch.setattr(importers, "expand", no_xacro)
    import_robot(TB3 / "turtlebot3_burger_2019.urdf")
    import_robot(TB3 / "turtlebot3_waffle_2019.urdf")  # ${...} only in comments
    with pytest.raises(AssertionError, match="expanded"):
        import_robot(TB3 / "turtlebot3_burger.urdf")


def test_xacro_args_reach_the_template(tmp_path: Path) -> None:
    out = tmp_path / "b.toml"
    assert wmr(["import", str(TB3 / "turtlebot3_burger.urdf"), "--out", str(out),
                "--xacro-arg", "namespace:=tb3_"]) == 0
    assert "# joint 'tb3_wheel_left_joint' (continuous)" in out.read_text()


PACKAGE = """<?xml version="1.0"?>
<package format="3"><name>{name}</name><version>1.0.0</version></package>
"""
MAIN = """<?xml version="1.0"?>
<robot name="found" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:include filename="$(find parts_description)/urdf/parts.xacro"/>
  <xacro:property name="r" value="0.033"/>
  <link name="base_link">
    <inertial><mass value="1.0"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial>
    <collision><origin xyz="0 0 0.07"/><geometry><box size="0.14 0.14 0.14"/></geometry>
    </collision>
  </link>
  <xacro:wheel side="left" y="0.08"/>
  <xacro:wheel side="right" y="-0.08"/>
</robot>
"""
PARTS = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="wheel" params="side y">
    <joint name="${side}_joint" type="continuous">
      <parent link="base_link"/><child link="${side}_link"/>
      <origin xyz="0 ${y} ${r}" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    </joint>
    <link name="${side}_link">
      <inertial><mass value="0.03"/>
        <inertia ixx="1.1e-5" ixy="0" ixz="0" iyy="1.1e-5" iyz="0" izz="2.1e-5"/></inertial>
      <collision><geometry><cylinder radius="${r}" length="0.018"/></geometry></collision>
    </link>
  </xacro:macro>
</robot>
"""


def workspace(root: Path) -> Path:
    """A ROS workspace: robot_description/urdf/robot.urdf.xacro including a macro from the
    parts_description package (a folder named otherwise, with its package.xml)."""
    main = root / "src" / "robot_description" / "urdf" / "robot.urdf.xacro"
    main.parent.mkdir(parents=True)
    main.write_text(MAIN)
    parts = root / "src" / "parts_pkg"
    (parts / "urdf").mkdir(parents=True)
    (parts / "package.xml").write_text(PACKAGE.format(name="parts_description"))
    (parts / "urdf" / "parts.xacro").write_text(PARTS)
    return main


def test_find_resolves_under_the_package_path_or_beside_the_file(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]
                                                                  ) -> None:
    main = workspace(tmp_path / "ws")
    out = tmp_path / "r.toml"
    # parts_pkg is not beside any folder above the file under its package name: not found.
    assert wmr(["import", str(main), "--out", str(out)]) == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {main}: xacro could not expand "
                                                   "it: unknown macro name: xacro:wheel")
    assert err.endswith("(includes skipped, their packages found nowhere above the file or "
                        "under --package-path: parts_description/urdf/parts.xacro; give the "
                        "folder holding them with --package-path DIR)\n")
    assert wmr(["import", str(main), "--out", str(out), "--package-path",
                str(tmp_path / "ws" / "src")]) == 0
    assert import_robot(main, package_path=[tmp_path / "ws"]).description.name == "found"
    # Named after its package, the folder is found from the file's own tree.
    (tmp_path / "ws" / "src" / "parts_pkg").rename(tmp_path / "ws" / "src" / "parts_description")
    assert import_robot(main).description.name == "found"


def test_a_template_that_does_not_expand_suggests_nothing_that_overwrites_it(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.urdf"
    bad.write_text(MAIN.replace("$(find parts_description)/urdf/", ""))  # include missing
    before = bad.read_text()
    assert wmr(["import", str(bad), "--out", str(tmp_path / "r.toml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {bad}: xacro could not expand it: ") and err.count("\n") == 1
    assert ">" not in err.split("could not expand it")[1]  # no `xacro F > F` advice
    assert bad.read_text() == before


def test_one_driven_wheel_is_refused_at_import(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.toml"
    assert wmr(["import", str(TB3 / "turtlebot3_burger_2019.urdf"), "--out", str(out),
                "--driven", "wheel_left_joint"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "one driven wheel ('wheel_left', --driven on the command " \
        "line): a planar robot of wheels on one axle and casters has two degrees of " \
        "freedom" in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_an_unwritable_output_is_one_line(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "file").write_text("not a folder")
    out = tmp_path / "file" / "r.toml"
    assert wmr(["import", str(TB3 / "turtlebot3_burger_2019.urdf"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: --out {out}: cannot write it: ") and err.count("\n") == 1


def test_the_robot_file_has_a_new_files_permissions(tmp_path: Path) -> None:
    out = tmp_path / "r.toml"
    old = os.umask(0o022)
    try:
        assert wmr(["import", str(TB3 / "turtlebot3_burger_2019.urdf"), "--out", str(out)]) == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


def test_a_refused_import_names_the_input(tmp_path: Path) -> None:
    with pytest.raises(RobotFileError, match=r"bad\.xml: neither URDF"):
        (tmp_path / "bad.xml").write_text("<sdf version='1.6'/>")
        import_robot(tmp_path / "bad.xml")


def test_a_mesh_without_inertia_is_reported(tmp_path: Path) -> None:
    """A link whose only geometry is a mesh (its file absent, never needed) and that has no
    <inertial>: its mass is not in the file; imported massless, with a finding."""
    lidar = """
  <joint name="lidar_joint" type="fixed">
    <parent link="base_link"/><child link="lidar"/><origin xyz="0 0 0.2"/>
  </joint>
  <link name="lidar">
    <collision><geometry><mesh filename="package://absent/meshes/lidar.stl"/></geometry>
    </collision>
  </link>
</robot>"""
    path = tmp_path / "burger_lidar.urdf"
    path.write_text((TB3 / "turtlebot3_burger_2019.urdf").read_text().replace("</robot>", lidar))
    findings = import_robot(path).robot.findings
    assert any(f.startswith("link 'lidar': a mesh without inertia (link 'lidar' <collision> is "
                            "a mesh, and the link has no <inertial>): imported massless")
               for f in findings), findings
