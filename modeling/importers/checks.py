"""The importer's part of the physics audit: 3D inertia tensors as description files give
them (``modeling.audit`` has the rest and runs on the imported robot file too).

* **Non-physical** (an error): a principal moment below zero, or one above the sum of the
  other two (the triangle inequality every mass distribution obeys: I₁ + I₂ − I₃ =
  2∫x₃² dm ≥ 0). A tensor of zeros on a positive mass is a point mass (a warning: its
  rotational inertia is left out).
* **Placeholders** (warnings): equal diagonal moments of a round value (1e-3 kg m²: the
  common 0.001 of ROS files) with no products of inertia.
* **Far from the geometry** (warnings): the tensor's trace against that of a uniform solid of
  the link's mass filling its collision shapes, outside [0.1, 10]; or a principal moment
  above m R², R the radius of a sphere about the centre of mass holding every collision
  shape: no mass inside those shapes can have it.
* **A centre of mass left at the link origin** (a warning): an ``<inertial>`` at exactly
  (0, 0, 0) of its link, more than 10 mm (and 10 % of the shapes' extent) from the centre
  of the link's collision shapes, whose tensor fits a uniform body of those shapes about
  their own centre better than about that origin (by the trace, on a log scale): the
  tensor was computed for the shape while the origin was left at its default. ROBOTIS'
  TurtleBot3 ``base_link`` is one: its centre of mass at the wheel axle, 77 mm below and
  behind its box's centre.
* **Wheels** (warnings): the spin axis (the tensor's symmetry axis, its odd principal
  moment) not along the joint axis; the centre of mass off the axle.
"""

from __future__ import annotations

import math

import numpy as np

from modeling.importers.geometry import (
    Frame,
    Inertial,
    Mat,
    Vec,
    bounding_radius,
    compose,
    uniform_tensor,
    volume,
)
from modeling.importers.mechanism import Geom, ImportFileError

ROUND_PLACEHOLDERS = tuple(10.0**-k for k in range(0, 10))
GEOMETRY_RATIO = (0.1, 10.0)
TRIANGLE_TOLERANCE = 1e-3  # relative: files round thin-disc values (I_spin = 2 I_diameter)
SPIN_AXIS_TOLERANCE = math.radians(10.0)
SYMMETRIC_SPREAD = 0.05  # principal moments within 5 %: no symmetry axis to speak of
OFF_AXLE = 1e-3  # m
ORIGIN_OFFSET = (0.01, 0.1)  # m, × the shapes' extent: a CoM this far from the shapes


def _g(x: float) -> str:
    return f"{x:.4g}"


def principal(tensor: Mat) -> tuple[Vec, Mat]:
    """Principal moments (ascending) and axes (columns) of a symmetric tensor."""
    values, vectors = np.linalg.eigh((tensor + tensor.T) / 2)
    return values, vectors


def check_tensor(path: str, where: str, inertial: Inertial) -> list[str]:
    """Raise on a non-physical tensor; return the point-mass and placeholder findings."""
    if inertial.mass <= 0:
        return []
    moments, _ = principal(inertial.tensor)
    top = float(max(abs(moments).max(), 1e-300))
    if moments[0] < -1e-9 * top:
        raise ImportFileError(
            f"{path}: {where} <inertia>: principal moments {_moments(moments)} kg m^2 include "
            "a negative one: not positive semi-definite, no body has this inertia")
    a, b, c = (float(m) for m in moments)
    if c > a + b + TRIANGLE_TOLERANCE * c:
        raise ImportFileError(
            f"{path}: {where} <inertia>: principal moments {_moments(moments)} kg m^2 break "
            f"the triangle inequality ({_g(c)} > {_g(a)} + {_g(b)}): no body has this "
            "inertia (typed in the wrong order, or a placeholder)")
    found = []
    if c == 0:
        found.append(f"{where}: a point mass ({_g(inertial.mass)} kg with a zero inertia "
                     "tensor): its rotational inertia is left out")
    t = inertial.tensor
    diag = np.diag(t)
    products = t - np.diag(diag)
    if (np.all(products == 0) and diag[0] > 0 and np.allclose(diag, diag[0], rtol=1e-9)
            and any(math.isclose(diag[0], p, rel_tol=1e-9) for p in ROUND_PLACEHOLDERS)):
        found.append(f"{where}: ixx = iyy = izz = {diag[0]:g} kg m^2 with no products of "
                     f"inertia on a {_g(inertial.mass)} kg link: the common placeholder, not "
                     "a measured or computed inertia")
    return found


def _moments(moments: Vec) -> str:
    return "(" + ", ".join(_g(float(m)) for m in moments) + ")"


def check_geometry(where: str, inertial: Inertial, geoms: list[tuple[Geom, Frame]]) -> str | None:
    """The far-from-the-geometry finding (module docstring), or None. ``geoms``: primitive
    collision shapes with their poses in the frame of ``inertial``."""
    shapes = [(g, f) for g, f in geoms if g.kind in ("box", "cylinder", "sphere", "capsule",
                                                      "ellipsoid")]
    if inertial.mass <= 0 or not shapes:
        return None
    expected = _uniform(inertial, shapes).about(inertial.com)
    ratio = float(np.trace(inertial.tensor) / np.trace(expected))
    reach = max(float(np.linalg.norm(f.origin - inertial.com)) + bounding_radius(g.kind, g.size)
                for g, f in shapes)
    bound = inertial.mass * reach**2
    largest = float(principal(inertial.tensor)[0][-1])
    shape_text = ", ".join(sorted({g.kind for g, _ in shapes}))
    low, high = GEOMETRY_RATIO
    if largest > 1.05 * bound:
        return (f"{where}: a principal moment of {_g(largest)} kg m^2, but no "
                f"{_g(inertial.mass)} kg inside its collision {shape_text} (within "
                f"{_g(reach)} m of its centre of mass) can have more than m R^2 = "
                f"{_g(bound)} kg m^2; a uniform body of that shape has moments "
                f"{_moments(principal(expected)[0])} kg m^2")
    if not low <= ratio <= high:
        return (f"{where}: inertia tensor (principal moments "
                f"{_moments(principal(inertial.tensor)[0])} kg m^2) is {ratio:.3g} × what a "
                f"uniform {_g(inertial.mass)} kg body filling its collision {shape_text} has "
                f"({_moments(principal(expected)[0])} kg m^2)")
    return None


def wheel_axis(inertial: Inertial, axle: Vec) -> tuple[float, float, Vec] | None:
    """(the odd principal moment, the mean of the other two, its axis) when the tensor has
    a symmetry axis that is not the axle, else None (module docstring)."""
    moments, axes = principal(inertial.tensor)
    if moments[-1] <= 0 or (moments[-1] - moments[0]) <= SYMMETRIC_SPREAD * moments[-1]:
        return None
    odd = 0 if (moments[1] - moments[0]) > (moments[2] - moments[1]) else 2
    axis = axes[:, odd]
    if abs(float(axis @ axle)) >= math.cos(SPIN_AXIS_TOLERANCE):
        return None
    others = [float(m) for i, m in enumerate(moments) if i != odd]
    return float(moments[odd]), sum(others) / 2, axis


def _uniform(inertial: Inertial, shapes: list[tuple[Geom, Frame]]) -> Inertial:
    """A uniform body of ``inertial``'s mass filling the primitive ``shapes``."""
    vols = [volume(g.kind, g.size) for g, _ in shapes]
    total = sum(vols)
    return compose(
        Inertial(inertial.mass * v / total, np.zeros(3),
                 uniform_tensor(g.kind, g.size, inertial.mass * v / total)).moved(f)
        for (g, f), v in zip(shapes, vols, strict=True))


def check_default_origin(where: str, inertial: Inertial,
                         geoms: list[tuple[Geom, Frame]]) -> str | None:
    """The centre-of-mass-left-at-the-origin finding (module docstring), or None;
    ``inertial`` and ``geoms`` in the link frame."""
    shapes = [(g, f) for g, f in geoms if g.kind in ("box", "cylinder", "sphere", "capsule",
                                                      "ellipsoid")]
    if inertial.mass <= 0 or not shapes or np.any(inertial.com != 0):
        return None
    uniform = _uniform(inertial, shapes)
    offset = float(np.linalg.norm(uniform.com))
    extent = max(float(np.linalg.norm(f.origin - uniform.com)) + bounding_radius(g.kind, g.size)
                 for g, f in shapes)
    if offset <= max(ORIGIN_OFFSET[0], ORIGIN_OFFSET[1] * extent):
        return None
    given = float(np.trace(inertial.tensor))
    about_shape = float(np.trace(uniform.tensor))
    about_origin = float(np.trace(uniform.about(inertial.com)))
    if given <= 0 or abs(math.log(given / about_shape)) >= abs(math.log(given / about_origin)):
        return None
    return (f"{where}: its centre of mass is exactly at the link origin, {1000 * offset:.0f} mm "
            f"from the centre of its collision shapes, and its tensor (trace {_g(given)} "
            f"kg m^2) fits a uniform body of those shapes about their centre (trace "
            f"{_g(about_shape)}), not about that origin ({_g(about_origin)}): the "
            "<inertial> origin looks left at its default; the centre of mass, and the yaw "
            "inertia composed from it, are then wrong")
