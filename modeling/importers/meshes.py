"""Wheel cylinders from collision meshes: a URDF wheel whose only collision geometry is a
mesh gets its radius and width from the mesh's vertices, when the mesh file is found and
is one this module reads (NumPy only, no mesh library).

* Found: ``package://PKG/...`` under the package of that name (``--package-path``, or
  above or beside the file, as xacro's ``$(find PKG)``: ``expand.find_package``),
  ``file://...`` as an absolute path, anything else relative to the file's folder.
* Read: STL, binary or ASCII, and Wavefront OBJ (its ``v`` lines). COLLADA (``.dae``) is
  not read: its vertices sit under node transforms and a unit the file declares, which a
  bounding box of the raw arrays would get wrong.
* Used: only for the child link of a revolute or continuous joint that has no collision
  cylinder of its own (the importer's wheels, ``planar``): the vertices, scaled and placed
  by the collision's origin, are measured about the joint axis through the centre of
  their bounding box; if the extents across the axis agree within :data:`ROUND`, the link
  gets a collision cylinder of that radius (half the extent across) and width (the extent
  along), centred there, named after the mesh. A mesh that is not round about the axis
  (a hub, a caster fork) is left as it is, and so is one not found or not read: each
  case is a line of the mechanism's notes, and the wheel is then refused as before, its
  radius unknown.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from modeling.importers.expand import find_package
from modeling.importers.geometry import Frame, rotation_onto
from modeling.importers.mechanism import Geom, Mechanism

ROUND = 0.02  # the two extents across the axis agree within 2 % of the larger: round
READABLE = (".stl", ".obj")


class MeshError(ValueError):
    """A mesh file that cannot be read (the message says why)."""


def find_mesh(uri: str, source: Path, package_path: Sequence[Path]) -> Path | None:
    """The file a mesh ``filename`` names (module docstring), or None if it is not there."""
    if uri.startswith("package://"):
        name, _, rest = uri.removeprefix("package://").partition("/")
        folder = find_package(name, source, package_path)
        found = None if folder is None else folder / rest
    elif uri.startswith("file://"):
        found = Path(uri.removeprefix("file://"))
    else:
        found = source.parent / uri
    return found if found is not None and found.is_file() else None


def read_vertices(path: Path) -> NDArray[np.float64]:
    """The vertices (n × 3) of an STL (binary or ASCII) or OBJ file; ``MeshError``."""
    suffix = path.suffix.lower()
    if suffix not in READABLE:
        raise MeshError(f"a {suffix or 'suffix-less'} mesh is not read (STL and OBJ are)")
    data = path.read_bytes()
    if suffix == ".obj":
        rows = [line.split()[1:4] for line in data.decode("utf-8", "replace").splitlines()
                if line.startswith("v ")]
        return _array(rows, path)
    # Binary STL: an 80-byte header, a count, 50 bytes per triangle. An ASCII file starts
    # with "solid" too, so the length decides.
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * count and count > 0:
            records = np.frombuffer(data, dtype=np.dtype([
                ("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")]),
                count=count, offset=84)
            return records["v"].reshape(-1, 3).astype(np.float64)
    text = data.decode("ascii", "replace")
    rows = [m.split() for m in re.findall(r"vertex\s+(\S+\s+\S+\s+\S+)", text)]
    return _array(rows, path)


def _array(rows: list[list[str]], path: Path) -> NDArray[np.float64]:
    try:
        out = np.array(rows, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        raise MeshError("its vertices are not numbers") from None
    if len(out) == 0 or not np.all(np.isfinite(out)):
        raise MeshError("no vertices" if len(out) == 0 else "non-finite vertices")
    return out


def _scale(text: str) -> NDArray[np.float64]:
    if not text.strip():
        return np.ones(3)
    try:
        values = np.array([float(v) for v in text.split()])
    except ValueError:
        values = np.array([])
    if len(values) != 3 or not np.all(np.isfinite(values)) or np.any(values == 0):
        raise MeshError(f"scale=\"{text}\" is not three non-zero numbers")
    return values


def cylinder_about(points: NDArray[np.float64], axis: NDArray[np.float64], label: str
                   ) -> tuple[Geom | None, str]:
    """The cylinder (link frame) of ``points`` about ``axis`` (unit, link frame), or None
    if they are not round about it; and a sentence saying which."""
    z = axis / np.linalg.norm(axis)
    # columns: the cylinder's x, y, z in the link frame
    rot = rotation_onto((0.0, 0.0, 1.0), tuple(float(c) for c in z))
    local = points @ rot
    lo, hi = local.min(axis=0), local.max(axis=0)
    extent = hi - lo
    across = extent[:2]
    if across.max() <= 0 or abs(across[0] - across[1]) > ROUND * across.max():
        return None, (f"{label}: its mesh is not round about the joint axis (extents "
                      f"{across[0]:.4g} and {across[1]:.4g} m across it): not a wheel's "
                      "cylinder")
    radius, width = float(across.mean()) / 2, float(extent[2])
    centre = rot @ ((lo + hi) / 2)
    geom = Geom("cylinder", (radius, width), Frame(rot, centre),
                f"{label} (its mesh's bounds)")
    return geom, (f"{label}: the mesh's vertices give a cylinder of radius {radius:.4g} m "
                  f"and width {width:.4g} m about the joint axis (the link has no collision "
                  "cylinder)")


def add_wheel_cylinders(mech: Mechanism, source: Path, package_path: Sequence[Path] = ()
                        ) -> None:
    """Give each revolute/continuous joint's child link without a collision cylinder the
    cylinder its collision meshes' bounds give (module docstring); notes say what was read
    and what was not."""
    for joint in mech.joints:
        if joint.kind not in ("revolute", "continuous"):
            continue
        link = mech.links[joint.child]
        if any(g.kind == "cylinder" for g in link.geoms):
            continue
        found: list[Geom] = []
        for g in [g for g in link.geoms if g.kind == "mesh" and g.source]:
            path = find_mesh(g.source, source, package_path)
            if path is None:
                mech.notes.append(f"{g.label}: mesh '{g.source}' not found (give "
                                  "--package-path to the package that holds it): its bounds "
                                  "are not read")
                continue
            try:
                points = read_vertices(path) * _scale(g.scale)
            except (MeshError, OSError) as exc:
                mech.notes.append(f"{g.label}: mesh '{g.source}' not read: {exc}")
                continue
            placed = points @ g.frame.rotation.T + g.frame.origin  # in the link frame
            geom, note = cylinder_about(placed, joint.axis, g.label)
            mech.notes.append(note)
            if geom is not None:
                found.append(geom)
        link.geoms.extend(found)
