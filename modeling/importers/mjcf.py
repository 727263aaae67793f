"""Reading an MJCF (MuJoCo) file into a :class:`~modeling.importers.mechanism.Mechanism`.

Standard library only (``xml.etree``; MuJoCo is not needed). Read: ``<compiler>``
(``angle``, whose default is degrees, ``eulerseq``, ``inertiafromgeom``), ``<default>``
classes (nested, with ``class`` and ``childclass``), the ``<worldbody>`` tree of
``<body>`` elements (``pos`` and one of ``quat``/``euler``/``axisangle``/``xyaxes``/
``zaxis``), each body's joint (``hinge`` → revolute, ``slide`` → prismatic, ``ball``; no
joint → welded to its parent), its ``<inertial>`` (``diaginertia`` or ``fullinertia``) or,
as MuJoCo does without one, the inertia of its geoms (uniform solids of ``mass`` or
``density``, default 1000 kg/m³; a mesh's inertia needs its file and is refused), its
collision geoms (not ``contype="0" conaffinity="0"``; ``fromto`` included), and the
``<actuator>`` elements on joints: driven joints, ``gear`` as the gear ratio N and the
joint's ``armature`` as the reflected rotor inertia J_r N². A ``plane`` geom of the world
body is the ground. Sites, cameras, lights and ``<sensor>`` elements are dropped and listed.
``<include>`` and ``<frame>`` are refused (not read).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from modeling.importers.geometry import (
    ZERO,
    Frame,
    Inertial,
    axis_angle_matrix,
    compose,
    euler_matrix,
    frame_from_axes,
    quat_matrix,
    rotation_onto,
    uniform_tensor,
    volume,
)
from modeling.importers.mechanism import (
    Geom,
    ImportFileError,
    Joint,
    Link,
    Mechanism,
    Motor,
)

ACTUATORS = ("motor", "velocity", "position", "general", "intvelocity", "damper",
             "cylinder", "muscle")
JOINT_TYPES = {"hinge": "revolute", "slide": "prismatic", "ball": "ball", "free": "floating"}
PRIMITIVES = ("box", "cylinder", "sphere", "capsule", "ellipsoid")


class _Reader:
    """One file's compiler settings and default classes, and the element readers."""

    def __init__(self, path: Path, root: ET.Element) -> None:
        self.path = path
        compiler: dict[str, str] = {}
        for c in root.iter("compiler"):
            compiler.update(c.attrib)
        self.degrees = compiler.get("angle", "degree") == "degree"
        self.eulerseq = compiler.get("eulerseq", "xyz")
        self.inertia_from_geom = compiler.get("inertiafromgeom", "auto")
        self.classes: dict[str, dict[str, dict[str, str]]] = {}
        top = root.find("default")
        self._defaults(top, {}, "main")

    def fail(self, message: str) -> ImportFileError:
        return ImportFileError(f"{self.path}: {message}")

    def _defaults(self, el: ET.Element | None, inherited: dict[str, dict[str, str]],
                  name: str) -> None:
        own = {tag: dict(attrs) for tag, attrs in inherited.items()}
        if el is not None:
            for child in el:
                if child.tag != "default":
                    own.setdefault(child.tag, {}).update(child.attrib)
        self.classes[name] = own
        if el is not None:
            for child in el.findall("default"):
                cls = child.get("class")
                if not cls:
                    raise self.fail("a nested <default> needs a class attribute")
                self._defaults(child, own, cls)

    def attrs(self, el: ET.Element, childclass: str) -> dict[str, str]:
        """An element's attributes over its class's defaults."""
        cls = el.get("class", childclass)
        if cls not in self.classes:
            raise self.fail(f"<{el.tag} class=\"{cls}\">: no <default class=\"{cls}\">")
        out = dict(self.classes[cls].get(el.tag, {}))
        out.update(el.attrib)
        return out

    def floats(self, where: str, attrs: dict[str, str], key: str, n: int | None,
               default: tuple[float, ...] | None = None) -> tuple[float, ...]:
        text = attrs.get(key)
        if text is None:
            if default is None:
                raise self.fail(f"{where}: missing attribute '{key}'")
            return default
        try:
            values = tuple(float(v) for v in text.split())
        except ValueError:
            values = ()
        if (n is not None and len(values) != n) or not values or not all(
                math.isfinite(v) for v in values):
            count = f"{n} " if n is not None else ""
            raise self.fail(f"{where}: attribute {key}=\"{text}\" must be {count}finite "
                            "number(s)")
        return values

    def angle(self, value: float) -> float:
        return math.radians(value) if self.degrees else value

    def rotation(self, where: str, a: dict[str, str]) -> np.ndarray:
        given = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in a]
        if len(given) > 1:
            raise self.fail(f"{where}: give one orientation, not {' and '.join(given)}")
        if not given:
            return np.eye(3)
        key = given[0]
        try:
            if key == "quat":
                return quat_matrix(*self.floats(where, a, key, 4))
            if key == "axisangle":
                v = self.floats(where, a, key, 4)
                return axis_angle_matrix(v[:3], self.angle(v[3]))
            if key == "euler":
                v = self.floats(where, a, key, 3)
                return euler_matrix([self.angle(x) for x in v], self.eulerseq)
            if key == "xyaxes":
                v = self.floats(where, a, key, 6)
                return frame_from_axes(v[:3], v[3:])
            return rotation_onto((0.0, 0.0, 1.0), self.floats(where, a, key, 3))
        except (ValueError, ZeroDivisionError, FloatingPointError):
            raise self.fail(f"{where}: {key}=\"{a[key]}\" is not a rotation") from None

    def frame(self, where: str, a: dict[str, str]) -> Frame:
        pos = np.array(self.floats(where, a, "pos", 3, (0.0, 0.0, 0.0)))
        return Frame(self.rotation(where, a), pos)

    def geom(self, where: str, a: dict[str, str]) -> tuple[Geom, float | None]:
        """The geom (sizes in ``geometry``'s convention) and its mass (None: from density
        unless a mesh)."""
        kind = a.get("type", "sphere")
        if kind not in (*PRIMITIVES, "mesh", "plane", "hfield", "sdf"):
            raise self.fail(f"{where}: unknown type=\"{kind}\"")
        frame = self.frame(where, a)
        size: tuple[float, ...] = ()
        if kind in PRIMITIVES:
            if "fromto" in a:
                if kind not in ("cylinder", "capsule", "box", "ellipsoid"):
                    raise self.fail(f"{where}: fromto is for capsules, cylinders, boxes and "
                                    "ellipsoids")
                ft = self.floats(where, a, "fromto", 6)
                start, end = np.array(ft[:3]), np.array(ft[3:])
                length = float(np.linalg.norm(end - start))
                if length == 0:
                    raise self.fail(f"{where}: fromto=\"{a['fromto']}\" has zero length")
                frame = Frame(rotation_onto((0.0, 0.0, 1.0), end - start), (start + end) / 2)
                radius = self.floats(where, a, "size", None)[0]
                if kind in ("cylinder", "capsule"):
                    size = (radius, length)
                elif kind == "box":
                    size = (2 * radius, 2 * radius, length)
                else:
                    size = (radius, radius, length / 2)
            else:
                v = self.floats(where, a, "size", None)
                need = {"sphere": 1, "cylinder": 2, "capsule": 2, "box": 3, "ellipsoid": 3}
                if len(v) < need[kind]:
                    raise self.fail(f"{where}: a {kind} needs {need[kind]} size value(s), got "
                                    f"size=\"{a.get('size')}\"")
                if kind == "sphere":
                    size = (v[0],)
                elif kind in ("cylinder", "capsule"):
                    size = (v[0], 2 * v[1])  # MJCF gives the half-length
                elif kind == "box":
                    size = (2 * v[0], 2 * v[1], 2 * v[2])  # MJCF gives half-sizes
                else:
                    size = (v[0], v[1], v[2])
            if any(s <= 0 for s in size):
                raise self.fail(f"{where}: sizes must be positive, got size=\"{a.get('size')}\"")
        mass = self.floats(where, a, "mass", 1)[0] if "mass" in a else None
        return Geom(kind, size, frame, where), mass

    def inertial(self, where: str, el: ET.Element) -> Inertial:
        a = dict(el.attrib)
        (mass,) = self.floats(where, a, "mass", 1)
        if mass < 0:
            raise self.fail(f"{where}: mass=\"{a['mass']}\" must not be negative")
        if "fullinertia" in a:
            xx, yy, zz, xy, xz, yz = self.floats(where, a, "fullinertia", 6)
            tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        elif "diaginertia" in a:
            tensor = np.diag(self.floats(where, a, "diaginertia", 3))
        else:
            raise self.fail(f"{where}: give diaginertia or fullinertia")
        return Inertial(mass, ZERO.copy(), tensor).moved(self.frame(where, a))


def read_mjcf(path: Path, text: str) -> Mechanism:
    """The mechanism of an MJCF file's text; ``ImportFileError`` naming the element."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ImportFileError(f"{path}: not well-formed XML: {exc}") from None
    if root.tag != "mujoco":
        raise ImportFileError(f"{path}: not an MJCF file (root element <{root.tag}>, "
                              "expected <mujoco>)")
    for tag in ("include", "frame", "replicate", "attach"):
        el = next(root.iter(tag), None)
        if el is not None:
            raise ImportFileError(f"{path}: <{tag}{_attr_text(el)}> is not supported by this "
                                  "importer: give a single file with the bodies written out "
                                  "(MuJoCo's `mj_saveLastXML` writes one)")
    reader = _Reader(path, root)
    world = root.find("worldbody")
    if world is None:
        raise reader.fail("no <worldbody>")
    mech = Mechanism(root.get("model") or path.stem, str(path), "MJCF", "", {}, [])
    for g in world.findall("geom"):
        a = reader.attrs(g, "main")
        if a.get("type") == "plane":
            frame = reader.frame("the world's plane geom", a)
            if abs(frame.rotation[2, 2]) > 0.9999:
                mech.ground = float(frame.origin[2])
                mech.ground_source = f"plane geom{_name(g)} of the world body"
    tops = world.findall("body")
    with_free = [b for b in tops if b.find("freejoint") is not None
                 or any(reader.attrs(j, b.get("childclass", "main")).get("type") == "free"
                        for j in b.findall("joint"))]
    if len(tops) == 1:
        top = tops[0]
    elif len(with_free) == 1:
        top = with_free[0]
        mech.dropped += [f"world body{_name(b)} (not the robot: no free joint)"
                         for b in tops if b is not top]
    else:
        names = ", ".join(b.get("name", "?") for b in tops) or "none"
        raise reader.fail(f"cannot tell which body of <worldbody> is the robot (top-level "
                          f"bodies: {names}; expected one, or one with a free joint)")
    for kind in ("site", "camera", "light"):
        for el in world.findall(kind):
            mech.dropped.append(f"<{kind}{_attr_text(el)}> of the world body")
    _body(reader, mech, top, None, "main")
    mech.root = _body_name(top, 0)
    mech.check_tree()
    _actuators(reader, mech, root)
    for sensor in root.iter("sensor"):
        for el in sensor:
            mech.dropped.append(f"<sensor><{el.tag}{_attr_text(el)}>")
    return mech


def _name(el: ET.Element) -> str:
    return f" '{el.get('name')}'" if el.get("name") else ""


def _attr_text(el: ET.Element) -> str:
    return "".join(f" {k}=\"{v}\"" for k, v in list(el.attrib.items())[:2])


def _body_name(el: ET.Element, index: int) -> str:
    return el.get("name") or f"body{index}"


def _body(reader: _Reader, mech: Mechanism, el: ET.Element, parent: str | None,
          childclass: str) -> None:
    """Read ``el`` and its sub-bodies into ``mech`` (recursive: MJCF nests bodies)."""
    name = _body_name(el, len(mech.links))
    if name in mech.links:
        raise reader.fail(f"body '{name}' is declared twice")
    label = f"body '{name}'"
    childclass = el.get("childclass", childclass)
    battrs = {k: v for k, v in el.attrib.items() if k not in ("name", "childclass")}
    frame = reader.frame(label, battrs)
    geoms: list[Geom] = []
    geom_parts: list[Inertial] = []
    meshes: list[str] = []
    for k, g in enumerate(el.findall("geom")):
        a = reader.attrs(g, childclass)
        where = f"geom{_name(g) or ' ' + str(k + 1)} of {label}"
        geom, mass = reader.geom(where, a)
        collides = not (a.get("contype") == "0" and a.get("conaffinity") == "0")
        if geom.kind in ("plane", "hfield", "sdf"):
            continue
        if collides:
            geoms.append(geom)
        if geom.kind == "mesh":
            if mass is None or mass > 0:
                meshes.append(where)
            continue
        density = float(a.get("density", "1000"))
        m = mass if mass is not None else density * volume(geom.kind, geom.size)
        if m > 0:
            geom_parts.append(Inertial(m, ZERO.copy(), uniform_tensor(geom.kind, geom.size, m))
                              .moved(geom.frame))
    inertial_el = el.find("inertial")
    inertial: Inertial | None
    source = ""
    if inertial_el is not None and reader.inertia_from_geom != "true":
        inertial = reader.inertial(f"{label} <inertial>", inertial_el)
        source = "its <inertial>"
    elif geom_parts or meshes:
        if meshes:
            raise reader.fail(f"{meshes[0]}: a mesh's mass and inertia come from its mesh "
                              "file, which this importer does not read; give the body an "
                              "<inertial> (or the geom mass=\"0\")")
        inertial = compose(geom_parts)
        source = f"its {len(geom_parts)} geom(s), uniform solids (MuJoCo's inertiafromgeom)"
    else:
        inertial = None
    mech.links[name] = Link(name, label, inertial, geoms, source)
    for kind in ("site", "camera", "light"):
        for s in el.findall(kind):
            mech.dropped.append(f"<{kind}{_attr_text(s)}> of {label}")

    joints = [(j, reader.attrs(j, childclass)) for j in el.findall("joint")]
    joints += [(j, {"type": "free", **j.attrib}) for j in el.findall("freejoint")]
    if parent is None:
        mech.root_frame = frame
        kinds = sorted({a.get("type", "hinge") for _, a in joints})
        if joints:
            mech.notes.append(f"the joints of {label} to the world ({', '.join(kinds)}) are "
                              "replaced by the planar base coordinates (x, y, yaw)")
    else:
        if len(joints) > 1:
            raise reader.fail(f"{label} has {len(joints)} joints: only one joint (or none: "
                              "welded) per body is supported")
        if joints:
            j, a = joints[0]
            jname = j.get("name") or f"{name}_joint"
            found = JOINT_TYPES.get(a.get("type", "hinge"))
            if found == "revolute" and "range" not in a and a.get("limited") != "true":
                found = "continuous"  # a hinge without limits turns freely, as a wheel does
            if found is None:
                raise reader.fail(f"joint '{jname}' of {label}: unknown type=\"{a.get('type')}\"")
            axis = np.array(reader.floats(f"joint '{jname}'", a, "axis", 3, (0.0, 0.0, 1.0)))
            if float(np.linalg.norm(axis)) == 0:
                raise reader.fail(f"joint '{jname}' of {label}: axis=\"{a.get('axis')}\" is "
                                  "zero")
            anchor = np.array(reader.floats(f"joint '{jname}'", a, "pos", 3, (0.0, 0.0, 0.0)))
            mech.joints.append(Joint(jname, f"joint '{jname}' (of {label})", found, parent, name,
                                     frame, axis / np.linalg.norm(axis), anchor))
            armature = float(a.get("armature", "0"))
            if armature > 0:
                mech.motors[jname] = Motor(reflected_inertia=armature,
                                           source=f"joint '{jname}' armature")
        else:
            mech.joints.append(Joint(f"{name}_weld", f"{label} (no joint: welded to "
                                     f"'{parent}')", "fixed", parent, name, frame, ZERO.copy(),
                                     ZERO.copy()))
    for sub in el.findall("body"):
        _body(reader, mech, sub, name, childclass)


def _actuators(reader: _Reader, mech: Mechanism, root: ET.Element) -> None:
    names = {j.name for j in mech.joints}
    for block in root.findall("actuator"):
        for el in block:
            if el.tag not in ACTUATORS:
                continue
            a = reader.attrs(el, "main")
            label = f"<actuator><{el.tag}{_name(el)}>"
            joint = a.get("joint")
            if joint is None:
                mech.notes.append(f"{label} acts on no joint (a tendon or site): ignored")
                continue
            if joint not in names:
                raise reader.fail(f"{label}: joint=\"{joint}\" does not exist")
            if joint not in mech.driven:
                mech.driven.append(joint)
                mech.driven_source[joint] = label
            if "gear" not in a:
                continue  # MuJoCo's default gear 1 says nothing about a gearbox
            gear = abs(reader.floats(label, a, "gear", None)[0])
            before = mech.motors.get(joint, Motor())
            mech.motors[joint] = Motor(
                gear_ratio=gear, reflected_inertia=before.reflected_inertia,
                source=f"{label} gear" + (f" and {before.source}" if before.source else ""))
