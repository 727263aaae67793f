"""From a 3D mechanism (URDF/MJCF) to a planar bodies-and-wheels robot, with provenance.

1. Every link is placed in the file's world frame at zero joint positions.
2. Joints are classified. A continuous/revolute joint with a horizontal axis whose child
   carries a collision cylinder along that axis is a **wheel** (a continuous one without
   such a cylinder is refused: its radius is unknown). A revolute joint about the vertical
   whose subtree has wheels joins two **bodies**: a trailer on its hitch, or a swivel
   caster's fork with its wheel at a trail offset. Fixed joints merge links into one rigid
   body; any other joint without wheels below it (an arm, a lift, a head) is **frozen** at
   its zero position and merged, with a note; one with wheels below it is refused.
3. Each rigid body's links are composed in 3D (``geometry.compose``: each link's tensor
   rotated into the world frame by the joints' and inertials' origins, parallel-axis
   theorem to the common centre of mass), then **projected on the plane**: the mass, the
   (x, y) of the centre of mass in the body frame and the yaw inertia I_zz about the
   vertical through the centre of mass are kept; the centre of mass height, the roll/pitch
   moments and the products of inertia are dropped (they do no work in planar motion on
   flat ground).
4. Body frames: the root body's frame is the root link's (projected on the ground); a child
   body's origin is its joint's axis. Each frame's yaw puts the body's wheel axles along its
   y axis, x forward (the format's fixed standard wheel), the link's own heading if it has
   no wheels.
5. Wheels: centre and radius from the collision cylinder, spin inertia aᵀ I a about the axle
   a and diameter inertia zᵀ I z about the vertical, from the wheel link's tensor rotated
   into the world frame and taken about the wheel's centre; if the tensor's symmetry axis
   is not the axle (a file that put the spin moment on another axis), its symmetric moment
   is the spin inertia, with a finding.

The result (:class:`PlanarRobot`) carries a comment for every value and the findings; the
audit of ``modeling.audit`` runs on the file written from it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from modeling.audit import Rotor
from modeling.importers import checks
from modeling.importers.geometry import (
    UP,
    Frame,
    Inertial,
    Vec,
    compose,
    lowest_point,
    yaw_of,
)
from modeling.importers.mechanism import Geom, Joint, Link, Mechanism

LEVEL = math.sin(math.radians(2.0))  # a horizontal axis: |a · z| below this
PLUMB = math.cos(math.radians(2.0))  # a vertical axis: |a · z| above this
ALIGNED = math.cos(math.radians(2.0))  # a cylinder along its joint's axis
GROUND_TOLERANCE = 1e-3  # m, or 2 % of the radius, whichever is larger
GROUND_REFUSE = 0.25  # × radius: a wheel this far off the ground is refused
SUPPORT_GAP = 3e-3  # m: a collision shape this close to the ground is a support


def _g(x: float) -> str:
    return f"{x:.4g}"


def _source(link: Link) -> str:
    """Where a link's inertial came from."""
    if link.inertial_label:
        return f"{link.label}, from {link.inertial_label}"
    return f"<inertial> of {link.label}"


def _vec(v: Sequence[float] | Vec) -> str:
    return "(" + ", ".join(f"{0.0 if abs(x) < 5e-13 else x:.4g}" for x in v) + ")"


@dataclass
class PlanarBody:
    name: str
    mass: float
    yaw_inertia: float
    com: tuple[float, float]
    links: list[str]
    notes: dict[str, str] = field(default_factory=dict)  # field -> provenance


@dataclass
class PlanarJoint:
    name: str
    parent: str
    child: str
    parent_point: tuple[float, float]
    child_point: tuple[float, float]
    notes: dict[str, str] = field(default_factory=dict)


@dataclass
class PlanarWheel:
    name: str
    body: str
    position: tuple[float, float]
    radius: float
    spin_inertia: float
    diameter_inertia: float
    mass: float
    driven: bool
    joint: str
    rotor: Rotor | None = None
    gear_ratio_only: float | None = None  # a gear ratio the file gives without J_r
    notes: dict[str, str] = field(default_factory=dict)


@dataclass
class PlanarRobot:
    """A robot ready to be written as a bodies-and-wheels file (``writer``)."""

    name: str
    source: str
    fmt: str
    bodies: list[PlanarBody]
    joints: list[PlanarJoint]
    wheels: list[PlanarWheel]
    header: list[str]  # what was merged, dropped, frozen, projected (comment lines)
    findings: list[str]  # warnings for the [import] table (and MODEL.md)


@dataclass(frozen=True)
class Options:
    """What the command line adds: driven wheels (joint, link or wheel names), a robot
    name, and the motor (rotor inertia J_r, gear ratio N) of every driven wheel."""

    driven: tuple[str, ...] = ()
    name: str = ""
    rotor_inertia: float | None = None
    gear_ratio: float | None = None


def identifier(name: str) -> str:
    """A coordinate-safe name: ``wheel_left_link`` → ``wheel_left``."""
    ident = re.sub(r"\W+", "_", name).strip("_")
    ident = re.sub(r"_link$", "", ident) or ident or "part"
    return f"n_{ident}" if ident[0].isdigit() else ident


@dataclass
class _Group:
    top: str  # the link whose parent joint starts the group (the root for the root group)
    links: list[str]
    kind: str  # "root", "body" or "wheel"
    joint: Joint | None  # the joint above ``top``


class _Builder:
    def __init__(self, mech: Mechanism, options: Options) -> None:
        self.mech = mech
        self.options = options
        self.findings: list[str] = []
        self.header: list[str] = []
        self.world: dict[str, Frame] = {}
        self._place(mech.root, mech.root_frame)

    def _place(self, link: str, frame: Frame) -> None:
        self.world[link] = frame
        for j in self.mech.children(link):
            self._place(j.child, frame.compose(j.frame))

    def fail(self, message: str) -> Exception:
        return self.mech.fail(message)

    # ----------------------------------------------------------------- classification
    def axis_world(self, j: Joint) -> Vec:
        return self.world[j.child].vector(j.axis)

    def _fixed_below(self, link: str) -> list[str]:
        out = [link]
        for j in self.mech.children(link):
            if j.kind == "fixed":
                out += self._fixed_below(j.child)
        return out

    def wheel_cylinder(self, j: Joint) -> tuple[Geom, Frame] | None:
        """The collision cylinder of a wheel joint's child (or its fixed children) along the
        joint's axis; refuse a cylinder across it."""
        axis = self.axis_world(j)
        across: tuple[Geom, float] | None = None
        for link in self._fixed_below(j.child):
            for g in self.mech.links[link].geoms:
                if g.kind != "cylinder":
                    continue
                frame = self.world[link].compose(g.frame)
                cos = abs(float(frame.rotation[:, 2] @ axis))
                if cos >= ALIGNED:
                    return g, frame
                across = (g, cos)
        if across is not None:
            g, cos = across
            angle = math.degrees(math.acos(min(1.0, cos)))
            raise self.fail(
                f"{j.label}: its axis {_vec(j.axis)} (in {self.mech.links[j.child].label}; "
                f"{_vec(axis)} in the world) is at {angle:.1f}° to the axis of {g.label}: a "
                "wheel spins about its cylinder's axis; fix the joint axis or the cylinder's "
                "origin rpy")
        return None

    def classify(self) -> dict[str, str]:
        """Joint name → "fixed", "wheel", "body", "frozen", "floating"."""
        kinds: dict[str, str] = {}
        for j in self.mech.joints:
            if j.kind == "fixed":
                kinds[j.name] = "fixed"
            elif j.kind in ("floating", "planar"):
                kinds[j.name] = "floating"
            elif (j.kind in ("revolute", "continuous")
                  and abs(float(self.axis_world(j) @ UP)) < LEVEL):
                if self.wheel_cylinder(j) is not None:
                    kinds[j.name] = "wheel"
                elif j.kind == "continuous" and j.name in self.mech.driven:
                    raise self.fail(
                        f"{j.label} (continuous, horizontal axis, driven): its child "
                        f"{self.mech.links[j.child].label} has no collision cylinder, so the "
                        "wheel's radius is unknown; give it a collision cylinder along the "
                        "joint axis")
                elif j.kind == "continuous":
                    self.findings.append(
                        f"{j.label} (continuous, horizontal axis) has no collision cylinder "
                        "on its child: not taken as a wheel (frozen at zero); if it is one, "
                        "give it a collision cylinder along the joint axis")
        wheel_links = {j.child for j in self.mech.joints if kinds.get(j.name) == "wheel"}
        for j in self.mech.joints:
            if j.name in kinds:
                continue
            below = set(self.mech.subtree(j.child))
            carries = bool(below & wheel_links)
            vertical = abs(float(self.axis_world(j) @ UP)) > PLUMB
            if j.kind in ("revolute", "continuous") and vertical and carries:
                kinds[j.name] = "body"
            elif carries:
                raise self.fail(
                    f"{j.label} ({j.kind}, axis {_vec(self.axis_world(j))} in the world) "
                    "carries wheels: only revolute joints about the vertical (hitches, caster "
                    "swivels) may, on a planar robot; a suspension or steering linkage is "
                    "not supported")
            else:
                kinds[j.name] = "frozen"
                self.header.append(
                    f"frozen at zero: {j.label} ({j.kind}), no wheel below it; its links "
                    "are merged into the body above")
        for j in self.mech.joints:
            if kinds[j.name] == "floating" and j.parent != self.mech.root:
                raise self.fail(f"{j.label} ({j.kind}) is not at the root: not supported")
        return kinds

    # ----------------------------------------------------------------- groups
    def groups(self, kinds: dict[str, str]) -> list[_Group]:
        out: list[_Group] = []

        def walk(link: str, group: _Group) -> None:
            group.links.append(link)
            for j in self.mech.children(link):
                kind = kinds[j.name]
                if kind in ("fixed", "frozen", "floating"):
                    walk(j.child, group)
                else:
                    if group.kind == "wheel":
                        raise self.fail(f"{j.label}: a {kind} below the wheel of "
                                        f"'{group.top}' is not supported")
                    new = _Group(j.child, [], kind, j)
                    out.append(new)
                    walk(j.child, new)

        root = _Group(self.mech.root, [], "root", None)
        out.append(root)
        walk(self.mech.root, root)
        return out

    def inertial(self, group: _Group) -> tuple[Inertial, list[tuple[str, Inertial]]]:
        """The group's composed inertial in the world frame, and its parts."""
        parts = []
        for name in group.links:
            link = self.mech.links[name]
            if link.inertial is not None and link.inertial.mass > 0:
                parts.append((name, link.inertial.moved(self.world[name])))
        return compose(p for _, p in parts), parts

    # ----------------------------------------------------------------- 3D audit
    def audit_links(self) -> None:
        for link in self.mech.links.values():
            if link.inertial is None:
                meshes = [g.label for g in link.geoms if g.kind == "mesh"]
                if meshes:
                    self.findings.append(
                        f"{link.label}: a mesh without inertia ({meshes[0]} is a mesh, and "
                        "the link has no <inertial>): imported massless; its mass is not in "
                        "the file, and a mesh file gives a shape, not a mass")
                continue
            where = f"{link.label} ({link.inertial_label})" if link.inertial_label else link.label
            self.findings += checks.check_tensor(self.mech.path, where, link.inertial)
            shapes = [(g, g.frame) for g in link.geoms]
            for found in (checks.check_geometry(where, link.inertial, shapes),
                          checks.check_default_origin(where, link.inertial, shapes)):
                if found:
                    self.findings.append(found)

    # ----------------------------------------------------------------- names
    def names(self, groups: list[_Group]) -> dict[str, str]:
        used: set[str] = set()
        out: dict[str, str] = {}
        for g in groups:
            links = [self.mech.links[n] for n in g.links]
            massive = [lk for lk in links if lk.inertial is not None and lk.inertial.mass > 0]
            top = self.mech.links[g.top]
            # A ground frame (base_footprint) names no body: the heaviest link does.
            frame_only = top not in massive and ("footprint" in top.name or top.name == "world")
            base = top if not (frame_only and massive) else max(
                massive, key=lambda lk: lk.inertial.mass if lk.inertial else 0.0)
            name = identifier(base.name)
            candidate, k = name, 2
            while candidate in used:
                candidate, k = f"{name}_{k}", k + 1
            used.add(candidate)
            out[g.top] = candidate
        return out


def _heading(frame: Frame) -> Vec:
    """A link frame's forward direction on the ground: its x axis projected (its y axis
    turned by −90° if x points up or down)."""
    x = frame.rotation[:, 0].copy()
    x[2] = 0.0
    if np.linalg.norm(x) < 0.1:
        y = frame.rotation[:, 1]
        x = np.array([y[1], -y[0], 0.0])
    return x / np.linalg.norm(x)


@dataclass
class _Plan:
    """The groups of a mechanism and where they are: what ``build``'s steps share."""

    b: _Builder
    groups: list[_Group]
    names: dict[str, str]  # top link -> body or wheel name
    group_of: dict[str, _Group]
    cylinders: dict[str, tuple[Geom, Frame]]  # wheel group top -> cylinder, world pose
    ground: float = 0.0
    ground_text: str = ""
    frames: dict[str, tuple[Vec, float]] = field(default_factory=dict)  # origin xy, yaw
    massless: list[str] = field(default_factory=list)

    @property
    def bodies(self) -> list[_Group]:
        return [g for g in self.groups if g.kind != "wheel"]

    @property
    def wheels(self) -> list[_Group]:
        return [g for g in self.groups if g.kind == "wheel"]

    def parent_group(self, g: _Group) -> _Group:
        assert g.joint is not None
        return self.group_of[g.joint.parent]

    def local(self, top: str, p: Vec) -> tuple[float, float]:
        """A world point in the planar frame of the body whose top link is ``top``."""
        origin, yaw = self.frames[top]
        d = p[:2] - origin
        c, s = math.cos(yaw), math.sin(yaw)
        x, y = c * d[0] + s * d[1], -s * d[0] + c * d[1]
        return (0.0 if abs(x) < 1e-12 else float(x), 0.0 if abs(y) < 1e-12 else float(y))


def _ground(plan: _Plan) -> None:
    mech, b = plan.b.mech, plan.b
    if mech.ground is not None:
        plan.ground = mech.ground
        plan.ground_text = f"z = {_g(mech.ground)} m, the {mech.ground_source}"
    elif mech.ground_link:
        plan.ground = float(b.world[mech.ground_link].origin[2])
        plan.ground_text = f"z = {_g(plan.ground)} m, {mech.ground_source}"
    else:
        plan.ground = min(float(f.origin[2]) - geom.size[0] for geom, f in plan.cylinders.values())
        plan.ground_text = (f"z = {_g(plan.ground)} m, through the lowest wheel (the file names "
                            "no ground frame)")


def _frames(plan: _Plan) -> None:
    """Each body's planar frame (module docstring, step 4)."""
    b = plan.b
    for body in plan.bodies:
        ref = b.world[body.top]
        anchor = body.joint.anchor if body.joint is not None else np.zeros(3)
        origin = ref.point(anchor)[:2].copy()
        forward = _heading(ref)
        yaw = yaw_of(forward)
        own = [w.joint for w in plan.wheels if plan.parent_group(w) is body]
        if own:
            axles = [b.axis_world(j) for j in own if j is not None]
            first = axles[0] / np.linalg.norm(axles[0][:2])
            for joint, a in zip(own, axles, strict=True):
                skew = abs(float(first[0] * a[1] - first[1] * a[0])) / float(
                    np.linalg.norm(a[:2]))
                if skew > math.sin(math.radians(2.0)):
                    label = joint.label if joint is not None else ""
                    raise b.fail(
                        f"the wheels of body '{plan.names[body.top]}' have axles that are not "
                        f"parallel ({label} at {math.degrees(math.asin(min(1.0, skew))):.1f}°): "
                        "only fixed wheels with parallel axles on one body are supported; put "
                        "a steered wheel on its own revolute joint (a caster fork)")
            roll = np.cross(first, UP)
            if float(roll @ forward) < 0:
                roll = -roll
            wheel_yaw = yaw_of(roll)
            turn = (wheel_yaw - yaw + math.pi) % (2 * math.pi) - math.pi
            if abs(turn) > math.radians(0.5):
                b.header.append(f"body frame of '{plan.names[body.top]}' turned by "
                                f"{math.degrees(turn):.1f}° from {b.mech.links[body.top].label} "
                                "so that its wheels' axles lie along its y axis")
            yaw = wheel_yaw
        plan.frames[body.top] = (origin, yaw)


def _bodies(plan: _Plan) -> list[PlanarBody]:
    """Each body composed in 3D and projected (module docstring, step 3)."""
    b, mech = plan.b, plan.b.mech
    out = []
    for group in plan.bodies:
        inertial, parts = b.inertial(group)
        plan.massless += [n for n in group.links if n not in dict(parts)]
        name = plan.names[group.top]
        if inertial.mass <= 0:
            raise b.fail(f"body '{name}' (links {', '.join(group.links)}) has no mass: a "
                         f"{'robot base' if group.joint is None else 'body on a revolute joint'}"
                         " needs an <inertial>")
        body = PlanarBody(name, inertial.mass, float(inertial.tensor[2, 2]),
                          plan.local(group.top, inertial.com), group.links)
        merged = [n for n, _ in parts]
        inner = [j.name for j in mech.joints if j.child in group.links and j.child != group.top]
        body.notes["name"] = (mech.links[merged[0]].label if len(group.links) == 1 else
                              f"links {', '.join(group.links)} (fixed joints "
                              f"{', '.join(inner) or 'none'})")
        if len(parts) == 1:
            link = mech.links[merged[0]]
            body.notes["mass"] = f"kg, {_source(link)}"
            body.notes["yaw_inertia"] = (f"kg m^2, I_zz of {link.label} about the vertical "
                                         "through its CoM (tensor rotated into the world frame)")
        else:
            body.notes["mass"] = "kg, composed: " + " + ".join(
                f"{n} {_g(p.mass)}" for n, p in parts)
            body.notes["yaw_inertia"] = (f"kg m^2, I_zz about the vertical through the composed "
                                         f"CoM: {len(parts)} link tensors rotated into the "
                                         "world frame + parallel-axis m d^2")
        body.notes["com"] = (f"m, CoM (x, y) in the body frame; its height z = "
                             f"{_g(float(inertial.com[2]) - plan.ground)} m above the ground "
                             "dropped")
        out.append(body)
        # What a placeholder does to the body: its share of the yaw inertia.
        for n, p in parts:
            label = mech.links[n].label
            if len(parts) > 1 and any(label in f and "placeholder" in f for f in b.findings):
                share = float(p.about(inertial.com)[2, 2]) / max(body.yaw_inertia, 1e-300)
                b.findings.append(
                    f"{label} contributes {100 * share:.0f} % of the yaw inertia of body "
                    f"'{name}', {_g(body.yaw_inertia)} kg m^2 ({_g(float(p.tensor[2, 2]))} of "
                    "it its own placeholder moment)")
    return out


def _joints(plan: _Plan) -> list[PlanarJoint]:
    b = plan.b
    out = []
    for group in plan.bodies:
        if group.joint is None:
            continue
        j = group.joint
        parent_top = plan.parent_group(group).top
        point = b.world[group.top].point(j.anchor)
        pj = PlanarJoint(j.name, plan.names[parent_top], plan.names[group.top],
                         plan.local(parent_top, point), plan.local(group.top, point))
        wheels_on = [w for w in plan.wheels if plan.parent_group(w) is group]
        bodies_on = [x for x in plan.bodies if x.joint is not None
                     and plan.parent_group(x) is group]
        kind = "caster swivel" if len(wheels_on) == 1 and not bodies_on else "hitch"
        pj.notes["kind"] = f"{j.label} ({j.kind}, vertical axis): a {kind}"
        pj.notes["parent_point"] = f"m, the joint axis in the frame of '{pj.parent}'"
        pj.notes["child_point"] = f"m, the frame of '{pj.child}' has its origin there"
        out.append(pj)
    return out


def _wheel(plan: _Plan, group: _Group) -> PlanarWheel:
    """One wheel (module docstring, step 5), with the ground check."""
    b, mech = plan.b, plan.b.mech
    j = group.joint
    assert j is not None
    geom, cylinder = plan.cylinders[group.top]
    radius, width = geom.size
    inertial, parts = b.inertial(group)
    plan.massless += [n for n in group.links if n not in dict(parts)]
    centre = cylinder.origin
    axle = b.axis_world(j)
    body_top = plan.parent_group(group).top
    name = plan.names[group.top]
    link = mech.links[group.top]
    note: dict[str, str] = {}
    label = f"wheel '{name}' ({j.label}, {link.label})"
    spin = diameter = 0.0
    if inertial.mass > 0:
        about = inertial.about(centre)
        spin, diameter = float(axle @ about @ axle), float(UP @ about @ UP)
        offset = float(np.linalg.norm(inertial.com - centre))
        if offset > checks.OFF_AXLE:
            b.findings.append(f"{label}: its centre of mass is {1000 * offset:.1f} mm from the "
                              "centre of its cylinder (an unbalanced wheel): the inertias are "
                              "taken about the centre, where the format puts its mass")
        odd = checks.wheel_axis(inertial, axle)
        note["spin"] = (f"kg m^2, a^T I a about the axle a (joint axis {_vec(j.axis)} in "
                        f"{link.label}), about the wheel centre")
        note["diameter"] = "kg m^2, z^T I z about the vertical through the centre"
        if odd is not None:
            spin_sym, diameter_sym, sym_axis = odd
            in_link = b.world[group.top].rotation.T @ sym_axis
            letter = "xyz"[int(np.argmax(np.abs(in_link)))]
            extra = about - inertial.tensor  # the parallel-axis part, if off-centre
            corrected = spin_sym + float(axle @ extra @ axle)
            low = 100 * (1 - spin / corrected)
            b.findings.append(
                f"{label}: the spin inertia is on the wrong axis: the tensor's symmetric "
                f"moment {_g(spin_sym)} kg m^2 is about the link's {letter} axis, but the "
                f"wheel spins about its joint axis {_vec(j.axis)} (its collision cylinder "
                f"agrees), about which the tensor gives {_g(spin)} kg m^2: a naive import is "
                f"{abs(low):.0f} % {'low' if low > 0 else 'high'}; imported: spin_inertia = "
                f"{_g(corrected)}, diameter_inertia = {_g(diameter_sym)} (the other moments)")
            spin, diameter = corrected, diameter_sym + float(UP @ extra @ UP)
            note["spin"] = ("kg m^2, the tensor's symmetric moment (the file put it on the "
                            f"link's {letter} axis, not the axle: see the findings)")
            note["diameter"] = "kg m^2, the mean of the tensor's other two moments"
        note["mass"] = ("kg, " + _source(mech.links[parts[0][0]]) if len(parts) == 1 else
                        "kg, composed: " + " + ".join(f"{n} {_g(p.mass)}" for n, p in parts))
    else:
        note["spin"] = note["diameter"] = "kg m^2, the wheel has no <inertial>"
        note["mass"] = "kg, the wheel has no <inertial>"
        b.findings.append(f"{label}: no <inertial>: a massless wheel (its mass and inertias "
                          "are 0)")
    _, yaw = plan.frames[body_top]
    rolls_forward = float(np.cross(axle, UP)[:2] @ np.array([math.cos(yaw), math.sin(yaw)])) > 0
    height = float(centre[2]) - radius - plan.ground
    if abs(height) > GROUND_REFUSE * radius:
        raise b.fail(
            f"{label}: its lowest point is {1000 * abs(height):.1f} mm "
            f"{'above' if height > 0 else 'below'} the ground plane ({plan.ground_text}): its "
            f"centre is at height {_g(float(centre[2]) - plan.ground)} m for a radius of "
            f"{_g(radius)} m; a wheel off the ground does not roll, so its constraints would be "
            "wrong (check the joint origin's z and the cylinder's radius)")
    if abs(height) > max(GROUND_TOLERANCE, 0.02 * radius):
        b.findings.append(
            f"{label}: not on the ground plane ({plan.ground_text}): centre height "
            f"{_g(float(centre[2]) - plan.ground)} m ≠ radius {_g(radius)} m (lowest point "
            f"{1000 * height:+.1f} mm)")
    note["name"] = (f"{j.label} ({j.kind}), {link.label}; positive joint rotation rolls "
                    f"{'forward' if rolls_forward else 'backward: θ = −(joint angle)'}")
    note["position"] = (f"m, centre of {geom.label} in the frame of '{plan.names[body_top]}' "
                        f"(height {_g(float(centre[2]) - plan.ground)} m)")
    note["radius"] = f"m, cylinder radius of {geom.label} (width {_g(width)} m)"
    return PlanarWheel(name, plan.names[body_top], plan.local(body_top, centre), radius, spin,
                       diameter, inertial.mass, False, j.name, notes=note)


def _drive(plan: _Plan, wheels: list[PlanarWheel]) -> list[PlanarWheel]:
    """Mark the driven wheels (the command line's, else the file's) and their motors;
    driven wheels first, in that order."""
    b, mech, options = plan.b, plan.b.mech, plan.b.options
    by_key: dict[str, PlanarWheel] = {}
    for w, group in zip(wheels, plan.wheels, strict=True):
        by_key.update({w.joint: w, group.top: w, w.name: w})
    given = [d.strip() for d in options.driven if d.strip()]
    order: list[tuple[PlanarWheel, str]] = []
    if given:
        for key in given:
            if key not in by_key:
                raise b.fail(f"--driven {key}: no wheel, wheel joint or wheel link of that "
                             f"name (wheels: {', '.join(w.name for w in wheels)})")
            order.append((by_key[key], "--driven on the command line"))
    else:
        order = [(by_key[j], mech.driven_source[j]) for j in mech.driven if j in by_key]
        ignored = [j for j in mech.driven if j not in by_key]
        if ignored:
            b.header.append(f"actuated joints that are not wheels (ignored): "
                            f"{', '.join(ignored)}")
    base = [w for w in wheels if w.body == plan.names[mech.root]]
    if not order and not mech.driven and not mech.missing_driven and len(base) == 2:
        # A file without actuators (ROBOTIS keeps them in separate Gazebo files): the two
        # wheels of the base are a differential drive's, the only kind that has two.
        source = ("assumed: the file names no actuator, and the base's two wheels are a "
                  "differential drive's")
        order = [(w, source) for w in base]
        b.findings.append(f"driven wheels {base[0].name} and {base[1].name} {source}; name "
                          "others with --driven")
    if not order:
        raise b.fail("no driven wheel: the file has no <transmission>, <ros2_control> joint, "
                     "drive plugin or actuator on a wheel joint; name them with --driven "
                     f"NAME,NAME (wheels: {', '.join(w.name for w in wheels)})")
    if len({id(w) for w, _ in order}) == 1:
        w, source = order[0]
        raise b.fail(f"one driven wheel ('{w.name}', {source}): a planar robot of wheels on "
                     "one axle and casters has two degrees of freedom, driven by two wheels "
                     f"(wheels: {', '.join(x.name for x in wheels)})")
    driven: list[PlanarWheel] = []
    for w, source in order:
        if not w.driven:
            w.driven = True
            w.notes["driven"] = source
            driven.append(w)
    for w in wheels:
        w.notes.setdefault("driven", "passive: no actuator on its joint")
    for w in driven:
        motor = mech.motors.get(w.joint)
        n = options.gear_ratio if options.gear_ratio is not None else (
            motor.gear_ratio if motor else None)
        reflected = motor.reflected_inertia if motor else None
        where = motor.source if motor else ""
        if options.rotor_inertia is not None:
            if n is None:
                raise b.fail("--rotor-inertia needs a gear ratio: give --gear-ratio (the file "
                             f"gives none for joint '{w.joint}')")
            w.rotor = Rotor(options.rotor_inertia, n)
            w.notes["rotor"] = "command line: --rotor-inertia" + (
                " --gear-ratio" if options.gear_ratio is not None else f"; N from {where}")
        elif reflected is not None:
            ratio = n if n is not None else 1.0
            w.rotor = Rotor(reflected / ratio**2, ratio)
            w.notes["rotor"] = (f"{where}: J_r = armature / N^2 (armature = J_r N^2 = "
                                f"{_g(reflected)} kg m^2)")
        elif n is not None:
            w.gear_ratio_only = n
            w.notes["rotor"] = ("command line: --gear-ratio" if options.gear_ratio is not None
                                else where)
    return driven + [w for w in wheels if not w.driven]


def _supports(plan: _Plan) -> list[str]:
    """Collision shapes of bodies that reach the ground without a wheel (ball casters,
    sliders, casters on fixed joints)."""
    out = []
    for group in plan.bodies:
        for name in group.links:
            for geom in plan.b.mech.links[name].geoms:
                if geom.kind in ("mesh", "plane"):
                    continue
                low = lowest_point(geom.kind, geom.size, plan.b.world[name].compose(geom.frame))
                if abs(low - plan.ground) < SUPPORT_GAP:
                    out.append(f"{geom.label} ({geom.kind})")
    return out


OMNI_NAMES = re.compile(r"mecanum|omni|swedish", re.IGNORECASE)


def _refuse_omnidirectional(b: _Builder, plan: _Plan) -> None:
    """Mecanum and omni wheels (named so, or on a base a Gazebo planar_move plugin
    drives) roll freely sideways on their rollers: the format's wheels are standard fixed
    wheels, which do not, so such a base would be modelled as a locked skid-steer."""
    named = [g.joint.label for g in plan.wheels if g.joint is not None
             and OMNI_NAMES.search(g.joint.name + " " + g.top)]
    if named or b.mech.omnidirectional:
        what = (f"mecanum/omni wheels ({', '.join(named[:4])})" if named else
                f"an omnidirectional base ({b.mech.omnidirectional} moves it sideways)")
        raise b.fail(f"{what}: the rollers of mecanum and omni wheels let them slip "
                     "sideways, which the format's standard fixed wheels (no side slip) cannot "
                     "model; an omnidirectional base is not supported")


def _why_no_wheels(b: _Builder) -> str:
    """What a file without wheels has instead: continuous joints without a collision
    cylinder (a mesh the importer does not read, or visuals only), or wheel links welded by
    fixed joints."""
    joints = [j for j in b.mech.joints if j.kind == "continuous"]
    if joints:
        j = joints[0]
        kinds = sorted({g.kind for g in b.mech.links[j.child].geoms})
        what = (f"a collision {' and '.join(kinds)}" if kinds else "no collision geometry")
        link = b.mech.links[j.child].label
        # why its mesh gave no cylinder (modeling.importers.meshes), if it has one
        mesh = next((n.removeprefix(f"{link} ") for n in b.mech.notes
                     if n.startswith(f"{link} <collision>")), "")
        return (f"; {j.label} (continuous) has {what} on its child {link} (a wheel needs a "
                "collision cylinder, or a round STL or OBJ collision mesh"
                + (f"; {mesh}" if mesh else "") + ")")
    welded = [j for j in b.mech.joints if j.kind == "fixed" and "wheel" in j.child.lower()]
    if welded:
        return (f"; the file welds its wheels: {', '.join(j.label for j in welded[:4])} "
                "are fixed joints (a wheel on a fixed joint does not turn)")
    return ""


def build(mech: Mechanism, options: Options | None = None) -> PlanarRobot:
    """The planar robot of ``mech`` (module docstring); ``ImportFileError`` naming the
    element when it cannot be one."""
    options = options or Options()
    b = _Builder(mech, options)
    groups = b.groups(b.classify())
    b.audit_links()
    plan = _Plan(b, groups, b.names(groups), {n: g for g in groups for n in g.links}, {})
    if not plan.wheels:
        raise b.fail("no wheels found: a wheel is a continuous or revolute joint with a "
                     "horizontal axis whose child link has a collision cylinder along it"
                     + _why_no_wheels(b))
    _refuse_omnidirectional(b, plan)
    for group in plan.wheels:
        assert group.joint is not None
        found = b.wheel_cylinder(group.joint)
        assert found is not None
        plan.cylinders[group.top] = found
    _ground(plan)
    _frames(plan)
    bodies = _bodies(plan)
    joints = _joints(plan)
    wheels = _drive(plan, [_wheel(plan, g) for g in plan.wheels])
    supports = _supports(plan)

    header = [
        "planar projection: each body keeps its mass, the (x, y) of its centre of mass in "
        "its frame and its yaw inertia about the vertical through its centre of mass; the "
        "centre of mass height, roll/pitch moments and products of inertia are dropped (no "
        "work in planar motion on flat ground). Each wheel keeps its spin inertia about the "
        "axle and its diameter inertia about the vertical, its mass at its centre",
        f"ground plane: {plan.ground_text}",
        "body frames: x forward, y left, z up; the root body's frame is that of "
        f"{mech.links[mech.root].label} on the ground; a body on a revolute joint has its "
        "origin on the joint's axis",
        *b.header,
    ]
    merged = [f"{plan.names[g.top]}: {', '.join(n for n in g.links if n not in plan.massless)}"
              for g in plan.bodies if len(g.links) > 1]
    if merged:
        header.append("rigid bodies merged over fixed joints (MJCF: bodies welded without a "
                      "joint): " + "; ".join(merged))
    if plan.massless:
        header.append("massless frames dropped: " + ", ".join(sorted(set(plan.massless))))
    if mech.dropped:
        header.append("elements without dynamics dropped: " + "; ".join(mech.dropped))
    if supports:
        header.append("supports on the ground without a wheel model (no constraint: treated "
                      "as frictionless, e.g. ball casters or sliders): " + ", ".join(supports))
    header += mech.notes
    return PlanarRobot(options.name or identifier(mech.name), mech.path, mech.fmt, bodies,
                       joints, wheels, header, b.findings)
