"""What the code generator needs to know about a robot, whichever robot it is.

A :class:`RobotModel` bundles the controllers' constrained system (9) in run-time
parameter symbols, the simulated plant's system (which may have parameters the
controllers' model lacks), the parameter tables with their default values, how a point
payload on the root body changes the plant parameters, and the naming (C prefix, output
folder). ``codegen`` and the controller laws read only this; they never import a robot.

Instances: the paper's robot from its lumped parameters
(``modeling.robots.drishti.model.robot_model``) and any robot described as bodies, joints
and wheels (``described_model``), whose run-time parameters are its base inertial
parameters (``modeling.base_parameters``) and wheel radii.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import sympy as sp

from modeling import parameter_table
from modeling.base_parameters import reduce_to_base, split_terms
from modeling.lagrange import ConstrainedSystem
from modeling.parameter_table import ParameterInfo
from modeling.physical_map import PhysicalMap, physical_map
from modeling.planar_robot import from_description
from modeling.robot_io import Naming, c_identifier

if TYPE_CHECKING:
    from modeling.description.schema import RobotDescription

# A described robot with at least this many bodies is generated through staged quantities
# (modeling.staged); below, closed forms (measured: see codegen.robot_functions).
STAGED_FROM_BODIES = 2


@dataclass(frozen=True)
class Parameter(ParameterInfo):
    """One run-time parameter: what every layer calls it (key, meaning, unit, C spelling:
    the robot's table of :class:`ParameterInfo`) and the model's ``symbol`` for it."""

    symbol: sp.Symbol = field(kw_only=True)

    @classmethod
    def of(cls, info: ParameterInfo, symbol: sp.Symbol) -> Parameter:
        """The parameter ``info`` declares, as ``symbol`` in the model."""
        return cls(info.key, info.doc, info.unit, info.c_name, info.remark, symbol=symbol)


@dataclass(frozen=True)
class NominalCondition:
    """A condition ``expr > 0`` on the controllers' nominal parameters that the generated
    guards of the minimal form do not already impose (``doc`` says why it is needed)."""

    expr: sp.Expr
    doc: str


def _identity(expr: sp.Expr) -> sp.Expr:
    return expr


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A robot as the generic layers see it (identity-hashed: one object per robot).

    ``system``: the controllers' model; ``plant_system``: the simulated robot's (the same
    object when the controllers' model has every parameter of the plant).
    ``positive``: keys of parameters that must be > 0 for the model to exist (guards).
    ``payload``: (m_L, x_L, y_L), a point mass at (x_L, y_L) in the root body's frame, and
    ``payload_relations`` each plant parameter of the loaded robot in terms of the unloaded
    one's and the payload. ``evaluation_form`` groups an entry of Sᵀ M S for evaluation
    (the paper's robot has a physically grouped form; identity otherwise).
    ``heading``: the root yaw, about which the paper formulation's M̂ is invariant.
    ``paper``: whether the paper formulation (all n coordinates, τ = Bᵀ u) is generated.
    ``nominal_conditions``: what a controller's config check requires of the nominal
    parameters beyond the minimal form's generated guards (finite parameters, the positive
    ones positive, Sᵀ M S positive definite).
    """

    name: str
    prefix: str
    output_dir: str  # relative to generated/; "" for the default robot
    source: str
    system: ConstrainedSystem
    plant_system: ConstrainedSystem
    coordinate_names: tuple[str, ...]
    tau: sp.Matrix
    params: tuple[Parameter, ...]
    plant_params: tuple[Parameter, ...]
    values: dict[str, float]
    positive: tuple[str, ...]
    payload: tuple[sp.Symbol, sp.Symbol, sp.Symbol]
    payload_relations: dict[sp.Symbol, sp.Expr]
    heading: sp.Symbol
    paper: bool
    evaluation_form: Callable[[sp.Expr], sp.Expr] = field(default=_identity)
    nominal_conditions: tuple[NominalCondition, ...] = ()
    # Generated through named intermediate quantities (modeling.staged): products and solves
    # evaluated step by step at the robot's numbers, not multiplied out (a robot of several
    # bodies; the closed forms of a single body are smaller).
    staged: bool = False
    docs: dict[str, str] = field(default_factory=dict)  # doc strings a robot words itself
    # The robot's bodies, hitches and wheels in numbers (modeling.planar_robot.PlanarRobot
    # .to_data()), written into robot.py as LAYOUT for an engine's model of it (None: a
    # [lumped]/[physical] robot, whose layout follows from its parameters).
    layout: dict[str, Any] | None = None
    # The paper's own robot (modeling.robot_io.SHIPPED_NAMING), not merely its model: the
    # generated robot.py declares it (PAPER_ROBOT) for the runtime.
    paper_robot: bool = False
    # A described robot's map from its physical quantities (bodies' masses, inertias,
    # centres of mass, a payload) to its plant parameters (modeling.physical_map); None
    # for a [lumped]/[physical] robot, whose parameters are the lumped ones themselves.
    physical: PhysicalMap | None = None

    @property
    def q(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.system.q)

    @property
    def qdot(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.system.qdot)

    @property
    def nq(self) -> int:
        return len(self.system.q)

    @property
    def nu(self) -> int:
        return int(self.tau.rows)

    @property
    def actuated(self) -> tuple[int, ...]:
        """Index in q of each input's coordinate (the minimal form's coordinates)."""
        return tuple(self.system.independent)

    @property
    def positive_symbols(self) -> frozenset[sp.Symbol]:
        """The symbols of the parameters the generated guards require positive
        (``positive``), of the controllers' model and the plant's."""
        keys = set(self.positive)
        return frozenset(p.symbol for p in (*self.params, *self.plant_params) if p.key in keys)

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(str(t) for t in self.tau)

    @property
    def formulations(self) -> tuple[Literal["paper", "minimal"], ...]:
        return ("paper", "minimal") if self.paper else ("minimal",)

    def param_values(self) -> dict[str, float]:
        """Defaults of the controllers' parameters (keys of ``params``)."""
        return {p.key: self.values[p.key] for p in self.params}

    def c_field_names(self) -> dict[str, str]:
        """Key → C struct field of the controllers' and the plant's parameters, where the
        two spellings differ (the generated Python's ``C_FIELD_NAMES``)."""
        return parameter_table.c_field_names((*self.params, *self.plant_params))


# ---------------------------------------------------------------------------------------
# Robots described as bodies, joints and wheels
# ---------------------------------------------------------------------------------------
PAYLOAD = sp.symbols("m_L x_L y_L", real=True)


def described_model(path: str | Path | RobotDescription, label: str = "",
                    naming: Naming | None = None) -> RobotModel:
    """The model of a robot file with ``[[body]]`` tables (``modeling.description``): of
    the file at ``path``, or of its description already read (``modeling.robot_file``
    reads a file once). ``naming``: its prefix and folder (default: ``c_identifier`` of
    its name, see ``modeling.robot_io.naming_of``).

    Run-time parameters: the base inertial parameters of T (``J_*`` generalised
    inertias, ``K_*`` first moments) and the wheel radii. The plant is the same model (a
    described robot's base parameters already include every first moment), and a payload
    adds a point body on the root: its relations are read off T of the loaded robot in
    the same base parameters. The paper formulation is generated only for a single rigid
    body: with a hitch, M̂ depends on the hitch angle and (25)'s ‖M̂⁻¹‖ is no longer a
    function of the parameters alone (see docs/CONTROLLERS.md). ``label`` names the file
    in generated preambles (default: ``path``).
    """
    from modeling.description import load_description

    if not isinstance(path, str | Path):
        return _described_model(path, label, naming)
    return _described_model(load_description(path), label or Path(path).as_posix(), naming)


@cache
def _described_model(desc: RobotDescription, label: str, naming: Naming | None
                     ) -> RobotModel:
    from modeling.description import description_system
    from modeling.description.canonical import trig_reduce
    from modeling.description.kinematics import body_poses, coordinates, velocity
    from modeling.description.schema import symbolize

    base_system = description_system(desc)
    names = dict(zip(base_system.qdot, base_system.coordinate_names, strict=True))
    variables = [*base_system.q, *base_system.qdot]
    reduction = reduce_to_base(base_system.kinetic_energy, variables, names)
    system = replace(base_system, kinetic_energy=reduction.kinetic_energy)
    physical = dict(base_system.description.values if base_system.description else {})
    beta = reduction.values(physical)

    # Payload: a point mass on the root body, T_loaded = T(β) + ½ m_L |v_L|².
    sym = symbolize(desc)
    coords = coordinates(sym)
    root = sym.bodies[0].name
    m_l, x_l, y_l = PAYLOAD
    v = velocity(body_poses(sym, coords)[root].point((x_l, y_l)), coords)
    loaded = trig_reduce(reduction.kinetic_energy + sp.Rational(1, 2) * m_l * (v.T * v)[0])
    payload_terms = split_terms(loaded - reduction.kinetic_energy, set(variables))
    relations: dict[sp.Symbol, sp.Expr] = {}
    for b in reduction.parameters:
        relations[b.symbol] = b.symbol + b.natural * payload_terms.get(b.monomial, sp.S.Zero)
    if trig_reduce(reduction.kinetic_energy.subs(relations, simultaneous=True) - loaded) != 0:
        raise ValueError(
            f"robot '{desc.name}': a payload on '{root}' changes the kinetic energy in a way "
            "its base parameters cannot carry"
        )

    # The table of a described robot: a base parameter's unit follows from its monomial's
    # coordinates (not stated yet); its meaning is the combination it stands for.
    params = tuple(
        Parameter(str(b.symbol), f"{b.expression} (multiplies {b.monomial} in T)",
                  symbol=b.symbol)
        for b in reduction.parameters
    )
    radii = tuple(
        Parameter(str(s), "wheel radius", "m", symbol=s)
        for s in system.parameters
        if str(s).startswith("radius_")
    )
    table = params + radii
    values = {str(k): v for k, v in beta.items()}
    values.update({str(p.symbol): physical[p.symbol] for p in radii})
    for p in radii:
        relations[p.symbol] = p.symbol
    positive = tuple(p.key for p in radii) + tuple(
        p.key for p in params if p.key.startswith("J_")
    )
    if naming is None:
        naming = Naming(c_identifier(desc.name), c_identifier(desc.name))
    return RobotModel(
        name=desc.name,
        prefix=naming.prefix,
        output_dir=naming.output_dir,
        source=label,
        system=system,
        plant_system=system,
        coordinate_names=base_system.coordinate_names,
        tau=base_system.tau,
        params=table,
        plant_params=table,
        values=values,
        positive=positive,
        payload=PAYLOAD,
        payload_relations=relations,
        heading=base_system.q[2],
        paper=len(desc.bodies) == 1,
        staged=len(desc.bodies) > STAGED_FROM_BODIES - 1,
        layout=from_description(desc).to_data(),
        paper_robot=naming.paper_robot,
        physical=physical_map(sym, reduction.relations(), relations, PAYLOAD,
                              tuple(b.symbol for b in reduction.parameters)),
    )
