"""Reading a URDF (ROS) file into a :class:`~modeling.importers.mechanism.Mechanism`.

Standard library only (``xml.etree``; no ROS). Read: ``<link>`` (``<inertial>`` with
``origin``, ``mass``, ``inertia``; ``<collision>`` geometry: box, cylinder, sphere, mesh),
``<joint>`` (type, parent, child, ``origin`` xyz/rpy, ``axis``, URDF's default axis x),
and what is driven: ``<transmission>`` joints (ROS 1, with ``mechanicalReduction`` as the
gear ratio), ``<ros2_control>`` joints with a command interface, and the joints named by a
Gazebo differential-drive or skid-steer plugin. ``<gazebo>`` sensors are dropped and
listed; ``<visual>`` is ignored (collision geometry says where a wheel touches the ground).

The text is plain URDF: a xacro template is expanded before it gets here
(``modeling.importers.expand``). Comments, namespace declarations and elements of other
namespaces (an unused ``<xacro:arg>``) are ignored.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from modeling.importers.geometry import (
    IDENTITY_FRAME,
    ZERO,
    Frame,
    Inertial,
    rpy_matrix,
)
from modeling.importers.mechanism import (
    Geom,
    ImportFileError,
    Joint,
    Link,
    Mechanism,
    Motor,
)

JOINT_KINDS = ("fixed", "revolute", "continuous", "prismatic", "floating", "planar")


def _floats(path: Path, where: str, attr: str, text: str | None, n: int,
            default: tuple[float, ...] | None = None) -> tuple[float, ...]:
    if text is None:
        if default is None:
            raise ImportFileError(f"{path}: {where}: missing attribute '{attr}'")
        return default
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        values = ()
    if len(values) != n or not all(np.isfinite(values)):
        raise ImportFileError(f"{path}: {where}: attribute {attr}=\"{text}\" must be {n} "
                              "finite number(s)")
    return values


def _origin(path: Path, where: str, element: ET.Element | None) -> Frame:
    if element is None:
        return IDENTITY_FRAME
    xyz = _floats(path, f"{where} <origin>", "xyz", element.get("xyz"), 3, (0.0, 0.0, 0.0))
    rpy = _floats(path, f"{where} <origin>", "rpy", element.get("rpy"), 3, (0.0, 0.0, 0.0))
    return Frame(rpy_matrix(*rpy), np.array(xyz))


def _inertial(path: Path, label: str, element: ET.Element | None) -> Inertial | None:
    if element is None:
        return None
    where = f"{label} <inertial>"
    mass_el = element.find("mass")
    if mass_el is None:
        raise ImportFileError(f"{path}: {where}: missing <mass value=...>")
    (mass,) = _floats(path, f"{where} <mass>", "value", mass_el.get("value"), 1)
    if mass < 0:
        raise ImportFileError(f"{path}: {where} <mass value=\"{mass_el.get('value')}\">: a "
                              "mass must not be negative")
    inertia_el = element.find("inertia")
    if inertia_el is None:
        raise ImportFileError(f"{path}: {where}: missing <inertia ixx=... iyy=... izz=...>")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    v = {k: _floats(path, f"{where} <inertia>", k, inertia_el.get(k), 1,
                    (0.0,) if k in ("ixy", "ixz", "iyz") else None)[0] for k in keys}
    tensor = np.array([[v["ixx"], v["ixy"], v["ixz"]],
                       [v["ixy"], v["iyy"], v["iyz"]],
                       [v["ixz"], v["iyz"], v["izz"]]])
    frame = _origin(path, where, element.find("origin"))
    return Inertial(mass, ZERO.copy(), tensor).moved(frame)


def _geometry(path: Path, where: str, element: ET.Element) -> Geom | None:
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        raise ImportFileError(f"{path}: {where}: missing <geometry>")
    shape = geometry[0]
    frame = _origin(path, where, element.find("origin"))
    if shape.tag == "box":
        size = _floats(path, f"{where} <box>", "size", shape.get("size"), 3)
    elif shape.tag == "cylinder":
        size = (_floats(path, f"{where} <cylinder>", "radius", shape.get("radius"), 1)[0],
                _floats(path, f"{where} <cylinder>", "length", shape.get("length"), 1)[0])
    elif shape.tag == "sphere":
        size = _floats(path, f"{where} <sphere>", "radius", shape.get("radius"), 1)
    elif shape.tag == "mesh":
        return Geom("mesh", (), frame, where, shape.get("filename", ""),
                    shape.get("scale", ""))
    else:
        raise ImportFileError(f"{path}: {where}: unknown geometry <{shape.tag}>")
    if any(s <= 0 for s in size):
        raise ImportFileError(f"{path}: {where} <{shape.tag}>: sizes must be positive, got "
                              f"{size}")
    return Geom(shape.tag, size, frame, where)


def read_urdf(path: Path, text: str) -> Mechanism:
    """The mechanism of a URDF file's text; ``ImportFileError`` naming the element."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ImportFileError(f"{path}: not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise ImportFileError(f"{path}: not a URDF file (root element <{root.tag}>, "
                              "expected <robot>)")
    links: dict[str, Link] = {}
    for i, el in enumerate(root.findall("link")):
        name = el.get("name")
        if not name:
            raise ImportFileError(f"{path}: <link> number {i + 1}: missing attribute 'name'")
        if name in links:
            raise ImportFileError(f"{path}: link '{name}' is declared twice")
        label = f"link '{name}'"
        geoms = []
        for k, col in enumerate(el.findall("collision")):
            tag = f"{label} <collision>" + (f" '{col.get('name')}'" if col.get("name") else
                                            f" {k + 1}" if len(el.findall("collision")) > 1
                                            else "")
            g = _geometry(path, tag, col)
            if g is not None:
                geoms.append(g)
        links[name] = Link(name, label, _inertial(path, label, el.find("inertial")), geoms)
    if not links:
        raise ImportFileError(f"{path}: no <link> elements")

    joints: list[Joint] = []
    for i, el in enumerate(root.findall("joint")):
        name = el.get("name") or f"joint{i + 1}"
        label = f"joint '{name}'"
        kind = el.get("type")
        if kind not in JOINT_KINDS:
            raise ImportFileError(f"{path}: {label}: type=\"{kind}\" is not a URDF joint type "
                                  f"({', '.join(JOINT_KINDS)})")
        ends = {}
        for end in ("parent", "child"):
            e = el.find(end)
            if e is None or not e.get("link"):
                raise ImportFileError(f"{path}: {label}: missing <{end} link=...>")
            ends[end] = e.get("link", "")
        axis_el = el.find("axis")
        axis = np.array(_floats(path, f"{label} <axis>", "xyz",
                                None if axis_el is None else axis_el.get("xyz"), 3,
                                (1.0, 0.0, 0.0)))
        if kind in ("revolute", "continuous", "prismatic"):
            norm = float(np.linalg.norm(axis))
            if norm == 0:
                raise ImportFileError(f"{path}: {label} <axis xyz=\"0 0 0\">: a joint axis "
                                      "must not be zero")
            axis = axis / norm
        joints.append(Joint(name, label, kind, ends["parent"], ends["child"],
                            _origin(path, label, el.find("origin")), axis, ZERO.copy()))

    children = {j.child for j in joints}
    roots = [n for n in links if n not in children]
    if len(roots) != 1:
        found = "no root link" if not roots else f"several root links: {', '.join(roots)}"
        raise ImportFileError(f"{path}: {found} (a URDF robot is one tree of links)")
    mech = Mechanism(root.get("name") or path.stem, str(path), "URDF", roots[0], links, joints)
    mech.check_tree()
    _drive(mech, root)
    _sensors(mech, root)
    for name, link in links.items():
        if "footprint" in name and link.inertial is None:
            mech.ground_link = name
            mech.ground_source = f"the massless frame link '{name}'"
    return mech


def _drive(mech: Mechanism, root: ET.Element) -> None:
    """Driven joints and gear ratios from transmissions, ros2_control and drive plugins."""
    names = {j.name for j in mech.joints}

    def drive(joint: str, source: str) -> None:
        if joint not in names:
            mech.notes.append(f"{source} names joint '{joint}', which does not exist: ignored")
            mech.missing_driven.append(joint)
            return
        if joint not in mech.driven:
            mech.driven.append(joint)
            mech.driven_source[joint] = source

    for t in root.iter("transmission"):
        label = f"<transmission name=\"{t.get('name', '')}\">"
        reduction = None
        for act in t.findall("actuator"):
            red = act.find("mechanicalReduction")
            if red is not None and red.text and red.text.strip():
                try:
                    reduction = float(red.text)
                except ValueError:
                    raise ImportFileError(f"{mech.path}: {label} <mechanicalReduction>"
                                          f"{red.text}</mechanicalReduction>: not a number"
                                          ) from None
        for j in t.findall("joint"):
            joint = j.get("name", "")
            drive(joint, label)
            if reduction is not None and reduction != 1 and joint in names:  # 1: ROS's default
                mech.motors[joint] = Motor(gear_ratio=reduction,
                                           source=f"{label} <mechanicalReduction>")
    for rc in root.iter("ros2_control"):
        for j in rc.findall("joint"):
            if j.find("command_interface") is not None:
                drive(j.get("name", ""), f"<ros2_control name=\"{rc.get('name', '')}\">")
    for plugin in root.iter("plugin"):
        filename = (plugin.get("filename") or "") + (plugin.get("name") or "")
        if re.search(r"planar_move|mecanum|omni", filename, re.IGNORECASE):
            mech.omnidirectional = f"<plugin filename=\"{plugin.get('filename', '')}\">"
        if not re.search(r"diff_?drive|skid_?steer|DiffDrive|SkidSteer", filename):
            continue
        for el in plugin.iter():
            if el is not plugin and "joint" in el.tag.lower() and el.text and el.text.strip():
                drive(el.text.strip(), f"<plugin filename=\"{plugin.get('filename', '')}\">")


def _sensors(mech: Mechanism, root: ET.Element) -> None:
    """Gazebo sensors and other elements without dynamics: dropped and listed."""
    for gz in root.iter("gazebo"):
        for sensor in gz.iter("sensor"):
            where = f" on link '{gz.get('reference')}'" if gz.get("reference") else ""
            mech.dropped.append(f"gazebo <sensor name=\"{sensor.get('name', '')}\" "
                                f"type=\"{sensor.get('type', '')}\">{where}")
