"""Robot descriptions: any wheeled robot as planar rigid bodies, revolute hitches and wheels.

A description lists bodies (the first is the root), revolute joints between them and fixed
standard wheels; ``description_system`` derives from it the kinetic energy, the rolling and
no-side-slip constraints ((6)–(8) of Roy et al. 2017 for the paper's robot) and the input
map, as a ``modeling.lagrange.ConstrainedSystem`` whose generic machinery gives (9)–(14)
and the minimal form. Modules: ``schema`` (dataclasses, validation, symbols), ``files`` (TOML),
``kinematics`` (coordinates, point velocities), ``derive`` (T, A, B, the system),
``elimination`` (exact ranks, block-triangular inverse). The paper's robot written this
way is ``modeling.robots.drishti.description``.

TOML format
-----------
Lengths in m, masses in kg, inertias in kg m², body frames with x forward and y left::

    name = "trailer"                 # optional, defaults to the file's stem

    [[body]]                         # the first body is the root: q starts with the
    name = "tractor"                 # world (x, y) of its frame origin and its yaw θ
    mass = 30.0                      # > 0
    yaw_inertia = 1.5                # ≥ 0, about the body's own centre of mass
    com = [0.05, 0.0]                # centre of mass in the body frame

    [[body]]
    name = "cart"                    # each further body adds its absolute yaw θ_cart
    mass = 15.0
    yaw_inertia = 0.8
    com = [-0.45, 0.0]

    [[joint]]                        # one per non-root body: a tree on the root
    kind = "revolute"                # optional; the only kind
    parent = "tractor"
    child = "cart"
    parent_point = [-0.3, 0.0]       # the hitch in the parent's frame …
    child_point = [0.0, 0.0]         # … and in the child's frame

    [[wheel]]                        # a fixed standard wheel: axle along the body's y
    name = "right"                   # axis; adds its rolling angle θ_right (driven
    body = "tractor"                 # wheels first, in file order, then passive ones)
    position = [0.0, -0.207]         # wheel centre in the body frame
    radius = 0.096                   # > 0
    spin_inertia = 0.07              # ≥ 0, about the axle
    diameter_inertia = 0.035         # ≥ 0, about the vertical axis
    mass = 1.5                       # ≥ 0, at the centre
    driven = true                    # a motor torque acts on this wheel's angle
    rotor_inertia = 1.2e-6           # optional, driven wheels, with gear_ratio: the motor's
    gear_ratio = 30.0                # J_r (kg m²) and N; J_r N² is added to spin_inertia

    [[support]]                      # optional: a caster or skid (frictionless: a normal
    name = "skid"                    # load, no traction) where the robot touches the ground
    body = "cart"                    # besides its wheels (default body: the root), at
    position = [-0.2, 0.0]           # this point of the body's frame; radius optional (m,
    radius = 0.03                    # default half the smallest wheel radius). A file
                                     # with none stands on modeling.supports' default

    [import]                         # optional: written by `wmr import` (the source file and
    source = "robot.urdf"            # the importer's findings, which become warnings)
    findings = []

All fields are required except ``joint.kind``, the motor pair, ``[[support]]`` (format,
default and checks: ``modeling.supports``) and ``[import]``. Names are
unique across bodies and wheels (they name the coordinates). Numbers must be finite.
Errors are ``DescriptionError`` (a ``modeling.robot_io.RobotFileError``, so a
``ValueError``) naming the file and the field,
e.g. ``trailer.toml: field 'wheel[2].radius' must be positive, got 0.0``. A file read
from disk then goes through the physics audit (``modeling.audit``): an implausible one is
refused the same way, and the warnings are the description's ``warnings``.
"""

from modeling.description.derive import (
    DescribedSystem,
    description_input_matrix,
    description_kinetic_energy,
    description_system,
)
from modeling.description.files import (
    load_description,
    packaged_description,
    parse_description,
)
from modeling.description.kinematics import Coordinates, coordinates
from modeling.description.schema import (
    BodySpec,
    DescriptionError,
    JointSpec,
    RobotDescription,
    WheelSpec,
    symbolize,
    validate,
)

__all__ = [
    "BodySpec",
    "Coordinates",
    "DescribedSystem",
    "DescriptionError",
    "JointSpec",
    "RobotDescription",
    "WheelSpec",
    "coordinates",
    "description_input_matrix",
    "description_kinetic_energy",
    "description_system",
    "load_description",
    "packaged_description",
    "parse_description",
    "symbolize",
    "validate",
]
