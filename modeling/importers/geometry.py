"""Rigid-body geometry for the importers: rotations, frames, composed inertias (NumPy).

Conventions: a rotation matrix R maps a child frame's coordinates into its parent's
(``p_parent = R p_child + t``); an inertia tensor is about the body's centre of mass and
expressed in the frame its owner names. Composition is the textbook one: masses add, the
centre of mass is the mass-weighted mean, and each part's tensor, rotated into the common
frame (R I Rᵀ), is carried to the common centre of mass by the parallel-axis theorem,
I + m (|d|² E − d dᵀ).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Vec = NDArray[np.float64]
Mat = NDArray[np.float64]
IDENTITY: Mat = np.eye(3)
ZERO: Vec = np.zeros(3)
UP: Vec = np.array([0.0, 0.0, 1.0])


def axis_rotation(axis: int, angle: float) -> Mat:
    """Rotation by ``angle`` about coordinate axis 0 (x), 1 (y) or 2 (z)."""
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Mat:
    """URDF's ``rpy``: roll about x, then pitch about y, then yaw about z, all about the
    parent's fixed axes: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return axis_rotation(2, yaw) @ axis_rotation(1, pitch) @ axis_rotation(0, roll)


def quat_matrix(w: float, x: float, y: float, z: float) -> Mat:
    """A unit quaternion (w, x, y, z), normalised first, as a rotation matrix."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if n == 0:
        raise ValueError("a zero quaternion is not a rotation")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def axis_angle_matrix(axis: Sequence[float] | Vec, angle: float) -> Mat:
    """Rotation by ``angle`` about ``axis`` (normalised)."""
    a = np.asarray(axis, dtype=float)
    n = float(np.linalg.norm(a))
    if n == 0:
        raise ValueError("a zero axis is not a rotation axis")
    a = a / n
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def euler_matrix(angles: Sequence[float], sequence: str) -> Mat:
    """MJCF's ``euler`` with ``compiler/eulerseq``: lower-case axes rotate with the frame
    (intrinsic, multiplied on the right), upper-case stay fixed (extrinsic, on the left)."""
    r = np.eye(3)
    for letter, angle in zip(sequence, angles, strict=True):
        step = axis_rotation("xyz".index(letter.lower()), angle)
        r = r @ step if letter.islower() else step @ r
    return r


def frame_from_axes(x_axis: Sequence[float], y_axis: Sequence[float]) -> Mat:
    """MJCF's ``xyaxes``: x normalised, y made orthogonal to it, z = x × y."""
    x = np.asarray(x_axis, dtype=float)
    x = x / np.linalg.norm(x)
    y = np.asarray(y_axis, dtype=float)
    y = y - (y @ x) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def rotation_onto(a: Sequence[float], b: Sequence[float]) -> Mat:
    """The smallest rotation taking direction ``a`` onto ``b`` (MJCF's ``zaxis``,
    ``fromto``)."""
    u = np.asarray(a, dtype=float) / np.linalg.norm(a)
    v = np.asarray(b, dtype=float) / np.linalg.norm(b)
    axis = np.cross(u, v)
    s, c = float(np.linalg.norm(axis)), float(u @ v)
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        other = np.array([1.0, 0, 0]) if abs(u[0]) < 0.9 else np.array([0, 1.0, 0])
        return axis_angle_matrix(np.cross(u, other), math.pi)
    return axis_angle_matrix(axis, math.atan2(s, c))


@dataclass(frozen=True)
class Frame:
    """A pose: ``rotation`` and ``origin`` of a frame in its parent frame."""

    rotation: Mat
    origin: Vec

    def compose(self, child: Frame) -> Frame:
        """The pose of ``child`` (given in this frame) in this frame's parent."""
        return Frame(self.rotation @ child.rotation, self.rotation @ child.origin + self.origin)

    def point(self, p: Sequence[float] | Vec) -> Vec:
        return self.rotation @ np.asarray(p, dtype=float) + self.origin

    def vector(self, v: Sequence[float] | Vec) -> Vec:
        return self.rotation @ np.asarray(v, dtype=float)


IDENTITY_FRAME = Frame(IDENTITY, ZERO)


@dataclass(frozen=True)
class Inertial:
    """Mass (kg), centre of mass (m) and the inertia tensor about it (kg m²), in one frame."""

    mass: float
    com: Vec
    tensor: Mat

    def moved(self, frame: Frame) -> Inertial:
        """The same body expressed in ``frame``'s parent: the centre of mass transformed,
        the tensor rotated (R I Rᵀ)."""
        r = frame.rotation
        return Inertial(self.mass, frame.point(self.com), r @ self.tensor @ r.T)

    def about(self, point: Vec) -> Mat:
        """The tensor about ``point`` (parallel-axis theorem)."""
        d = self.com - point
        return self.tensor + self.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))


def compose(parts: Iterable[Inertial]) -> Inertial:
    """One rigid body from parts expressed in one frame (see the module docstring)."""
    items = [p for p in parts if p.mass > 0]
    mass = sum(p.mass for p in items)
    if mass <= 0:
        return Inertial(0.0, ZERO.copy(), np.zeros((3, 3)))
    com = sum((p.mass * p.com for p in items), np.zeros(3)) / mass
    tensor = sum((p.about(com) for p in items), np.zeros((3, 3)))
    return Inertial(mass, com, tensor)


# ---------------------------------------------------------------------------------------
# Primitive shapes: uniform-density tensors about the centre, in the shape's own frame
# (cylinders and capsules along z), and the radius of a sphere about the centre that holds
# the shape. ``size`` is the full extent for a box (x, y, z), (radius, length) for a
# cylinder or capsule (length of the straight part), (radius,) for a sphere, the three
# semi-axes for an ellipsoid.
# ---------------------------------------------------------------------------------------
def volume(kind: str, size: Sequence[float]) -> float:
    if kind == "box":
        return size[0] * size[1] * size[2]
    if kind == "cylinder":
        return math.pi * size[0] ** 2 * size[1]
    if kind == "sphere":
        return 4 / 3 * math.pi * size[0] ** 3
    if kind == "capsule":
        return math.pi * size[0] ** 2 * size[1] + 4 / 3 * math.pi * size[0] ** 3
    if kind == "ellipsoid":
        return 4 / 3 * math.pi * size[0] * size[1] * size[2]
    raise ValueError(f"no volume for a {kind}")


def uniform_tensor(kind: str, size: Sequence[float], mass: float) -> Mat:
    """The inertia tensor of a uniform solid of mass ``mass`` about its centre."""
    if kind == "box":
        a, b, c = size
        return mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    if kind == "cylinder":
        r, h = size
        side = mass * (3 * r * r + h * h) / 12
        return np.diag([side, side, mass * r * r / 2])
    if kind == "sphere":
        return np.eye(3) * 0.4 * mass * size[0] ** 2
    if kind == "capsule":
        r, h = size
        v_cyl, v_caps = math.pi * r * r * h, 4 / 3 * math.pi * r**3
        m_cyl = mass * v_cyl / (v_cyl + v_caps)
        m_caps = mass - m_cyl
        axial = m_cyl * r * r / 2 + m_caps * 0.4 * r * r
        side = (m_cyl * (3 * r * r + h * h) / 12
                + m_caps * (0.4 * r * r + h * h / 4 + 3 * h * r / 8))
        return np.diag([side, side, axial])
    if kind == "ellipsoid":
        a, b, c = size
        return mass / 5 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    raise ValueError(f"no inertia for a {kind}")


def bounding_radius(kind: str, size: Sequence[float]) -> float:
    """The radius of the smallest sphere about the shape's centre that holds it."""
    if kind == "box":
        return 0.5 * math.sqrt(sum(s * s for s in size))
    if kind == "cylinder":
        return math.hypot(size[0], size[1] / 2)
    if kind == "sphere":
        return size[0]
    if kind == "capsule":
        return size[0] + size[1] / 2
    if kind == "ellipsoid":
        return max(size)
    raise ValueError(f"no extent for a {kind}")


def lowest_point(kind: str, size: Sequence[float], frame: Frame) -> float:
    """The lowest z of a shape placed at ``frame`` (in the frame's parent)."""
    r, c = frame.rotation, frame.origin
    if kind == "sphere":
        return float(c[2] - size[0])
    if kind == "box":
        half = np.asarray(size) / 2
        return float(c[2] - np.abs(r[2, :]) @ half)
    if kind in ("cylinder", "capsule"):
        radius, length = size
        axis_z = abs(float(r[2, 2]))
        drop = length / 2 * axis_z + radius * math.sqrt(max(0.0, 1 - axis_z**2))
        if kind == "capsule":
            drop = length / 2 * axis_z + radius
        return float(c[2] - drop)
    if kind == "ellipsoid":
        m = r @ np.diag(np.asarray(size) ** 2) @ r.T
        return float(c[2] - math.sqrt(m[2, 2]))
    raise ValueError(f"no extent for a {kind}")


def yaw_of(direction: Vec) -> float:
    """The heading (rad) of a direction's horizontal projection."""
    return math.atan2(float(direction[1]), float(direction[0]))
