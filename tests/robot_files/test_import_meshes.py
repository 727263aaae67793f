"""Wheels whose collision geometry is a mesh (``modeling.importers.meshes``): the mesh's
vertices give the wheel's cylinder when its file is found and is STL (binary or ASCII) or
OBJ; otherwise the wheel is refused as before, its radius unknown, and the one-line error
says why the mesh gave no cylinder.

The robot: a 2 kg box base on two wheels of radius 0.05 m and width 0.02 m, 0.3 m apart,
and a slider caster; each wheel's only collision is a mesh of a 64-sided prism along the
mesh's own z, turned onto the axle by the collision's origin (rpy -π/2 about x), as CAD
exports are. The meshes are written here; MuJoCo, reading the same binary STL, gives the
same extents (a reader we did not write).
"""

from __future__ import annotations

import math
import re
import struct
from pathlib import Path

import numpy as np
import pytest

from modeling.importers import import_robot
from modeling.importers.meshes import read_vertices
from modeling.robot_io import RobotFileError

RADIUS, WIDTH, TRACK = 0.05, 0.02, 0.3
URDF = """<?xml version="1.0"?>
<robot name="meshy">
  <link name="base_link">
    <inertial><origin xyz="0 0 0.1"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.04"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.4 0.3 0.1"/></geometry>
    </collision>
    <collision><origin xyz="-0.15 0 0.025"/><geometry><sphere radius="0.025"/></geometry>
    </collision>
  </link>
  {wheels}
</robot>
"""
WHEEL = """
  <joint name="{side}_joint" type="continuous">
    <parent link="base_link"/><child link="{side}_wheel"/>
    <origin xyz="0 {y} 0.05"/><axis xyz="0 1 0"/>
  </joint>
  <link name="{side}_wheel">
    <inertial><mass value="0.1"/>
      <inertia ixx="7e-5" ixy="0" ixz="0" iyy="1.25e-4" iyz="0" izz="7e-5"/></inertial>
    <collision><origin rpy="-1.5707963267948966 0 0"/>
      <geometry><mesh filename="{mesh}"{scale}/></geometry></collision>
  </link>
"""


def prism(radius: float, width: float, sides: int = 64, x_radius: float | None = None
          ) -> np.ndarray:
    """Triangles (n × 3 × 3) of a closed prism along z, centred at the origin (an ellipse
    with semi-axis ``x_radius`` along x if given)."""
    a = np.linspace(0, 2 * math.pi, sides, endpoint=False)
    ring = np.stack([(x_radius or radius) * np.cos(a), radius * np.sin(a)], axis=1)
    top = np.column_stack([ring, np.full(sides, width / 2)])
    bottom = np.column_stack([ring, np.full(sides, -width / 2)])
    tris = []
    for i in range(sides):
        j = (i + 1) % sides
        tris += [(bottom[i], bottom[j], top[j]), (bottom[i], top[j], top[i]),
                 ((0, 0, width / 2), top[i], top[j]), ((0, 0, -width / 2), bottom[j], bottom[i])]
    return np.array(tris, dtype=float)


def binary_stl(tris: np.ndarray) -> bytes:
    out = bytearray(b"wheel".ljust(80, b" ") + struct.pack("<I", len(tris)))
    for t in tris:
        out += struct.pack("<12fH", 0, 0, 0, *t.reshape(-1), 0)
    return bytes(out)


def ascii_stl(tris: np.ndarray) -> str:
    lines = ["solid wheel"]
    for t in tris:
        lines += ["facet normal 0 0 0", " outer loop",
                  *[f"  vertex {x:.9g} {y:.9g} {z:.9g}" for x, y, z in t],
                  " endloop", "endfacet"]
    return "\n".join([*lines, "endsolid wheel", ""])


def obj(tris: np.ndarray) -> str:
    verts = tris.reshape(-1, 3)
    faces = [f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}" for k in range(len(tris))]
    return "\n".join(["# wheel", *[f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in verts],
                      *faces, ""])


def robot(folder: Path, mesh: str, scale: str = "") -> Path:
    attr = f' scale="{scale}"' if scale else ""
    wheels = "".join(WHEEL.format(side=s, y=y, mesh=mesh, scale=attr)
                     for s, y in (("left", TRACK / 2), ("right", -TRACK / 2)))
    path = folder / "urdf" / "meshy.urdf"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(URDF.format(wheels=wheels))
    return path


def wheels_of(path: Path, package_path: tuple[Path, ...] = ()) -> tuple[list[float], float]:
    imported = import_robot(path, package_path=package_path)
    desc = imported.description
    ys = [float(w.position[1]) for w in desc.wheels]
    header = re.sub(r"\n#\s+", " ", imported.text)  # the header's lines joined
    assert "the mesh's vertices give a cylinder of radius 0.05 m and width 0.02 m" in header
    return [float(w.radius) for w in desc.wheels], max(ys) - min(ys)


def test_a_binary_stl_in_a_package(tmp_path: Path) -> None:
    """package://wheels_description/meshes/wheel.stl, the package found by --package-path."""
    pkg = tmp_path / "elsewhere" / "wheels_pkg"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='3'><name>wheels_description</name></package>")
    (pkg / "meshes" / "wheel.stl").write_bytes(binary_stl(prism(RADIUS, WIDTH)))
    path = robot(tmp_path / "robot", "package://wheels_description/meshes/wheel.stl")
    with pytest.raises(RobotFileError, match="no wheels found"):
        import_robot(path)  # the package is nowhere above or beside the file
    radii, track = wheels_of(path, (tmp_path / "elsewhere",))
    assert radii == pytest.approx([RADIUS, RADIUS], rel=1e-6)
    assert track == pytest.approx(TRACK, rel=1e-12)


def test_an_ascii_stl_beside_the_file_off_its_origin(tmp_path: Path) -> None:
    """The mesh 10 mm off its own origin along its axis (the collision origin turns that
    onto the link's +y): each wheel's centre moves 10 mm to the left."""
    path = robot(tmp_path, "../meshes/wheel.stl")
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "wheel.stl").write_text(
        ascii_stl(prism(RADIUS, WIDTH) + np.array([0.0, 0.0, 0.01])))
    radii, _ = wheels_of(path)
    assert radii == pytest.approx([RADIUS, RADIUS], rel=1e-6)
    ys = sorted(float(w.position[1]) for w in import_robot(path).description.wheels)
    assert ys == pytest.approx([-TRACK / 2 + 0.01, TRACK / 2 + 0.01], abs=1e-9)


def test_an_obj_in_millimetres_with_its_scale(tmp_path: Path) -> None:
    path = robot(tmp_path, "wheel.obj", scale="0.001 0.001 0.001")
    (path.parent / "wheel.obj").write_text(obj(prism(1000 * RADIUS, 1000 * WIDTH)))
    radii, _ = wheels_of(path)
    assert radii == pytest.approx([RADIUS, RADIUS], rel=1e-6)


@pytest.mark.parametrize("name, why", [
    ("wheel.dae", "mesh 'wheel.dae' not read: a .dae mesh is not read (STL and OBJ are)"),
    ("absent.stl", "mesh 'absent.stl' not found (give --package-path"),
    ("oval.stl", "its mesh is not round about the joint axis (extents 0.08 and 0.1 m"),
])
def test_a_mesh_that_gives_no_cylinder_leaves_the_wheel_refused(
        tmp_path: Path, name: str, why: str) -> None:
    path = robot(tmp_path, name)
    (path.parent / "wheel.dae").write_text("<COLLADA/>")
    (path.parent / "oval.stl").write_bytes(binary_stl(prism(RADIUS, WIDTH, x_radius=0.04)))
    with pytest.raises(RobotFileError, match="no wheels found") as exc:
        import_robot(path)
    assert "\n" not in str(exc.value) and why in str(exc.value)


def test_the_stl_reader_agrees_with_mujoco(tmp_path: Path) -> None:
    """MuJoCo's own STL reader: the same extents (sorted: MuJoCo turns a mesh into its
    principal frame)."""
    mujoco = pytest.importorskip("mujoco")
    stl = tmp_path / "wheel.stl"
    stl.write_bytes(binary_stl(prism(RADIUS, WIDTH)))
    ours = read_vertices(stl)
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><asset><mesh name="w" file="{stl}"/></asset>'
        '<worldbody><body><geom type="mesh" mesh="w"/></body></worldbody></mujoco>')
    theirs = model.mesh_vert[model.mesh_vertadr[0]:model.mesh_vertadr[0]
                             + model.mesh_vertnum[0]]
    assert sorted(np.ptp(ours, axis=0)) == pytest.approx(sorted(np.ptp(theirs, axis=0)),
                                                         rel=1e-6)
    assert sorted(np.ptp(ours, axis=0)) == pytest.approx([WIDTH, 2 * RADIUS, 2 * RADIUS],
                                                         rel=1e-6)
