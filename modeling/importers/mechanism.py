"""What the URDF and MJCF readers produce: links, joints, geometry and motors, neutral to
the format (``modeling.importers.urdf``, ``modeling.importers.mjcf``), which
``modeling.importers.planar`` turns into a bodies-and-wheels robot.

Every element keeps a ``label`` saying where it came from in the file (``link
'wheel_left_link'``, ``body 'cart'``, ``geom 'tyre' of body 'cart'``), so that comments,
findings and errors name it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from modeling.importers.geometry import IDENTITY_FRAME, Frame, Inertial, Vec
from modeling.robot_io import RobotFileError


class ImportFileError(RobotFileError):
    """A URDF/MJCF file that cannot be imported; the message names the file, the element
    and the value (one line)."""


@dataclass(frozen=True)
class Geom:
    """A collision shape: ``kind`` (box, cylinder, sphere, capsule, ellipsoid, mesh, plane),
    ``size`` as ``modeling.importers.geometry`` defines it, and its pose in its link; a
    mesh's ``source`` (its file name as written) and ``scale`` (its attribute's text: read
    only when the mesh is, ``modeling.importers.meshes``)."""

    kind: str
    size: tuple[float, ...]
    frame: Frame
    label: str
    source: str = ""
    scale: str = ""


@dataclass
class Link:
    """A rigid link: its inertial (``None``: massless, a frame) in the link frame and its
    collision geometry."""

    name: str
    label: str
    inertial: Inertial | None
    geoms: list[Geom] = field(default_factory=list)
    inertial_label: str = ""  # where the inertial came from (e.g. "from its geoms")


@dataclass
class Joint:
    """A joint: ``kind`` fixed, revolute, continuous, prismatic, floating, planar or ball;
    ``frame`` is the child link's frame in the parent's at zero position; ``anchor`` the
    joint's point and ``axis`` its direction, both in the child frame."""

    name: str
    label: str
    kind: str
    parent: str
    child: str
    frame: Frame
    axis: Vec
    anchor: Vec


@dataclass(frozen=True)
class Motor:
    """What the file says about the motor on a joint: the gear ratio N (``None``: not
    given) and the reflected rotor inertia J_r N² (MJCF ``armature``; ``None``: not
    given), with where each came from."""

    gear_ratio: float | None = None
    reflected_inertia: float | None = None
    source: str = ""


@dataclass
class Mechanism:
    """A robot as a tree of links joined by joints, with what the file says is driven.

    ``driven``: joint names with an actuator (transmissions, ros2_control, a drive plugin,
    MJCF actuators), in the file's order; ``motors``: per joint; ``ground``: the ground
    plane's height if the file gives one (an MJCF plane, a URDF footprint frame);
    ``dropped``: elements without dynamics that were left out (sensors, sites, ...), as
    lines for the output's header; ``notes``: other remarks of the reader.
    """

    name: str
    path: str
    fmt: str  # "URDF" or "MJCF"
    root: str
    links: dict[str, Link]
    joints: list[Joint]
    driven: list[str] = field(default_factory=list)
    driven_source: dict[str, str] = field(default_factory=dict)
    missing_driven: list[str] = field(default_factory=list)  # named by actuators, absent
    omnidirectional: str = ""  # what says the base is holonomic (a planar_move plugin)
    motors: dict[str, Motor] = field(default_factory=dict)
    ground: float | None = None  # the ground plane's height (world z), if the file says
    ground_link: str = ""  # ... or a frame on the ground (URDF: a massless *footprint* link)
    ground_source: str = ""
    dropped: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    root_frame: Frame = IDENTITY_FRAME  # the root link's pose in the file's world frame

    def fail(self, message: str) -> ImportFileError:
        return ImportFileError(f"{self.path}: {message}")

    def children(self, link: str) -> list[Joint]:
        return [j for j in self.joints if j.parent == link]

    def parent_joint(self, link: str) -> Joint | None:
        return next((j for j in self.joints if j.child == link), None)

    def subtree(self, link: str) -> list[str]:
        """``link`` and every link below it, depth first in file order."""
        out = [link]
        for j in self.children(link):
            out += self.subtree(j.child)
        return out

    def check_tree(self) -> None:
        """One root, each link one parent, every joint's links declared, no cycle."""
        for j in self.joints:
            for end in ("parent", "child"):
                if getattr(j, end) not in self.links:
                    raise self.fail(f"{j.label}: {end} link '{getattr(j, end)}' is not "
                                    "declared")
        seen: dict[str, str] = {}
        for j in self.joints:
            if j.child in seen:
                raise self.fail(f"{j.label}: link '{j.child}' already has a parent joint "
                                f"('{seen[j.child]}'); closed chains are not supported")
            seen[j.child] = j.name
        if self.root in seen:
            raise self.fail(f"link '{self.root}' cannot be both the root and a child")
        reached = set(self.subtree(self.root))
        loose = [n for n in self.links if n not in reached]
        if loose:
            raise self.fail(f"link '{loose[0]}' is not connected to the root link "
                            f"'{self.root}' by joints")
