"""A MuJoCo model (MJCF) of any planar wheeled robot, with the derived model's planar dynamics.

``mjcf(robot, contact)`` writes the MJCF of a :class:`modeling.planar_robot.PlanarRobot`
(``wmr mjcf``, and the MuJoCo plant of ``runtime.mujoco``). The inertias are chosen so that
MuJoCo's mass matrix, restricted to the planar motions (root x, y, yaw; each hitch's yaw;
each wheel's spin) and mapped to the derived model's coordinates, is the derived M(q) of
(9) (``tests/runtime/test_mujoco.py`` checks it with ``mj_fullM`` at random states):

* the root is a free body (``root``: its frame origin is the robot's (x, y), e.g.
  Drishti's C); every further body hangs from its parent on a vertical hinge at the hitch
  (``hitch_<body>``, the hinge angle is the relative yaw θ_body − θ_parent); body frames
  are at ground level, centres of mass at the axle height (the mean wheel radius: out of
  the plane, it only sets the load transfer under acceleration);
* each wheel is a body on a hinge about its body's y axis (``wheel_<name>``: positive when
  it rolls forward), centre at its wheel radius above the ground. MuJoCo needs a positive
  mass and inertia for every moving body: a wheel gets at least ``MIN_WHEEL_MASS_FRACTION``
  of the robot's mass, a diameter inertia at least that mass's m r²/4 and a small spin
  inertia of its own; what a wheel receives beyond the description is taken off its body
  (mass, centre of mass and yaw inertia, by the parallel-axis theorem), so the assembly's
  planar inertia is unchanged, and the spin inertia beyond the wheel body's own is the
  hinge's ``armature`` (MuJoCo adds it to the wheel's diagonal of M);
* every support (``modeling.supports``: a caster or skid the robot file states, else the
  default, two across the axle of a robot whose wheels all stand on one line) is a
  frictionless sphere on its body (named as the support, normal force only: ``condim``
  1) touching the ground at the stated point;
* payload bodies (``payload_<i>``) are welded to the root body at the stated points with
  a negligible mass; the plant sets their mass at run time (the payload schedule).

Contact (:class:`ContactSettings`, the experiment's ``[plant]`` for ``model = "mujoco"``):
wheel–ground friction μ (``friction``: the slip threshold, |f_t| ≤ μ N per contact), the
tyre (``tyre_width`` 0: a sphere, one point contact under the wheel centre, as the derived
model's rolling constraints assume; > 0: a capsule across the tyre, two contact points
± width/2 from the wheel's mid-plane, which scrub when the robot turns), and the contact's
softness (``contact_timeconst``, MuJoCo's ``solref`` time constant: the larger, the softer
the contact, the deeper the tyres sink and the more they creep under traction). Every
support is the same spring (the compliance ``modeling.contact_loads`` states for the
normal loads): MuJoCo scales a contact's stiffness by the inverse of its body's inverse
weight, so each contact geom gets its own time constant (:func:`contact_time_constants`:
the softest by that scale keeps ``contact_timeconst``, the others are slower) and the
engine carries the loads the load model states. The wheel
geoms take precedence over the ground's (``priority``), so their friction is the contact's.
Each driven wheel has a torque motor (``motor_<name>``, gear 1, limited to ± ``tau_max``),
bearing friction as joint ``damping`` (viscous, N m s/rad) and ``frictionloss`` (Coulomb,
N m). Everything here is numbers: no SymPy.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from modeling.planar_robot import (
    PlanarBody,
    PlanarRobot,
    PlanarWheel,
    Point,
    body_origins,
)
from modeling.supports import robot_supports, support_points

MIN_WHEEL_MASS_FRACTION = 1e-4  # of the robot's mass: the lightest wheel body MuJoCo gets
PAYLOAD_PLACEHOLDER_MASS = 1e-9  # kg: a payload body before the plant sets its mass
GRAVITY = 9.81


@dataclass(frozen=True)
class ContactSettings:
    """What the engine adds to the robot's description (see the module docstring)."""

    friction: float = 1.0  # μ, wheel-ground sliding friction
    tyre_width: float = 0.0  # m; 0: a sphere (point contact)
    contact_timeconst: float = 0.005  # s, solref[0]: the contact's softness
    contact_dampratio: float = 1.0  # solref[1]
    timestep: float = 0.001  # s
    tau_max: float = math.inf  # N m per driven wheel (inf: no limit)
    viscous: float = 0.0  # N m s/rad per driven wheel
    coulomb: float = 0.0  # N m per driven wheel
    payloads: tuple[Point, ...] = ()  # payload points on the root body (m, root frame)


@dataclass(frozen=True)
class EngineBody:
    """A body as the engine gets it: the description's, less what its wheels took."""

    mass: float
    com: Point
    yaw_inertia: float


def wheel_body_inertia(robot: PlanarRobot, w: PlanarWheel) -> tuple[float, float, float]:
    """(mass, diameter inertia, own spin inertia) of a wheel's engine body."""
    mass = max(w.mass, MIN_WHEEL_MASS_FRACTION * robot.total_mass())
    floor = mass * w.radius**2 / 4
    diameter = max(w.diameter_inertia, floor)
    spin = min(floor, w.spin_inertia / 2) if w.spin_inertia > 0 else floor
    return mass, diameter, spin


def engine_body(robot: PlanarRobot, body: PlanarBody) -> EngineBody:
    """``body`` less the mass and yaw inertia its wheels' engine bodies add beyond the
    description (parallel-axis theorem about the body frame's origin)."""
    mass, (cx, cy) = body.mass, body.com
    j_origin = body.yaw_inertia + mass * (cx**2 + cy**2)
    mx, my = mass * cx, mass * cy
    for w in robot.wheels:
        if w.body != body.name:
            continue
        wm, wd, _ = wheel_body_inertia(robot, w)
        dm, dj = wm - w.mass, wd - w.diameter_inertia
        px, py = w.position
        mass -= dm
        mx -= dm * px
        my -= dm * py
        j_origin -= dm * (px**2 + py**2) + dj
    if mass <= 0:
        raise ValueError(f"robot '{robot.name}': body '{body.name}' is too light for its "
                         "wheels' engine bodies")
    com = (mx / mass, my / mass)
    yaw = j_origin - mass * (com[0] ** 2 + com[1] ** 2)
    if yaw <= 0:
        raise ValueError(f"robot '{robot.name}': body '{body.name}' has too little yaw "
                         "inertia for its wheels' engine bodies")
    return EngineBody(mass, com, yaw)


def supports(robot: PlanarRobot) -> tuple[tuple[Point, float], ...]:
    """The frictionless supports' centres (root frame, hitches straight) and radii, in
    :func:`modeling.supports.robot_supports` order: the robot file's stated supports, else
    the default (two across the axle of a robot whose wheels are all on one line)."""
    points = support_points(robot)
    return tuple((points[s.name], s.radius) for s in robot_supports(robot))


def support_names(robot: PlanarRobot) -> tuple[str, ...]:
    """The names of :func:`supports`' spheres, in its order."""
    return tuple(s.name for s in robot_supports(robot))


def engine_inverse_weights(robot: PlanarRobot, contact: ContactSettings = ContactSettings()
                           ) -> dict[str, float]:
    """The translational inverse weight MuJoCo gives each body of :func:`mjcf`'s model
    (``body_invweight0``: trace(J M⁻¹ Jᵀ)/3 at the body's centre of mass, in the model's
    reference pose, payload bodies at their placeholder mass), computed from the same
    numbers the MJCF states: the free root, the hitches' and wheels' hinges (armature
    included), every body's mass and diagonal inertia. Keys: every body's name (its
    supports) and ``wheel_<name>``. ``tests/runtime/test_contact_loads.py`` checks it against
    MuJoCo's."""
    height = sum(w.radius for w in robot.wheels) / len(robot.wheels)
    # nodes: (name, parent node, origin, joint (kind, axis, anchor) or None, mass, com, diag)
    nodes: list[tuple[str, int, np.ndarray, tuple[str, np.ndarray, np.ndarray] | None,
                      float, np.ndarray, np.ndarray]] = []
    index: dict[str, int] = {}
    armature: dict[int, float] = {}
    origins = body_origins(robot)
    ez, ey = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    for body in robot.bodies:
        o = np.array([*origins[body.name], 0.0])
        eb = engine_body(robot, body)
        side = 0.6 * eb.yaw_inertia
        joint: tuple[str, np.ndarray, np.ndarray] | None
        if body is robot.root:
            parent, joint = -1, ("free", ez, o)
        else:
            j = robot.joint_of(body.name)
            parent = index[j.parent]
            joint = ("hinge", ez, o + np.array([*j.child_point, 0.0]))
        index[body.name] = len(nodes)
        nodes.append((body.name, parent, o, joint, eb.mass, o + np.array([*eb.com, height]),
                      np.array([side, side, eb.yaw_inertia])))
        if body is robot.root:
            tiny = PAYLOAD_PLACEHOLDER_MASS
            for px, py in contact.payloads:
                c = o + np.array([px, py, height])
                nodes.append(("payload", index[body.name], c, None, tiny, c,
                              np.full(3, tiny)))
        for w in robot.wheels:
            if w.body != body.name:
                continue
            mass, diameter, spin = wheel_body_inertia(robot, w)
            c = o + np.array([*w.position, w.radius])
            armature[len(nodes)] = max(w.spin_inertia - spin, 0.0)
            nodes.append((f"wheel_{w.name}", index[body.name], c, ("hinge", ey, c), mass, c,
                          np.array([diameter, spin, diameter])))
    # the degrees of freedom: (owner node, kind, axis, anchor)
    dofs: list[tuple[int, str, np.ndarray, np.ndarray]] = []
    for n, (_, _, _, joint, _, _, _) in enumerate(nodes):
        if joint is None:
            continue
        kind, axis, anchor = joint
        if kind == "free":
            dofs += [(n, "slide", e, anchor) for e in np.eye(3)]
            dofs += [(n, "hinge", e, anchor) for e in np.eye(3)]
        else:
            dofs.append((n, "hinge", axis, anchor))

    def ancestors(n: int) -> set[int]:
        out = set()
        while n >= 0:
            out.add(n)
            n = nodes[n][1]
        return out

    def jacobian(n: int, point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        up = ancestors(n)
        jp, jr = np.zeros((3, len(dofs))), np.zeros((3, len(dofs)))
        for k, (owner, kind, axis, anchor) in enumerate(dofs):
            if owner in up:
                if kind == "slide":
                    jp[:, k] = axis
                else:
                    jp[:, k], jr[:, k] = np.cross(axis, point - anchor), axis
        return jp, jr

    mass_matrix = np.zeros((len(dofs), len(dofs)))
    for n, (_, _, _, _, mass, com, diag) in enumerate(nodes):
        jp, jr = jacobian(n, com)
        mass_matrix += mass * jp.T @ jp + jr.T @ np.diag(diag) @ jr
    for k, (owner, kind, _, _) in enumerate(dofs):
        if kind == "hinge" and owner in armature:
            mass_matrix[k, k] += armature[owner]
    inverse = np.linalg.inv(mass_matrix)
    out = {}
    for n, (name, _, _, _, _, com, _) in enumerate(nodes):
        if name != "payload":
            jp, _ = jacobian(n, com)
            out[name] = float(np.trace(jp @ inverse @ jp.T)) / 3
    return out


def contact_time_constants(robot: PlanarRobot, contact: ContactSettings = ContactSettings()
                           ) -> dict[str, float]:
    """The ``solref`` time constant of each contact geom (``tyre_<wheel>``, the supports)
    that makes every support the same spring, as ``modeling.contact_loads`` assumes.
    MuJoCo's contact at rest is a spring of stiffness d k / ((1 − d) A) per contact point,
    k = 1/(d_max τ ζ)² from ``solref`` = (τ, ζ) and A the contact body's inverse weight
    (:func:`engine_inverse_weights`; the ground's is 0): so τ² A / n (n contact points of
    the geom: 2 for a capsule tyre, else 1) is made equal across geoms; the geom of the
    largest A / n keeps the experiment's ``contact_timeconst``, every other one is
    slower by √ of the ratio (never faster than the experiment's)."""
    weights = engine_inverse_weights(robot, contact)
    points = 2.0 if contact.tyre_width > 0 else 1.0
    per = {f"tyre_{w.name}": points / weights[f"wheel_{w.name}"] for w in robot.wheels}
    for support in robot_supports(robot):
        per[support.name] = 1.0 / weights[support.body]
    least = min(per.values())
    return {k: contact.contact_timeconst * math.sqrt(v / least) for k, v in per.items()}


def _f(x: float) -> str:
    return repr(float(x))


def _v(*xs: float) -> str:
    return " ".join(_f(x) for x in xs)


def mjcf(robot: PlanarRobot, contact: ContactSettings = ContactSettings()) -> str:
    """The MJCF text of ``robot`` (see the module docstring)."""
    if contact.friction < 0 or contact.tyre_width < 0 or contact.contact_timeconst <= 0:
        raise ValueError("contact settings: friction and tyre_width must be >= 0 and "
                         "contact_timeconst > 0")
    height = sum(w.radius for w in robot.wheels) / len(robot.wheels)
    root = ET.Element("mujoco", model=robot.name)
    ET.SubElement(root, "compiler", angle="radian", inertiafromgeom="false",
                  autolimits="true")
    ET.SubElement(root, "option", timestep=_f(contact.timestep), gravity=_v(0, 0, -GRAVITY),
                  integrator="implicitfast", cone="elliptic", impratio="10")
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", contype="0", conaffinity="0", group="1",
                  rgba="0.6 0.6 0.7 0.5")
    world = ET.SubElement(root, "worldbody")
    solref = _v(contact.contact_timeconst, contact.contact_dampratio)
    timeconst = contact_time_constants(robot, contact)
    stands = robot_supports(robot)
    mu = _v(contact.friction, 0.0, 0.0)
    ET.SubElement(world, "geom", name="ground", type="plane", size="0 0 1", contype="1",
                  conaffinity="1", condim="3", friction=mu, solref=solref, group="0",
                  rgba="0.8 0.8 0.8 1")
    elements: dict[str, ET.Element] = {}
    for body in robot.bodies:
        if body is robot.root:
            parent, pos = world, (0.0, 0.0)
        else:
            j = robot.joint_of(body.name)
            parent = elements[j.parent]
            pos = (j.parent_point[0] - j.child_point[0], j.parent_point[1] - j.child_point[1])
        el = ET.SubElement(parent, "body", name=body.name, pos=_v(*pos, 0.0))
        elements[body.name] = el
        if body is robot.root:
            ET.SubElement(el, "freejoint", name="root")
        else:
            j = robot.joint_of(body.name)
            ET.SubElement(el, "joint", name=f"hitch_{body.name}", type="hinge", axis="0 0 1",
                          pos=_v(*j.child_point, 0.0))
        eb = engine_body(robot, body)
        side = 0.6 * eb.yaw_inertia  # out of plane: roll and pitch inertia, not planar
        ET.SubElement(el, "inertial", pos=_v(*eb.com, height), mass=_f(eb.mass),
                      diaginertia=_v(side, side, eb.yaw_inertia))
        own = [w for w in robot.wheels if w.body == body.name]
        xs = [w.position[0] for w in own] + [body.com[0]]
        ys = [w.position[1] for w in own] + [body.com[1]]
        ET.SubElement(el, "geom", name=f"{body.name}_shape", type="box",
                      pos=_v((max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2, height),
                      size=_v(max((max(xs) - min(xs)) / 2, 0.02),
                              max((max(ys) - min(ys)) / 2, 0.02), 0.02), mass="0")
        for support in (s for s in stands if s.body == body.name):
            ET.SubElement(el, "geom", name=support.name, type="sphere",
                          size=_f(support.radius), pos=_v(*support.position, support.radius),
                          contype="1", conaffinity="1", condim="1", priority="1", mass="0",
                          solref=_v(timeconst[support.name], contact.contact_dampratio))
        if body is robot.root:
            for i, (px, py) in enumerate(contact.payloads):
                pl = ET.SubElement(el, "body", name=f"payload_{i}", pos=_v(px, py, height))
                tiny = PAYLOAD_PLACEHOLDER_MASS
                ET.SubElement(pl, "inertial", pos="0 0 0", mass=_f(tiny),
                              diaginertia=_v(tiny, tiny, tiny))
        for w in own:
            _wheel(el, robot, w, contact,
                   _v(timeconst[f"tyre_{w.name}"], contact.contact_dampratio))
    actuators = ET.SubElement(root, "actuator")
    for w in robot.ordered_wheels():
        if not w.driven:
            continue
        attrs = {"name": f"motor_{w.name}", "joint": f"wheel_{w.name}", "gear": "1"}
        if math.isfinite(contact.tau_max):
            attrs["ctrlrange"] = _v(-contact.tau_max, contact.tau_max)
        ET.SubElement(actuators, "motor", attrs)
    ET.indent(root)
    header = (f"<!-- {robot.name}: generated by wmr-toolchain (wmr mjcf) from the robot's "
              "description; planar inertias equal to the derived model's M(q). -->\n")
    return header + ET.tostring(root, encoding="unicode") + "\n"


def _wheel(parent: ET.Element, robot: PlanarRobot, w: PlanarWheel, contact: ContactSettings,
           solref: str) -> None:
    mass, diameter, spin = wheel_body_inertia(robot, w)
    el = ET.SubElement(parent, "body", name=f"wheel_{w.name}", pos=_v(*w.position, w.radius))
    joint = {"name": f"wheel_{w.name}", "type": "hinge", "axis": "0 1 0",
             "armature": _f(max(w.spin_inertia - spin, 0.0))}
    if w.driven:
        joint["damping"] = _f(contact.viscous)
        joint["frictionloss"] = _f(contact.coulomb)
    ET.SubElement(el, "joint", joint)
    ET.SubElement(el, "inertial", pos="0 0 0", mass=_f(mass),
                  diaginertia=_v(diameter, spin, diameter))
    tyre = {"name": f"tyre_{w.name}", "contype": "1", "conaffinity": "1", "condim": "3",
            "priority": "1", "friction": _v(contact.friction, 0.0, 0.0), "solref": solref,
            "group": "0", "rgba": "0.1 0.1 0.1 1", "mass": "0"}
    if contact.tyre_width > 0:
        half = contact.tyre_width / 2
        shape = {"type": "capsule", "fromto": _v(0, -half, 0, 0, half, 0)}
    else:
        shape = {"type": "sphere"}
    ET.SubElement(el, "geom", {**shape, "size": _f(w.radius), **tyre})
