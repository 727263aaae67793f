"""The physics audit: what a robot file's numbers say about the robot, checked before any work.

Every robot file the toolchain reads goes through here: a ``[lumped]``/``[physical]`` file
from ``modeling.robots.drishti.robot_file.parse_robot``, a bodies-and-wheels file from
``modeling.description.files.parse_description`` (``wmr import`` checks its output the
same way before writing it). An *error* refuses the file with one line naming the file,
the field and its value (a ``RobotFileError``: the commands exit 2); a *warning* is logged
once per process (``warning: FILE: ...`` on stderr when nothing configured logging),
returned to the caller (``Robot.warnings``, ``RobotDescription.warnings``) and written
into the generated MODEL.md. Standard library only: the runtime reads ``[lumped]`` files
through this module without SymPy or NumPy. (The runtime runs a bodies-and-wheels file only
on code generated from it, which records the file's digest and the audit's warnings,
``AUDIT_WARNINGS`` of its ``robot.py``: the audit ran when that code was generated; every
command prints them again through :func:`report`.)

The checks and their thresholds (the constants below):

* **Units.** A wheel radius above 5 m or a length (track, positions, hitch points) above
  20 m is a length in millimetres; a radius below 1 mm is implausible too. A total mass
  above 5,000 kg is a mass in grams, below 1 g a mass in tonnes. The robot's mean density,
  its mass over the cube of its size (the largest distance between wheel centres, at least
  a wheel's diameter; for several bodies, over the sum of each body's cubed size, since a
  train fills its length only one body wide), must lie between air's (1.2 kg/m³) and
  osmium's (22,600 kg/m³): a robot fills less than that cube, so a larger value cannot be
  a robot (a 2 kg robot with a 0.16 m track typed in grams reads 488,000 kg/m³). Softer
  bounds (radius above 1.5 m or below 5 mm, size above 5 m, mass above 1,000 kg or below
  50 g, density above steel's 8,000 kg/m³ or below 10 kg/m³) are warnings.
* **Inertias.** A body's yaw inertia about its centre of mass against m L², L its size (the
  largest distance between its centre of mass, wheel centres and hitch points, at least a
  wheel's diameter): a uniform plate has m L²/12, a ring m L²/4; outside [0.01, 100] m L²
  the number is a placeholder or in other units (warning). A wheel's diameter inertia above
  1.5 m r² fits no wheel (a wheel of width w ≤ 2r has at most m (r²/2 + w²/4)); its spin
  inertia below 1 % of a disc's m r²/2 is a placeholder (warnings), or, if a thousandth of
  its mass makes it 0.3–3 × a disc's, a wheel mass in grams (the warning says so). **Unit
  slips** are errors: an inertia 1,000 × or more what its mass and size allow is no body's
  (m L² for a body; M r² for a wheel's spin, M the robot's mass, which bounds a geared
  rotor's J_r N² too; 1.5 m r² about its diameter); the error names the unit that brings it
  closest to a typical body's (m L²/12, a disc's m r²/2 and m r²/4): 1 kg m² is 1e3 g m²,
  1e4 kg cm², 1e6 kg mm², 1e7 g cm² (a 6 kg chassis with I = 80000 is in kg mm², a 28 g
  wheel with Iw = 207 in g cm²). The 3D tensors of an
  imported file (triangle inequality, positive definiteness, the 0.001 kg m² placeholder,
  the spin axis) are checked by the importer (``modeling.importers.checks``).
* **Layout.** Fixed wheels on one body at more than one axle position (a skid-steer: four
  wheels with parallel axles at two x positions) are refused: their no-side-slip
  constraints force the body's yaw rate to zero, so under pure rolling, the only contact
  model derived here, the robot could not turn. A child body whose wheels sit on its hitch
  (a caster without trail) is refused: rolling then leaves its swivel angle free.
* **Motors.** A driven wheel whose spin inertia is what the wheel alone has (at most 1.5 ×
  a solid disc's m r²/2) and that gives no ``rotor_inertia`` and ``gear_ratio``: the rotor
  turns N times faster than the wheel and adds J_r N² about the axle. The warning states
  the size of the omission for an assumed typical small-robot gearmotor, J_r = 1e-6 kg m²
  (a 20–30 mm brushed DC motor: 1–10 g cm²) and N = 50, that is J_r N² = 2.5e-3 kg m²,
  against the wheel's own spin inertia (about 100 × a TurtleBot-sized wheel's 2e-5 kg m²).
  A ``[lumped]`` file's Iw cannot be judged (no wheel mass); a ``[physical]`` one's is.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from modeling.robot_io import RobotFileError

if TYPE_CHECKING:
    from modeling.description.schema import RobotDescription

# Units (errors) and plausibility (warnings); lengths m, masses kg, densities kg/m³.
RADIUS_MAX, RADIUS_WARN_MAX = 5.0, 1.5
RADIUS_MIN, RADIUS_WARN_MIN = 0.001, 0.005
LENGTH_MAX, LENGTH_WARN_MAX = 20.0, 5.0
MASS_MAX, MASS_WARN_MAX = 5000.0, 1000.0
MASS_MIN, MASS_WARN_MIN = 0.001, 0.05
DENSITY_MAX, DENSITY_WARN_MAX = 22_600.0, 8_000.0  # osmium; steel
DENSITY_MIN, DENSITY_WARN_MIN = 1.2, 10.0  # air
# Inertias: I / (m L²) of a body, diameter / (m r²) and spin / (m r²/2) of a wheel.
YAW_RATIO = (0.01, 100.0)
UNIT_SLIP = 1e3  # × what the mass and size allow: an error, an inertia in other units
INERTIA_UNITS = (("g m^2", 1e3), ("kg cm^2", 1e4), ("kg mm^2", 1e6), ("g cm^2", 1e7),
                 ("g mm^2", 1e9))  # how many of each make 1 kg m²
DIAMETER_RATIO_MAX = 1.5
SPIN_RATIO_MIN = 0.01
GRAMS_SPIN = (0.3, 3.0)  # × a disc's m r²/2 with the mass read as grams: a wheel in grams
WHEEL_ALONE = 1.5  # spin ≤ 1.5 × m r²/2: the wheel without its motor's rotor
# The assumed typical small-robot gearmotor of the rotor warning.
TYPICAL_ROTOR_INERTIA = 1e-6  # kg m², J_r
TYPICAL_GEAR_RATIO = 50.0  # N
AXLE_TOLERANCE = 1e-3  # m: wheels closer than this in x share an axle

LOG = logging.getLogger("wmr.audit")
_reported: set[tuple[str, str]] = set()


@dataclass(frozen=True)
class Rotor:
    """A driven wheel's motor as a robot file gives it: rotor inertia J_r (kg m²) and gear
    ratio N (motor turns per wheel turn)."""

    inertia: float
    gear_ratio: float

    @property
    def reflected(self) -> float:
        """J_r N², the rotor's inertia as the wheel feels it."""
        return self.inertia * self.gear_ratio**2


def _g(x: float) -> str:
    return f"{x:.4g}"


def refuse(where: str, message: str) -> RobotFileError:
    """The one-line error of a file the audit refuses."""
    return RobotFileError(f"{where}: {message}")


def report(where: str, warnings: Iterable[str]) -> tuple[str, ...]:
    """Log each warning once per process (``warning: FILE: ...``) and return them all."""
    out = tuple(warnings)
    for w in out:
        if (where, w) not in _reported:
            _reported.add((where, w))
            LOG.warning("warning: %s: %s", where, w)
    return out


SECTION_INTRO = ("The physics audit of the robot file warned (check each before trusting "
                 "these results):")


def section(warnings: Sequence[str], heading: str = "## Robot file audit") -> list[str]:
    """The warnings as a written output carries them (REPORT.md, FAULTS.md, a campaign's
    summary.md, the crosscheck's report): a heading, one sentence, one ``- `` line per
    warning and a blank line; nothing for a robot without warnings. One function, so that
    every output words them alike."""
    if not warnings:
        return []
    return [heading, "", SECTION_INTRO, "", *[f"- {w}" for w in warnings], ""]


# ---------------------------------------------------------------------------------------
# Shared checks
# ---------------------------------------------------------------------------------------
def _radius(where: str, label: str, r: float, warnings: list[str]) -> None:
    if r > RADIUS_MAX:
        raise refuse(where, f"field '{label}' = {r!r} m: a wheel radius above {RADIUS_MAX:g} m "
                     "is implausible for a wheeled robot; lengths in millimetres? Give "
                     "lengths in metres")
    if r < RADIUS_MIN:
        raise refuse(where, f"field '{label}' = {r!r} m: a wheel radius below "
                     f"{RADIUS_MIN * 1000:g} mm is implausible for a wheeled robot; lengths "
                     "in kilometres? Give lengths in metres")
    if r > RADIUS_WARN_MAX or r < RADIUS_WARN_MIN:
        warnings.append(f"field '{label}' = {_g(r)} m: an unusual wheel radius (expected "
                        f"{RADIUS_WARN_MIN * 1000:g} mm to {RADIUS_WARN_MAX:g} m); check "
                        "its unit")


def _length(where: str, label: str, x: float) -> None:
    if abs(x) > LENGTH_MAX:
        raise refuse(where, f"field '{label}' = {x!r} m: a length above {LENGTH_MAX:g} m is "
                     "implausible for a wheeled robot; lengths in millimetres? Give lengths "
                     "in metres")


def _mass_and_size(where: str, label: str, mass: float, size: float,
                   warnings: list[str], volume: float | None = None) -> None:
    """Total mass, size and the mean density they imply (see the module docstring).
    ``volume``: what the mass fills when it is not the cube of ``size`` (a train of
    bodies: the sum of each body's cube; a long train is not a cube of its length)."""
    if mass > MASS_MAX:
        raise refuse(where, f"{label} = {mass!r} kg: a total mass above {MASS_MAX:,.0f} kg "
                     "is implausible for a wheeled robot; masses in grams? Give masses in kg")
    if mass < MASS_MIN:
        raise refuse(where, f"{label} = {mass!r} kg: a total mass below {MASS_MIN * 1000:g} g "
                     "is implausible for a wheeled robot; masses in tonnes? Give masses in kg")
    if size > LENGTH_MAX:
        raise refuse(where, f"the robot's size (largest distance between wheel centres) = "
                     f"{size!r} m is implausible for a wheeled robot (> {LENGTH_MAX:g} m); "
                     "lengths in millimetres? Give lengths in metres")
    over = "the cube of its size" if volume is None else "its bodies' cubed sizes"
    density = mass / (size**3 if volume is None else volume)
    if density > DENSITY_MAX:
        raise refuse(where, f"{label} = {mass!r} kg in a robot of size {_g(size)} m is "
                     f"{density:,.0f} kg/m^3 over {over}, denser than osmium "
                     f"({DENSITY_MAX:,.0f} kg/m^3): masses in grams, or lengths in another "
                     "unit? Give masses in kg and lengths in m")
    if density < DENSITY_MIN:
        raise refuse(where, f"{label} = {mass!r} kg in a robot of size {_g(size)} m is "
                     f"{density:.3g} kg/m^3 over {over}, lighter than air: "
                     "masses in tonnes, or lengths in millimetres? Give masses in kg and "
                     "lengths in m")
    if mass > MASS_WARN_MAX or mass < MASS_WARN_MIN:
        warnings.append(f"{label} = {_g(mass)} kg: an unusual total mass for a wheeled robot "
                        f"(expected {MASS_WARN_MIN * 1000:g} g to {MASS_WARN_MAX:,.0f} kg); "
                        "check its unit")
    if size > LENGTH_WARN_MAX:
        warnings.append(f"the robot's size (largest distance between wheel centres) = "
                        f"{_g(size)} m is unusual (> {LENGTH_WARN_MAX:g} m); check its unit")
    if density > DENSITY_WARN_MAX:
        warnings.append(f"{label} = {_g(mass)} kg is {density:,.0f} kg/m^3 over {over} "
                        f"(size {_g(size)} m), denser than solid steel: a "
                        "ballast set to suit a simulator, or masses in another unit?")
    elif density < DENSITY_WARN_MIN:
        warnings.append(f"{label} = {_g(mass)} kg is {density:.3g} kg/m^3 over {over} "
                        f"(size {_g(size)} m), lighter than a foam block: check "
                        "the masses' unit")


def _unit_slip(where: str, label: str, inertia: float, allowed: float, typical: float,
               what: str) -> None:
    """Refuse an inertia ``UNIT_SLIP`` × or more above ``allowed`` (the most its mass and
    size allow), naming the unit that brings it nearest ``typical`` (module docstring)."""
    if allowed <= 0 or inertia < UNIT_SLIP * allowed:
        return
    unit, factor = min(INERTIA_UNITS,
                       key=lambda u: abs(math.log10(inertia / u[1] / typical)))
    raise refuse(where, (
        f"{label} = {inertia!r} kg m^2 is {inertia / allowed:.3g} × the most {what} can have "
        f"({_g(allowed)} kg m^2): no body has it; an inertia in {unit} typed as kg m^2? "
        f"({_g(inertia)} {unit} = {_g(inertia / factor)} kg m^2, near the "
        f"{_g(typical)} kg m^2 such a body has); give inertias in kg m^2"))


def _yaw_ratio(label: str, inertia: float, mass: float, size: float,
               warnings: list[str], where: str) -> None:
    """I against m L² (module docstring): a unit slip refused, a far value a warning."""
    if mass <= 0 or size <= 0:
        return
    _unit_slip(where, label, inertia, mass * size**2, mass * size**2 / 12,
               f"a body of m = {_g(mass)} kg and size L = {_g(size)} m (m L^2)")
    ratio = inertia / (mass * size**2)
    low, high = YAW_RATIO
    if not low <= ratio <= high:
        warnings.append(
            f"{label} = {_g(inertia)} kg m^2 is {ratio:.3g} m L^2 (m = {_g(mass)} kg, size "
            f"L = {_g(size)} m); a body of that mass and size has about m L^2/12 = "
            f"{_g(mass * size**2 / 12)} kg m^2 (outside [{low:g}, {high:g}] m L^2: a "
            "placeholder, or another unit)"
        )


def _wheel_inertias(spin_label: str, diameter_label: str, mass: float, radius: float,
                    spin: float, diameter: float, warnings: list[str], where: str,
                    total: float) -> None:
    """A wheel's inertias against m r² (module docstring); ``total``: the robot's mass,
    which bounds a spin inertia holding a geared rotor's J_r N² (as an equivalent mass
    J_r N²/r² at the rim, which no drive makes 1,000 × the robot's)."""
    if mass <= 0:
        return  # a massless wheel: its inertias are lumped elsewhere
    mr2 = mass * radius**2
    wheel = f"a wheel of m = {_g(mass)} kg and r = {_g(radius)} m"
    _unit_slip(where, spin_label, spin, max(mr2, total * radius**2), mr2 / 2,
               f"{wheel} about its axle, with its motor's rotor, on a {_g(total)} kg robot "
               "(M r^2)")
    _unit_slip(where, diameter_label, diameter, DIAMETER_RATIO_MAX * mr2, mr2 / 4,
               f"{wheel} about a diameter ({DIAMETER_RATIO_MAX:g} m r^2)")
    if diameter > DIAMETER_RATIO_MAX * mr2:
        warnings.append(
            f"{diameter_label} = {_g(diameter)} kg m^2 is {diameter / mr2:.3g} m r^2 "
            f"(m = {_g(mass)} kg, r = {_g(radius)} m): no wheel of that mass and radius has "
            f"more than about {DIAMETER_RATIO_MAX:g} m r^2 about a diameter (a disc has "
            f"m r^2/4 = {_g(mr2 / 4)})"
        )
    if spin < SPIN_RATIO_MIN * mr2 / 2:
        in_grams = spin / (mr2 / 2 / 1000)  # × a disc, were the mass in grams
        grams = (f"; or the wheel's mass in grams: m = {_g(mass / 1000)} kg gives "
                 f"{in_grams:.2g} × a disc" if GRAMS_SPIN[0] <= in_grams <= GRAMS_SPIN[1]
                 else "")
        warnings.append(
            f"{spin_label} = {_g(spin)} kg m^2 is {spin / (mr2 / 2):.2g} × a solid "
            f"disc's m r^2/2 = {_g(mr2 / 2)} kg m^2 (m = {_g(mass)} kg, r = {_g(radius)} m): "
            f"a placeholder, or another unit{grams}"
        )


def rotor_warning(
    label: str, spin: float, mass: float, radius: float,
    remedy: str = "give rotor_inertia (J_r, kg m^2) and gear_ratio (N)",
) -> str | None:
    """The missing-rotor warning of a driven wheel whose spin inertia is the wheel's alone
    (module docstring), or None. ``remedy``: what the file's format lets a user do."""
    disc = mass * radius**2 / 2
    if mass <= 0 or spin > WHEEL_ALONE * disc:
        return None
    typical = TYPICAL_ROTOR_INERTIA * TYPICAL_GEAR_RATIO**2
    return (
        f"{label}: spin inertia {_g(spin)} kg m^2 is what the wheel alone has (a solid disc "
        f"of its mass and radius: m r^2/2 = {_g(disc)} kg m^2), without its motor: the "
        "rotor turns N times faster than the wheel and adds J_r N^2 about the axle; "
        f"{remedy} from the motor's datasheet. For a typical small-robot gearmotor "
        f"(assumed J_r = {TYPICAL_ROTOR_INERTIA:g} kg m^2, N = {TYPICAL_GEAR_RATIO:g}: "
        f"J_r N^2 = {typical:.2g} kg m^2) the inertia left out is "
        f"{typical / max(spin, 1e-300):.3g} × the one given"
    )


# ---------------------------------------------------------------------------------------
# [lumped] and [physical] files (the paper's differential drive)
# ---------------------------------------------------------------------------------------
def audit_lumped(where: str, p: Mapping[str, float]) -> tuple[str, ...]:
    """Audit a ``[lumped]`` table (m, I, K, Iw, r, b, d); raise on an error, return the
    warnings (logged)."""
    warnings: list[str] = []
    _radius(where, "lumped.r", p["r"], warnings)
    for key in ("b", "d"):
        _length(where, f"lumped.{key}", p[key])
    size = max(p["b"], 2 * p["r"], abs(p["d"]))
    _mass_and_size(where, "field 'lumped.m'", p["m"], size, warnings)
    inertia_com = p["I"] - p["K"] ** 2 / p["m"]  # about the centre of mass, not C
    _yaw_ratio("field 'lumped.I' less K^2/m (the yaw inertia about the centre of mass)",
               inertia_com, p["m"], size, warnings, where)
    return report(where, warnings)


def audit_physical(where: str, p: Mapping[str, float]) -> tuple[str, ...]:
    """Audit a ``[physical]`` table (platform + two wheels); raise on an error, return the
    warnings (logged)."""
    warnings: list[str] = []
    _radius(where, "physical.r", p["r"], warnings)
    for key in ("b", "d", "x_P", "y_P"):
        _length(where, f"physical.{key}", p[key])
    size = max(p["b"], 2 * p["r"], abs(p["d"]))
    _mass_and_size(where, "the total mass m_P + 2 m_w", p["m_P"] + 2 * p["m_w"], size,
                   warnings)
    _yaw_ratio("field 'physical.I_P'", p["I_P"], p["m_P"], size, warnings, where)
    _wheel_inertias("field 'physical.Iw'", "field 'physical.Im'", p["m_w"], p["r"], p["Iw"],
                    p["Im"], warnings, where, p["m_P"] + 2 * p["m_w"])
    rotor = rotor_warning("field 'physical.Iw' (each driven wheel)", p["Iw"], p["m_w"], p["r"],
                          "add J_r N^2 to Iw, with the rotor inertia J_r and gear ratio N")
    if rotor:
        warnings.append(rotor)
    return report(where, warnings)


# ---------------------------------------------------------------------------------------
# Bodies-and-wheels files
# ---------------------------------------------------------------------------------------
def _spread(points: Sequence[tuple[float, float]]) -> float:
    """The largest distance between two of ``points`` (0 for fewer than two)."""
    return max((math.dist(a, b) for i, a in enumerate(points) for b in points[i + 1:]),
               default=0.0)


def audit_description(
    where: str, desc: RobotDescription, rotors: Mapping[str, Rotor] | None = None,
    findings: Sequence[str] = (),
) -> tuple[str, ...]:
    """Audit a description with numeric fields (as read from a file); raise on an error,
    return ``findings`` (an importer's, carried in the file) and the warnings, all logged.

    ``rotors``: the driven wheels' motors the file gives (their J_r N² is already in the
    wheels' spin inertia).
    """
    rotors = rotors or {}
    warnings: list[str] = []
    index = {w.name: i for i, w in enumerate(desc.wheels)}
    bodies = {b.name: i for i, b in enumerate(desc.bodies)}

    def num(x: object) -> float:
        return float(x)  # type: ignore[arg-type]  # numbers here: read from a file

    for i, w in enumerate(desc.wheels):  # the radius first: the plainest sign of a unit
        _radius(where, f"wheel[{i}].radius", num(w.radius), warnings)
    for i, w in enumerate(desc.wheels):
        for axis, v in zip("xy", w.position, strict=True):
            _length(where, f"wheel[{i}].position.{axis}", num(v))
    for i, b in enumerate(desc.bodies):
        for axis, v in zip("xy", b.com, strict=True):
            _length(where, f"body[{i}].com.{axis}", num(v))
    for i, j in enumerate(desc.joints):
        for key in ("parent_point", "child_point"):
            for axis, v in zip("xy", getattr(j, key), strict=True):
                _length(where, f"joint[{i}].{key}.{axis}", num(v))

    # Over-constrained layouts, before anything else is judged.
    for b in desc.bodies:
        on_body = [w for w in desc.wheels if w.body == b.name]
        axles: list[float] = []
        for w in sorted(on_body, key=lambda w: num(w.position[0])):
            x = num(w.position[0])
            if not axles or x - axles[-1] > AXLE_TOLERANCE:
                axles.append(x)
        if len(axles) > 1:
            names = ", ".join(f"'{w.name}' (x = {_g(num(w.position[0]))} m)" for w in on_body)
            raise refuse(where, (
                f"body '{b.name}' (body[{bodies[b.name]}]) has fixed wheels on {len(axles)} "
                f"axles ({names}): a skid-steer or other over-constrained layout is not "
                "supported: under pure rolling, the only contact model this toolchain "
                "derives, the no-side-slip constraints of parallel axles at different x "
                "positions force the body's yaw rate to zero (the robot could not turn), and "
                "turning needs wheel slip and tyre forces, which are not modelled; keep the "
                "fixed wheels of a body on one axle and make the others casters (bodies on "
                "revolute joints)"))
    for i, j in enumerate(desc.joints):
        on_child = [w for w in desc.wheels if w.body == j.child]
        cx, cy = (num(v) for v in j.child_point)
        if on_child and all(math.dist((num(w.position[0]), num(w.position[1])), (cx, cy))
                            < AXLE_TOLERANCE for w in on_child):
            raise refuse(where, (
                f"joint[{i}] (child '{j.child}'): the wheels of '{j.child}' sit on its hitch "
                f"point {j.child_point} (a caster without trail): rolling does not then "
                "determine its swivel angle, and the model has no S(q); give the wheel its "
                "trail offset behind the swivel axis"))

    # Sizes, masses, density.
    origin: dict[str, tuple[float, float]] = {desc.bodies[0].name: (0.0, 0.0)}
    pending = list(desc.joints)
    while pending:  # bodies placed at zero angles (validate() made the joints a tree)
        ready = [j for j in pending if j.parent in origin]
        if not ready:
            break
        for j in ready:
            px, py = origin[j.parent]
            origin[j.child] = (px + num(j.parent_point[0]) - num(j.child_point[0]),
                               py + num(j.parent_point[1]) - num(j.child_point[1]))
            pending.remove(j)
    centres = [(origin.get(w.body, (0.0, 0.0))[0] + num(w.position[0]),
                origin.get(w.body, (0.0, 0.0))[1] + num(w.position[1])) for w in desc.wheels]
    largest_wheel = max((2 * num(w.radius) for w in desc.wheels), default=0.0)
    size = max(_spread(centres), largest_wheel)
    total = sum(num(b.mass) for b in desc.bodies) + sum(num(w.mass) for w in desc.wheels)
    body_sizes = []
    for b in desc.bodies:
        points = [(num(b.com[0]), num(b.com[1]))]
        points += [(num(w.position[0]), num(w.position[1]))
                   for w in desc.wheels if w.body == b.name]
        points += [(num(j.parent_point[0]), num(j.parent_point[1]))
                   for j in desc.joints if j.parent == b.name]
        points += [(num(j.child_point[0]), num(j.child_point[1]))
                   for j in desc.joints if j.child == b.name]
        body_sizes.append(max(_spread(points), max((2 * num(w.radius) for w in desc.wheels
                                                    if w.body == b.name), default=0.0)))
    if size > 0:
        volume = sum(x**3 for x in body_sizes) if len(desc.bodies) > 1 else None
        _mass_and_size(where, "the total mass (bodies and wheels)", total, size, warnings,
                       volume if volume else None)

    for i, (b, body_size) in enumerate(zip(desc.bodies, body_sizes, strict=True)):
        _yaw_ratio(f"field 'body[{i}].yaw_inertia' (body '{b.name}')", num(b.yaw_inertia),
                   num(b.mass), body_size, warnings, where)
    for w in desc.wheels:
        i = index[w.name]
        rotor = rotors.get(w.name)
        spin = num(w.spin_inertia) - (rotor.reflected if rotor else 0.0)
        _wheel_inertias(f"field 'wheel[{i}].spin_inertia' (wheel '{w.name}')",
                        f"field 'wheel[{i}].diameter_inertia' (wheel '{w.name}')",
                        num(w.mass), num(w.radius), spin, num(w.diameter_inertia), warnings,
                        where, total)
        if w.driven and rotor is None:
            missing = rotor_warning(f"wheel[{i}] (driven wheel '{w.name}')", spin, num(w.mass),
                                    num(w.radius))
            if missing:
                warnings.append(missing)
    return report(where, [*findings, *warnings])
