"""Drishti, the differential-drive wheeled mobile robot of Roy et al. (2017), as one
instance of :mod:`modeling.lagrange` (the paper's robot: C prefix ``wmr``).

Hand-typed physics, and only this: where the bodies sit, the kinetic energy of a planar
rigid body, the rolling constraints at the wheels, and that each motor torque acts on its
wheel angle. Everything else — (1)–(5), (9)–(14), (31), the minimal form and the lumped
relations for m, I and K — is derived.

Frames and assumptions
----------------------
* q = (x_c, y_c, θ, θ_r, θ_l): (x_c, y_c) is the reference point C on the robot's axis of
  symmetry, a distance d ahead of the axle midpoint (so that (6) is the no-side-slip
  condition of the axle); θ is the heading; θ_r, θ_l are wheel angles, positive when the
  wheel rolls forward.
* The wheels (mass m_w, spin inertia I_w, inertia I_m about a vertical diameter) sit on the
  axle at ±b/2 from its midpoint; they roll without slipping on radius r.
* The platform (mass m_P, inertia I_P about its own centre of mass) has its centre of mass
  at (x_P, y_P) in the body frame, measured from the axle midpoint (x forward, y left).
  The paper's relation I = I_P + m_P d² + 2 m_w (b²/4 + d²) + 2 I_m is the case
  x_P = y_P = 0 (platform centre of mass on the axle), for which K = m d.
* A point payload (issue 4) is another body of the same kind.

The lumped kinetic energy is then, exactly,
  T = ½ m (ẋ² + ẏ²) + ½ I θ̇² + K θ̇ (ẋ sin θ − ẏ cos θ) − K_lat θ̇ (ẋ cos θ + ẏ sin θ)
      + ½ I_w (θ̇_r² + θ̇_l²),
with K the first moment of mass behind C and K_lat the first moment to the left of C.
The paper's model has K_lat = 0 (mass symmetric about the robot's axis).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import sympy as sp

from modeling.lagrange import ConstrainedSystem, trig_canonical
from modeling.robot_io import DEFAULT_ROBOT, SHIPPED_NAMING, packaged_source
from modeling.robot_model import PAYLOAD, NominalCondition, Parameter, RobotModel
from modeling.robots.drishti import parameters
from modeling.wheel_constraints import NO_SIDE_SLIP, ROLLING, WheelConstraint

SOURCE = "modeling/robots/drishti/model.py"  # this file, as generated preambles name it

# ---------------------------------------------------------------------------------------
# Symbols
# ---------------------------------------------------------------------------------------
COORDINATE_NAMES = ("x_c", "y_c", "theta", "theta_r", "theta_l")
q = sp.symbols("x_c y_c theta theta_r theta_l", real=True)
qdot = sp.symbols("xdot_c ydot_c thetadot thetadot_r thetadot_l", real=True)
qddot = sp.symbols("xddot_c yddot_c thetaddot thetaddot_r thetaddot_l", real=True)
tau = sp.Matrix(sp.symbols("tau_r tau_l", real=True))

x_c, y_c, theta, theta_r, theta_l = q
xd_c, yd_c, thd, thd_r, thd_l = qdot

# Lumped parameters (the paper's m, I, K, I_w, r, b, d, plus the lateral first moment).
m, I_z, K, K_lat, I_w, r, b, d = sp.symbols("m I K K_lat I_w r b d", real=True)
LUMPED_SYMBOLS: tuple[sp.Symbol, ...] = (m, I_z, K, I_w, r, b, d)
PLANT_SYMBOLS: tuple[sp.Symbol, ...] = (m, I_z, K, K_lat, I_w, r, b, d)
POSITIVE_LUMPED = {m, I_z, I_w, r, b}

# Physical parameters.
m_P, I_P, x_P, y_P, m_w, I_m = sp.symbols("m_P I_P x_P y_P m_w I_m", real=True)
PHYSICAL_SYMBOLS: tuple[sp.Symbol, ...] = (m_P, I_P, x_P, y_P, m_w, I_w, I_m, r, b, d)


@dataclass(frozen=True)
class Body:
    """A planar rigid body fixed to the robot: mass, inertia about its own centre of mass
    (vertical axis) and the centre of mass in the body frame relative to C."""

    name: str
    mass: sp.Expr
    inertia: sp.Expr
    forward: sp.Expr
    lateral: sp.Expr


def heading_vectors() -> tuple[sp.Matrix, sp.Matrix]:
    """e = (cos θ, sin θ) along the robot's axis, n = (−sin θ, cos θ) to its left."""
    return sp.Matrix([sp.cos(theta), sp.sin(theta)]), sp.Matrix([-sp.sin(theta), sp.cos(theta)])


def point_velocity(forward: sp.Expr, lateral: sp.Expr) -> sp.Matrix:
    """World velocity of the body-frame point C + forward·e + lateral·n."""
    e, n = heading_vectors()
    # ė = θ̇ n and ṅ = −θ̇ e for a rotating frame.
    return sp.Matrix([xd_c, yd_c]) + thd * (forward * n - lateral * e)


def physical_bodies() -> tuple[Body, ...]:
    """The platform and the two wheels of the paper, positions relative to C."""
    return (
        Body("platform", m_P, I_P, x_P - d, y_P),
        Body("right wheel", m_w, I_m, -d, -b / 2),
        Body("left wheel", m_w, I_m, -d, b / 2),
    )


def kinetic_energy_of_bodies(bodies: tuple[Body, ...]) -> sp.Expr:
    """T = Σ ½ mᵢ |vᵢ|² + ½ Iᵢ θ̇² over the bodies, plus the wheels' spin ½ I_w (θ̇_r² + θ̇_l²)."""
    t = sp.S.Zero
    for body in bodies:
        v = point_velocity(body.forward, body.lateral)
        half = sp.Rational(1, 2)
        t += half * body.mass * (v.T * v)[0] + half * body.inertia * thd**2
    t += sp.Rational(1, 2) * I_w * (thd_r**2 + thd_l**2)
    return sp.expand(t)


def lumped_kinetic_energy(lateral_moment: bool = False) -> sp.Expr:
    """The kinetic energy in the lumped parameters (see the module docstring)."""
    e_dot = xd_c * sp.sin(theta) - yd_c * sp.cos(theta)
    t = (
        sp.Rational(1, 2) * m * (xd_c**2 + yd_c**2)
        + sp.Rational(1, 2) * I_z * thd**2
        + K * thd * e_dot
        + sp.Rational(1, 2) * I_w * (thd_r**2 + thd_l**2)
    )
    if lateral_moment:
        t -= K_lat * thd * (xd_c * sp.cos(theta) + yd_c * sp.sin(theta))
    return sp.expand(t)


def lumped_relations(bodies: tuple[Body, ...]) -> dict[sp.Symbol, sp.Expr]:
    """m, I, K, K_lat of a set of bodies, read off the Hessian of their kinetic energy.

    m = ∂²T/∂ẋ², I = ∂²T/∂θ̇², and ∂²T/∂ẋ∂θ̇ = K sin θ − K_lat cos θ.
    """
    t = kinetic_energy_of_bodies(bodies)
    mass = sp.diff(t, xd_c, 2)
    inertia = trig_canonical(sp.expand(sp.diff(t, thd, 2)))
    coupling = sp.expand(sp.diff(t, xd_c, thd))
    k_long = coupling.subs(theta, sp.pi / 2)
    k_lat = -coupling.subs(theta, 0)
    return {
        m: sp.factor_terms(sp.expand(mass)),
        I_z: sp.collect(sp.expand(inertia), [m_P, m_w], sp.factor),
        K: sp.collect(sp.expand(k_long), [m_P, m_w]),
        K_lat: sp.expand(k_lat),
    }


def compact_form(expr: sp.Expr) -> sp.Expr:
    """Group an entry of Sᵀ M S as the physics does: I_w + (r²/4) m + (r/b)² (I − 2Kd + md²),
    the last bracket being the yaw inertia about the axle midpoint (evaluation form only)."""
    return sp.collect(sp.expand(expr), [r**2 / b**2, r**2], sp.factor)


# Point payload at (x_L ahead of C, y_L left of C), mass m_L.
m_L, x_L, y_L = PAYLOAD


def payload_relations() -> dict[sp.Symbol, sp.Expr]:
    """m, I, K, K_lat of the robot (lumped m, I, K, K_lat) carrying a point payload.

    Derived like ``lumped_relations``: the Hessian of T_lumped + ½ m_L |v_L|² read off in
    the lumped form, so an off-axis payload (y_L ≠ 0) yields the lateral moment K_lat
    that the controllers' model (K_lat = 0) does not have.
    """
    v = point_velocity(x_L, y_L)
    t = lumped_kinetic_energy(lateral_moment=True) + sp.Rational(1, 2) * m_L * (v.T * v)[0]
    t = sp.expand(t)
    coupling = sp.expand(sp.diff(t, xd_c, thd))
    return {
        m: sp.expand(sp.diff(t, xd_c, 2)),
        I_z: trig_canonical(sp.expand(sp.diff(t, thd, 2))),
        K: coupling.subs(theta, sp.pi / 2),
        K_lat: -coupling.subs(theta, 0),
    }


def constraint_matrix() -> sp.Matrix:
    """A(q) of (9), rows in the paper's sign convention, built from contact velocities.

    Row 1, (6): the axle midpoint (body point (−d, 0)) has no sideways velocity.
    Rows 2–3, (7)–(8) negated as in the paper's A: r θ̇_w − (wheel-centre velocity · e) = 0.
    """
    e, n = heading_vectors()
    axle = point_velocity(-d, sp.S.Zero)
    right = point_velocity(-d, -b / 2)
    left = point_velocity(-d, b / 2)
    rows = [
        (axle.T * n)[0],
        r * thd_r - (right.T * e)[0],
        r * thd_l - (left.T * e)[0],
    ]
    a = sp.Matrix([[sp.expand(sp.diff(row, v)) for v in qdot] for row in rows])
    return a.applyfunc(sp.trigsimp)


# Row 1 is the axle's: the two wheels' no-side-slip rows are one row (same axle, same n).
WHEEL_CONSTRAINTS = (WheelConstraint(NO_SIDE_SLIP, ("right", "left")),
                     WheelConstraint(ROLLING, ("right",)), WheelConstraint(ROLLING, ("left",)))


def input_matrix() -> sp.Matrix:
    """B of (9): τ_r acts on θ_r, τ_l on θ_l."""
    bm = sp.zeros(5, 2)
    bm[3, 0] = 1
    bm[4, 1] = 1
    return bm


@cache
def wmr_system(lateral_moment: bool = False) -> ConstrainedSystem:
    """The WMR as a constrained Lagrangian system in the lumped parameters.

    ``lateral_moment=False`` is the paper's (and the controllers') model; ``True`` adds the
    lateral first moment K_lat that an off-axis payload creates (the plant of issue 4).
    """
    return ConstrainedSystem(
        q=q,
        qdot=qdot,
        qddot=qddot,
        kinetic_energy=lumped_kinetic_energy(lateral_moment),
        constraint_matrix=constraint_matrix(),
        input_matrix=input_matrix(),
        independent=(3, 4),
        wheel_constraints=WHEEL_CONSTRAINTS,
    )


# ---------------------------------------------------------------------------------------
# The robot as the generic layers see it
# ---------------------------------------------------------------------------------------
# The controllers' parameters in the order of the generated structs, and the plant's extra
# one: key, meaning, unit and C spelling come from the table in ``parameters``.
PARAMETERS: tuple[Parameter, ...] = tuple(
    Parameter.of(info, symbol)
    for info, symbol in zip(parameters.LUMPED, LUMPED_SYMBOLS, strict=True)
)
PARAM_KEYS: tuple[str, ...] = tuple(p.key for p in PARAMETERS)
K_LAT_PARAMETER = Parameter.of(parameters.K_LAT, K_lat)


def default_values() -> dict[str, float]:
    """The plant parameters of ``drishti.toml`` (beside this file): its ``[lumped]`` table
    and K_lat = 0 (read through ``parameters``, which needs no model)."""
    source = packaged_source()  # the robot file wmr model reads: one reading, one parse
    where = source.where
    lumped = parameters.tables_of(source.data, where).lumped
    if lumped is None:
        raise ValueError(f"{where}: Drishti's own robot file must give [lumped] parameters")
    return {**lumped, K_LAT_PARAMETER.key: 0.0}


@cache
def robot_model() -> RobotModel:
    """The paper's robot in its lumped parameters: named by the shipped-robot table
    (``modeling.robot_io.SHIPPED_NAMING``: prefix ``wmr``, output at the root of
    ``generated/``, the paper's own robot), the plant with the lateral first moment K_lat
    the controllers lack, the payload ``payload_relations``, and the paper formulation."""
    params = PARAMETERS
    plant = (*params[:3], K_LAT_PARAMETER, *params[3:])
    rel = payload_relations()
    defaults = default_values()
    naming = SHIPPED_NAMING[DEFAULT_ROBOT]
    return RobotModel(
        name=DEFAULT_ROBOT,
        prefix=naming.prefix,
        output_dir=naming.output_dir,
        paper_robot=naming.paper_robot,
        source=SOURCE,
        system=wmr_system(),
        plant_system=wmr_system(lateral_moment=True),
        coordinate_names=COORDINATE_NAMES,
        tau=tau,
        params=params,
        plant_params=plant,
        values=defaults,
        positive=("r", "b"),
        payload=(m_L, x_L, y_L),
        payload_relations={p.symbol: rel.get(p.symbol, p.symbol) for p in plant},
        heading=theta,
        paper=True,
        evaluation_form=compact_form,
        nominal_conditions=(
            NominalCondition(m, "m > 0"),
            NominalCondition(I_z, "I > 0"),
            NominalCondition(I_w, "Iw > 0"),
            NominalCondition(
                m * I_z - K**2,
                "m I - K^2 > 0 (I - K^2/m is the yaw inertia about the centre of mass): a "
                "factor of det M-tilde, so the paper form's M-hat is singular without it",
            ),
        ),
        docs={
            "model_source": f"{SOURCE}, modeling/lagrange.py",
            "report": "modeling.robots.drishti.report",  # MODEL.md with the paper's verdicts
            "plant_params": "true parameters of the simulated robot, including K_lat",
            "payload": "payload mass, position ahead of C, position left of C",
            "plant_state_derivative": (
                "x_dot = (S(q) eta, eta_dot) of the plant: the minimal form derived with the\n"
                "lateral first moment K_lat (an off-axis payload)."
            ),
            "plant_params_with_payload": (
                "Plant parameters (m, I, K, K_lat, Iw, r, b, d) of a robot carrying a point "
                "payload,\nfrom the Hessian of the combined kinetic energy\n"
                "(modeling.robots.drishti.model.payload_relations)."
            ),
        },
    )
